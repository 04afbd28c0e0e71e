#!/usr/bin/env bash
# Size benchmark (issue 8), not run by CI:
#  1. a generated three-axis program of VOLMAP_HUGE_MB (default 1024) MB,
#     made on the fly by awk and post-processed from standard input to
#     standard output (no file of that size is stored): time and peak
#     memory (issue target: < 64 MB, i.e. constant memory);
#  2. a table of about 10^7 nodes (hsu-3axis sample, one direction layer,
#     spacing VOLMAP_HUGE_SPACING, default 1.85 mm: 272 x 218 x 164 =
#     9.72 M nodes) built and saved with `volmap map`, then loaded and
#     exported with `volmap export --format csv`: time, peak memory, sizes.
# Usage: bench/huge_inputs.sh [BUILD_DIR]   (default build); results on stdout.
set -euo pipefail
cd "$(dirname "$0")/.."
build=${1:-build}
volmap="$build/volmap"
mb=${VOLMAP_HUGE_MB:-1024}
spacing=${VOLMAP_HUGE_SPACING:-1.85,1.85,1.85}
work=$(mktemp -d "${TMPDIR:-/tmp}/volmap-huge.XXXXXX")
trap 'rm -rf "$work"' EXIT
[ -x "$volmap" ] || { echo "build $volmap first (ninja -C $build volmap)" >&2; exit 2; }
measure() {  # label, command...: prints "label: <s> s, <MB> MB peak"
  local label=$1; shift
  /usr/bin/time -f "%e %M" -o "$work/time" "$@"
  read -r secs kb <"$work/time"
  printf '%-44s %8.1f s %8.1f MB peak\n' "$label:" "$secs" "$(echo "$kb/1024" | bc -l)"
}
echo "machine: $(nproc) cores, $(awk '/MemTotal/{printf "%.0f GB", $2/1048576}' /proc/meminfo), $(uname -m), load $(cut -d' ' -f1 /proc/loadavg)"

# 1. The program: a raster over a 400 x 300 mm pocket at 40 depths, 0.5 mm
#    steps, G1 moves of 2 mm (about 40 bytes a line), repeated until the
#    size is reached.
gen() {
  awk -v bytes=$((mb * 1024 * 1024)) 'BEGIN {
    print "%"; print "(volmap bench: generated raster)"; print "G21 G90 G17 G54"; print "G0 Z5"; print "G0 X-200 Y-150"
    n = 100; pass = 0
    while (n < bytes) {
      z = -0.05 * (pass % 40); line = sprintf("G1 Z%.3f F300", z); print line; n += length(line) + 1
      for (y = -150; y <= 150 && n < bytes; y += 0.5) {
        line = sprintf("G1 Y%.3f F1200", y); print line; n += length(line) + 1
        for (i = 0; i <= 200 && n < bytes; i++) {
          x = ((int((y + 150) / 0.5)) % 2 == 0) ? -200 + 2 * i : 200 - 2 * i
          line = sprintf("G1 X%.4f Y%.4f Z%.4f", x, y + 0.001 * (i % 7), z); print line; n += length(line) + 1
        }
      }
      pass++
    }
    print "G0 Z5"; print "M2"; print "%"
  }'
}
gen | wc -lc | awk '{printf "generated program: %d lines, %.0f MB\n", $1, $2/1048576}'
measure "generate only (awk | wc)" bash -c "$(declare -f gen); mb=$mb; gen | wc -c >/dev/null"
/usr/bin/time -f "%e %M" -o "$work/time_post" \
  "$volmap" post --machine samples/machines/hsu-3axis.json --errors samples/errors/hsu-3axis.csv \
  --work-offset 250,200,100 - -o - < <(gen) | wc -c >"$work/out_bytes"
read -r secs kb <"$work/time_post"
printf '%-44s %8.1f s %8.1f MB peak (volmap process only)\n' "post ${mb} MB program, stdin -> stdout:" "$secs" "$(echo "$kb/1024" | bc -l)"
printf 'post output: %.0f MB\n' "$(echo "$(cat "$work/out_bytes")/1048576" | bc -l)"

# 2. The table: one direction layer (the sample's reverse rows and dir column dropped).
awk -F, 'BEGIN{OFS=","} /^[A-Z],dir,/{d=1; $2=""; sub(",,", ","); print; next}
         /^$/ {d=0} d && $2=="-1" {next} d {$2=""; sub(",,", ","); print; next} {print}' \
  samples/errors/hsu-3axis.csv >"$work/one-layer.csv"
measure "map --spacing $spacing (build + save)" bash -c '"$0" map --machine samples/machines/hsu-3axis.json \
  --errors "$1/one-layer.csv" --spacing "$2" -o "$1/t.vmt" --json >"$1/map.json"' "$volmap" "$work" "$spacing"
python3 - "$work/map.json" <<'PY'
import json, sys
d = json.load(open(sys.argv[1]))
print(f"table: {d['nodes']} nodes x {len(d['layers'])} layer(s), {d['bytes']/2**20:.0f} MB, build {d['build_seconds']:.1f} s, {d['threads']} threads")
PY
measure "export --format csv (load + write)" bash -c '"$0" export --table "$1/t.vmt" --format csv -o "$1/csv" >/dev/null' "$volmap" "$work"
du -sh "$work/t.vmt" "$work/csv" | awk '{print "size: " $2 " " $1}'
