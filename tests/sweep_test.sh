#!/bin/bash
# A sweep killed part-way (SIGKILL) and restarted with the same command, and
# the same sweep run as two shards merged by fovea collect, both give the CSV
# of an uninterrupted sweep in every column but the wall-clock times.
# Usage: sweep_test.sh FOVEA SWEEP_FILE WORK_DIR ROWS (the sweep's run count)
set -euo pipefail
fovea=$1
sweep=$2
work=$3
rows=$4
rm -rf "$work"
mkdir -p "$work"
fail() { echo "FAIL: $*" >&2; exit 1; }

# strip FILE: the CSV without its wall-clock columns.
source "$(dirname "$0")/csv_strip.sh"
done_runs() { ls "$1"/runs/*/summary.json 2>/dev/null | wc -l; }

echo "== uninterrupted sweep"
"$fovea" sweep "$sweep" --out "$work/full" --jobs 2
[ -f "$work/full/results.csv" ] || fail "no results.csv"
[ -f "$work/full/report.html" ] || fail "no report.html"
total=$(($(wc -l < "$work/full/results.csv") - 1))
[ "$total" -eq "$rows" ] || fail "expected $rows rows, got $total"
grep -q "<svg" "$work/full/report.html" || fail "the sweep report has no plot"
strip "$work/full/results.csv" > "$work/full.csv"
if cmp -s "$work/full/results.csv" "$work/full.csv"; then fail "no wall-clock columns were stripped"; fi

echo "== killed with SIGKILL part-way, then restarted"
"$fovea" sweep "$sweep" --out "$work/killed" --jobs 2 2> "$work/killed.log" &
pid=$!
for _ in $(seq 1 600); do
  [ "$(done_runs "$work/killed")" -ge 4 ] && break
  sleep 0.1
done
kill -9 "$pid"
wait "$pid" 2>/dev/null || true
n=$(done_runs "$work/killed")
echo "killed after $n of $total runs"
[ "$n" -ge 4 ] && [ "$n" -lt "$total" ] || fail "the sweep was not killed part-way ($n of $total runs done)"
[ ! -f "$work/killed/results.csv" ] || fail "a killed sweep wrote results.csv"
sleep 1
# (no pgrep on a minimal system: look through /proc)
for f in /proc/[0-9]*/cmdline; do
  c=$(tr '\0' ' ' < "$f" 2>/dev/null) || continue
  case $c in *"$work/killed/configs"*) fail "a run outlived the killed sweep: $c" ;; esac
done
# Without --resume the folder is refused (it holds the sweep already),
# exit 2, and nothing in it changes.
before=$(find "$work/killed" -type f | sort | xargs md5sum)
set +e
"$fovea" sweep "$sweep" --out "$work/killed" --jobs 2 2> "$work/refused.log"
code=$?
set -e
[ "$code" -eq 2 ] || fail "a sweep into a folder holding it without --resume exited $code, not 2"
grep -q "pass --resume" "$work/refused.log" || fail "the refusal does not say --resume: $(cat "$work/refused.log")"
[ "$before" = "$(find "$work/killed" -type f | sort | xargs md5sum)" ] || fail "the refused sweep changed the folder"
"$fovea" sweep "$sweep" --out "$work/killed" --jobs 2 --resume 2> "$work/restart.log"
grep -q "$n already done" "$work/restart.log" || fail "the restart did not skip the $n finished runs: $(head -1 "$work/restart.log")"
ls -a "$work/killed/runs" | grep -q partial && fail "staging folders left behind"
strip "$work/killed/results.csv" > "$work/killed.csv"
cmp "$work/full.csv" "$work/killed.csv" || fail "the restarted sweep's CSV differs from the uninterrupted one's"

echo "== two shards and fovea collect"
"$fovea" sweep "$sweep" --out "$work/shard1" --jobs 2 --shard 1/2 --no-report
"$fovea" sweep "$sweep" --out "$work/shard2" --jobs 2 --shard 2/2 --no-report
[ ! -f "$work/shard1/results.csv" ] || fail "a shard wrote the whole sweep's CSV"
"$fovea" collect "$work/merged" "$work/shard1" "$work/shard2"
strip "$work/merged/results.csv" > "$work/merged.csv"
cmp "$work/full.csv" "$work/merged.csv" || fail "shards + collect differ from the unsharded sweep"

echo "== run report"
run=$(ls "$work/full/runs" | head -1)
"$fovea" report "$work/full/runs/$run"
grep -q "data:image/png;base64" "$work/full/runs/$run/report.html" || fail "the run report embeds no picture"
echo "PASS: $total runs; killed at $n and resumed; shards merged; CSVs equal without wall-clock columns"
