#!/bin/bash
# Issue 22's experiment: FOVEA on the imperfect TAVT (experiments/configs/
# imperfect-rig.yaml), believing its design and believing the calibration
# fovea calibrate-head recovers, against the ideal rig: cylinder_planes and
# three_surfaces, seeds 0-2, 25 fixations. Prints the calibration and a table
# of the three rigs' means over the six runs.
# Usage: experiments/scripts/imperfect_rig.sh OUT [FOVEA]   (OUT must not exist)
set -euo pipefail
out=$1
fovea=${2:-build/experiments/fovea}
src=$(cd "$(dirname "$0")/../.." && pwd)
[ -e "$out" ] && { echo "imperfect_rig.sh: '$out' exists; give a new folder" >&2; exit 2; }
mkdir -p "$out"
out=$(cd "$out" && pwd)
imperfect=$src/experiments/configs/imperfect-rig.yaml

"$fovea" chessboards --head --config "$imperfect" --placements 8 --views 12 --square 0.02 \
  --out "$out/boards"
"$fovea" calibrate-head --views "$out/boards/views.yaml" --board 9x6 --square 0.02 \
  --out "$out/calibration.yaml" --truth "$out/boards/truth.yaml"

# One sweep per rig; the imperfect rig's keys copied under config: rig.
rig_keys=$(sed -n '/^rig:/,$p' "$imperfect" | tail -n +2)
sweep() {  # sweep NAME EXTRA_RIG_KEYS
  {
    echo "config:"
    echo "  loop: {fixations: 25}"
    if [ -n "$2" ]; then echo "  rig:"; printf '%s\n' "$2" | sed 's/^/  /'; fi
    echo "axes:"
    echo "  scene: [cylinder_planes, three_surfaces]"
    echo "  seed: [0, 1, 2]"
    echo "jobs: 2"
  } > "$out/$1.yaml"
  "$fovea" sweep "$out/$1.yaml" --out "$out/$1" --no-report > "$out/$1.log"
}
sweep ideal ""
sweep design "$rig_keys"
sweep calibrated "$rig_keys
  calibration: $out/calibration.yaml"

# Means over the six runs of each rig, from each run's summary.json (a run
# that mapped nothing has null errors: counted as missing).
echo
printf '%-11s %-16s %9s %9s %9s %14s %10s %9s %9s %12s\n' rig scene coverage good idr_cov \
  median_err_mm rel_err_% attempts refused servo_steps
for rig in ideal design calibrated; do
  for scene in cylinder_planes three_surfaces all; do
  pattern=$scene
  [ "$scene" = all ] && pattern=.
  summaries=$(grep -l "^  \"scene\": \".*$pattern" "$out/$rig"/runs/*/summary.json)
  # Servo iterations per servoed attempt, from the runs' fixation records
  # (none when a rig mapped nothing: grep finds no servo, which is no error).
  steps=$(for f in $summaries; do cat "${f%summary.json}fixations.jsonl"; done |
    { grep -o '"servo":{[^}]*}' || true; } | { grep -o '"iterations":[0-9]*' || true; } | cut -d: -f2 |
    awk '{ s += $1; n++ } END { if (n) printf "%.2f", s / n; else printf "-" }')
  cat $summaries |
    awk -v rig="$rig" -v scene="$scene" -v steps="$steps" '
    function add(name, v) { if (v != "null") { sum[name] += v; n[name]++ } }
    function value() { v = $2; sub(/,$/, "", v); return v }
    /^  "idr": \{/ { in_idr = 1 }
    in_idr && /^    "coverage":/ { add("idr", value()) }
    /^  \}/ { in_idr = 0 }
    /^  "coverage":/ { add("coverage", value()) }
    /^  "good_coverage":/ { add("good", value()) }
    /^  "median_abs_error_m":/ { v = value(); if (v != "null") v *= 1000; add("med", v) }
    /^  "median_rel_error":/ { v = value(); if (v != "null") v *= 100; add("rel", v) }
    /^  "attempts":/ { add("attempts", value()) }
    /^  "refused":/ { add("refused", value()) }
    function m(name) { return n[name] ? sum[name] / n[name] : -1 }
    END { printf "%-11s %-16s %9.3f %9.3f %9.3f %14.2f %10.3f %9.1f %9.1f %12s\n", rig, scene,
          m("coverage"), m("good"), m("idr"), m("med"), m("rel"), m("attempts"), m("refused"),
          steps }'
  done
done
