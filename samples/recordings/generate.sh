#!/usr/bin/env bash
# Regenerates the explain sample recordings with `volmap simulate`.
# Usage: samples/recordings/generate.sh [path/to/volmap]   (default: build/volmap)
# Each <name>.csv is made from <name>.plan.json and the truth <name>.effects.json
# (none for the null recordings) on the machine and geometry listed below.
set -euo pipefail
here="$(cd "$(dirname "$0")" && pwd)"
root="$(cd "$here/../.." && pwd)"
volmap="${1:-$root/build/volmap}"
cd "$root"
m3=samples/machines/hsu-3axis.json
m5=samples/machines/lei-hsu-xyzac.json
sim() {  # name machine errors [effects]
  local name=$1 machine=$2 errors=$3 fx=()
  [ -f "samples/recordings/$name.effects.json" ] && fx=(--effects "samples/recordings/$name.effects.json")
  "$volmap" simulate --machine "$machine" --errors "$errors" "${fx[@]}" \
    --plan "samples/recordings/$name.plan.json" -o "samples/recordings/$name.csv"
}
g3=samples/recordings/geometry-3axis.csv
g5=samples/recordings/geometry-5axis.csv
# fitted rigid-body baseline (explain without --baseline): geometry without reversal
sim reversal            $m3 $g3
sim cyclic              $m3 $g3
sim setup-shift         $m3 $g3
sim null                $m3 $g3
sim null-5axis          $m5 $g5
sim drift-one-direction $m3 $g3
sim reversal-one-feed   $m3 $g3
# fixed baseline (explain --baseline samples/errors/...): concealed under the full sample errors
sim thermal-drift       $m3 samples/errors/hsu-3axis.csv
sim servo-lag           $m3 samples/errors/hsu-3axis.csv
sim thermal-temperature $m3 samples/errors/hsu-3axis.csv
sim sag                 $m3 samples/errors/hsu-3axis.csv
sim rotary-wobble       $m5 samples/errors/lei-hsu-xyzac.csv
sim rotary-positioning  $m5 samples/errors/lei-hsu-xyzac.csv
sim ballbar             $m3 samples/errors/hsu-3axis.csv
