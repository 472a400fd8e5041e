#!/bin/bash
# The hardware rig end to end without hardware: record a short run's frames
# in the simulator, then run the same config on a HardwareRig whose stages
# are the indexer emulator (through LibSerial on a pseudo-terminal) and whose
# cameras replay the recording. Run from the source tree.
# Usage: hardware_emulated_test.sh FOVEA WORK_DIR
set -euo pipefail
fovea=$1
work=$2
rm -rf "$work"
mkdir -p "$work"
fail() { echo "FAIL: $*" >&2; exit 1; }
"$fovea" run --config experiments/configs/record-for-emulation.yaml --set rig.record_dir="$work/rec" --out "$work/sim"
frames=$(ls "$work/rec" | grep -c '^left_')
[ "$frames" -gt 3 ] || fail "only $frames frames recorded"
"$fovea" run --config experiments/configs/emulated-hardware.yaml --set rig.left_camera="$work/rec/left_%05d.png" \
  --set rig.right_camera="$work/rec/right_%05d.png" --out "$work/hw"
grep -q '"fixations": 3' "$work/hw/summary.json" || fail "the hardware run did not make 3 fixations"
grep -q 'type: hardware' "$work/hw/config.yaml" || fail "the hardware run's config is not the hardware one"
echo "PASS: $frames stereo frames recorded and replayed through the hardware rig; $(grep '^  "coverage"' "$work/hw/summary.json")"
