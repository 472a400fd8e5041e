#!/bin/bash
# Runs one libFuzzer target for a bounded time from its seed corpus (read
# only; new inputs go to WORK_DIR/corpus) and fails if it finds a crash, a
# leak, undefined behaviour, a timeout or memory past the limit; the input
# that did it is kept in WORK_DIR.
# Usage: run_fuzz.sh TARGET SEED_CORPUS WORK_DIR SECONDS
set -euo pipefail
target=$1
seeds=$2
work=$3
seconds=$4
rm -rf "$work"
mkdir -p "$work/corpus"
cd "$work"
"$target" -max_total_time="$seconds" -timeout=20 -rss_limit_mb=4096 -max_len=4096 -print_final_stats=1 \
  -artifact_prefix="$work/" "$work/corpus" "$seeds" 2> "$work/fuzz.log" || {
  tail -40 "$work/fuzz.log" >&2
  echo "FAIL: $(basename "$target") found a problem; the input is in $work" >&2
  exit 1
}
grep -E "stat::number_of_executed_units|stat::peak_rss_mb" "$work/fuzz.log" || true
echo "PASS: $(basename "$target") ran ${seconds} s and found nothing"
