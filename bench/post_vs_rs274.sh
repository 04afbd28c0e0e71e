#!/bin/sh
# volmap post vs LinuxCNC's rs274 -g, side by side on the same N-line
# three-axis programs of bench/nc_programs.sh: issue #5's raster (target:
# volmap post >= 20x faster) and issue #35's circle, where every line changes
# and each word is renumbered in place.
# Usage: bench/post_vs_rs274.sh [N=1000000] [VOLMAP=build/volmap]
# SHAPES="raster circle" (the default) chooses the programs.
# Prints, for each program, user+sys times, the ratio and peak memory (max
# RSS) of both, and the load average (the machine may be shared: compare
# with care).
# BIG=1 also streams a 1 GB raster (38 M lines, generated on the fly, never
# stored) through `volmap post - -o -` and prints its peak memory.
set -eu
N=${1:-1000000}
here=$(cd "$(dirname "$0")/.." && pwd)
VOLMAP=${2:-$here/build/volmap}
dir=$(mktemp -d)
trap 'rm -rf "$dir"' EXIT
gen() { sh "$here/bench/nc_programs.sh" "$@"; }
run() {  # name, command...: prints "user+sys seconds" and "max RSS kB" into $dir/$1.t
  name=$1; shift
  /usr/bin/time -f "%U %S %M" -o "$dir/$name.t" "$@" > /dev/null 2> "$dir/$name.err" || {
    echo "$name failed:"; cat "$dir/$name.err"; exit 1; }
}
for shape in ${SHAPES:-raster circle}; do
  # The raster where its figures have always been taken; the circle in the
  # middle of the travel.
  case $shape in
  raster) offset=150,100,200 ;;
  circle) offset=250,200,100 ;;
  *) echo "unknown shape $shape (raster, circle)"; exit 2 ;;
  esac
  gen "$shape" "$N" > "$dir/$shape.ngc"
  echo "$shape: $N moves, $(wc -c < "$dir/$shape.ngc") bytes; load average: $(cut -d' ' -f1-3 /proc/loadavg)"
  run rs274 rs274 -g "$dir/$shape.ngc" "$dir/rs274.out"
  run volmap "$VOLMAP" post --machine "$here/samples/machines/hsu-3axis.json" \
    --errors "$here/samples/errors/hsu-3axis.csv" --work-offset "$offset" \
    "$dir/$shape.ngc" -o "$dir/post.ngc"
  awk -v n="$N" '
    FNR == 1 && FILENAME ~ /rs274/ { r = $1 + $2; rm = $3 }
    FNR == 1 && FILENAME ~ /volmap/ { v = $1 + $2; vm = $3 }
    END {
      printf "  rs274 -g     : %6.2f s user+sys, %7.0f ns/line, peak %6.1f MB\n", r, r / n * 1e9, rm / 1024
      printf "  volmap post  : %6.2f s user+sys, %7.0f ns/line, peak %6.1f MB\n", v, v / n * 1e9, vm / 1024
      printf "  ratio rs274 / volmap post: %.1fx\n", (v > 0 ? r / v : 0)
    }' "$dir/rs274.t" "$dir/volmap.t"
  echo "  output: $(wc -l < "$dir/post.ngc") lines; $(grep -o '[0-9]* changed' "$dir/volmap.err")"
done
echo "load average: $(cut -d' ' -f1-3 /proc/loadavg)"
if [ "${BIG:-0}" = 1 ]; then
  gen raster 38000000 200 | /usr/bin/time -f "%U %S %M" -o "$dir/big.t" "$VOLMAP" post \
    --machine "$here/samples/machines/hsu-3axis.json" --errors "$here/samples/errors/hsu-3axis.csv" \
    --work-offset 150,100,200 - -o - | wc -c > "$dir/big.bytes"
  [ "$(cat "$dir/big.bytes")" -gt 1000000000 ] || { echo "the 1 GB run failed"; exit 1; }
  awk -v out="$(cat "$dir/big.bytes")" '{ printf "1 GB program (38 M lines, streamed): volmap post %.1f s user+sys, peak %.1f MB, %.2f GB out\n", $1 + $2, $3 / 1024, out / 1e9 }' "$dir/big.t"
fi
