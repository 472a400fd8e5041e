#!/bin/bash
# Bad input through the fovea command line, as a careless user or script
# gives it. For every case: the documented exit code (2 for what the user
# typed or wrote, 1 for failures while working; never a signal), exactly one
# line on stderr of at most 300 characters naming the problem, and the work
# folder exactly as it was: no output folder or file left behind, every file
# that was there untouched. Then the cases that need a process beside them
# (a sweep holding its folder) and the good inputs that used to fail.
# Each case is tagged with the item of issue 17 it guards ([1] .. [13]), or
# with the issue (22).
# Usage: bad_input_test.sh FOVEA SOURCE_DIR WORK_DIR
set -uo pipefail
fovea=$(readlink -f "$1")
src=$2
work=$3
rm -rf "$work"
mkdir -p "$work/t" "$work/in"
t=$work/t
in=$work/in
failures=0
cases=0
item=""
fail() { echo "FAIL: [$item] $*" >&2; failures=$((failures + 1)); }

# ---- inputs: made afresh before every case, so that cases never depend on
# what an earlier one did ------------------------------------------------------
long=$(head -c 100000 /dev/zero | tr '\0' 'x')
boards=${work}_boards  # chessboard pairs (9x6 inner corners), rendered once
rm -rf "$boards"
"$fovea" chessboards --out "$boards" --views 3 > /dev/null 2>&1 || fail "fovea chessboards failed"
heads=${work}_heads  # a head-calibration set: 3 board placements x 4 stage states
rm -rf "$heads"
"$fovea" chessboards --head --placements 3 --views 4 --square 0.02 --out "$heads" > /dev/null 2>&1 ||
  fail "fovea chessboards --head failed"
cfgs=$src/experiments/configs
hw="run --config $cfgs/emulated-hardware.yaml --set rig.calibration=$cfgs/emulated-hardware-calibration.yaml"
scene() {  # scene NAME BODY: a scene file with the rig and BODY in its world
  printf '<mujoco><include file="tavt.xml"/><worldbody>\n<light directional="true" pos="0 0 3" dir="0 1 -0.6"/>\n%s\n</worldbody></mujoco>\n' "$2" > "$in/$1.xml"
}
make_inputs() {
  rm -rf "$t" "$in"
  mkdir -p "$t" "$in"
  echo "a file that was here before" > "$t/keep.txt"
  mkdir -p "$t/full" "$t/theirs" "$t/empty"
  echo "someone's notes" > "$t/full/notes.txt"
  echo "someone's run" > "$t/theirs/summary.json"
  ln -s "$t/empty" "$t/link"
  echo "an old sheet" > "$t/contact_sheet.png"
  printf 'loop:\n  fixations: 3\nloop:\n  fixations: 4\n' > "$in/dup.yaml"
  printf 'seed: 1\n---\nseed: 2\n' > "$in/two_docs.yaml"
  printf 'axes:\n  seed: [0, 1]\n  seed: [2]\n' > "$in/dup_axes.yaml"
  printf 'axes:\n  seed: {from: 0, to: 10000, step: 1}\n' > "$in/huge.yaml"
  printf 'config: {loop: {fixations: 1}, rig: {width_px: 160, height_px: 120}}\naxes: {seed: [0]}\n' > "$in/one.yaml"
  truncate -s 65M "$in/big.yaml"
  truncate -s 65M "$in/big.xml"
  scene nan_size '<geom name="wall" type="box" size="0.5 nan 0.01" pos="0 1 0"/>'
  scene inf_pos '<geom name="wall" type="box" size="0.5 0.5 0.01" pos="0 inf 0"/>'
  scene huge_pos '<geom name="wall" type="box" size="0.5 0.5 0.01" pos="0 1e999 0"/>'
  scene intruder '<geom name="box" type="box" size="0.05 0.05 0.05" pos="0 0.1 0"/>'
  printf '%%YAML:1.0\n---\nleft: {width_px: 320, height_px: 240, fx_px: 600., fy_px: 600., cx_px: 159.5, cy_px: 119.5}\nright: {width_px: 320, height_px: 240, fx_px: 600., fy_px: 600., cx_px: 159.5, cy_px: 119.5}\n' > "$in/small_calibration.yaml"
  cp -r "$boards" "$in/boards"
  cp -r "$heads" "$in/head"
  # Head sets the head model cannot use: too few views; every carriage
  # reading the same; every tilt reading the same (readings as a rig wrote them).
  head -n 22 "$in/head/views.yaml" > "$in/head/few.yaml"  # 2 header lines, 4 per view
  sed -E 's/state: \[[^,]*, ([^,]*, [^,]*), [^,]*, /state: [-0.1, \1, 0.1, /' \
    "$in/head/views.yaml" > "$in/head/fixed_carriage.yaml"
  sed -E 's/state: \[([^,]*, [^,]*), [^,]*, ([^,]*, [^,]*), [^]]*\]/state: [\1, 0, \2, 0]/' \
    "$in/head/views.yaml" > "$in/head/fixed_tilt.yaml"
  printf '%%YAML:1.0\n---\nversion: 3\nleft: {width_px: 640, height_px: 480, fx_px: 1194., fy_px: 1194., cx_px: 319.5, cy_px: 239.5}\nright: {width_px: 640, height_px: 480, fx_px: 1194., fy_px: 1194., cx_px: 319.5, cy_px: 239.5}\n' > "$in/future_calibration.yaml"
}

snapshot() { (cd "$work" && find t in -printf '%p %y %s\n' | sort && find t -type f -exec md5sum {} + | sort); }
# expect CODE TEXT ARGS...: one bad input, run from inside the target folder.
expect() {
  local code=$1 text=$2
  shift 2
  cases=$((cases + 1))
  make_inputs
  local before
  before=$(snapshot)
  local err
  err=$(cd "$t" && timeout -k 5 300 "$fovea" "$@" 2>&1 >/dev/null)
  local got=$?
  local shown="fovea $*"
  shown=${shown:0:160}
  [ "$got" -eq "$code" ] || fail "$shown: exit $got, expected $code: ${err:0:300}"
  [ "$(printf '%s\n' "$err" | wc -l)" -eq 1 ] && [ -n "$err" ] || fail "$shown: stderr is not one line: ${err:0:600}"
  [ "${#err}" -le 300 ] || fail "$shown: an error line of ${#err} characters"
  case $err in *"$text"*) ;; *) fail "$shown: the error does not say '$text': ${err:0:300}" ;; esac
  local now
  now=$(snapshot)
  [ "$now" = "$before" ] || fail "$shown: the work folder changed: $(diff <(echo "$before") <(echo "$now") | head -5 | tr '\n' ' ')"
}

# [1] existing targets are never destroyed
item=1
expect 2 "exists and is not empty" run --out "$t/full" --fixations 1
expect 2 "is not a folder" run --out "$t/keep.txt" --fixations 1
expect 2 "names an existing folder" run --out . --fixations 1
expect 2 "names an existing folder" run --out .. --fixations 1
expect 2 "was not written by fovea" run --out "$t/theirs" --force --fixations 1
expect 2 "symbolic link" run --out "$t/link" --fixations 1
expect 2 "exists and is not empty" render --out "$t/full"
expect 2 "exists and is not empty" idr --out "$t/full"
expect 2 "exists and is not empty" fixate --point 0 0.9 0 --out "$t/full"
expect 2 "exists and is not empty" textures --out "$t/full"
expect 2 "exists and is not empty" chessboards --out "$t/full"
expect 2 "exists (pass --force" calibrate --left "$in/boards/left_*.png" --right "$in/boards/right_*.png" --board 9x6 --square 0.025 --out "$t/keep.txt"
expect 2 "exists (pass --force" catalog --out "$t"
expect 2 "not a sweep folder" sweep "$in/one.yaml" --out "$t/full"
expect 2 "is not a sweep folder" collect "$t/out" "$in/boards"
# [2] a trailing slash is the same folder: refused before any work
item=2
expect 2 "exists and is not empty" run --out "$t/full/" --fixations 1
# [3] a serial port that is no terminal device
item=3
expect 2 "not a serial device" $hw --set rig.emulate_stages=false --set rig.port=/dev/null --out "$t/out"
expect 2 "not a serial device" $hw --set rig.emulate_stages=false --set rig.port="$t/keep.txt" --out "$t/out"
expect 2 "does not exist" $hw --set rig.emulate_stages=false --set rig.port=/dev/ttyNOPE0 --out "$t/out"
# [4] unbounded or special files
item=4
expect 2 "not a regular file" config --dump --config /dev/zero
expect 2 "not a regular file" run --config /dev/zero --out "$t/out"
expect 2 "not a regular file" sweep /dev/zero --out "$t/out"
expect 2 "not a regular file" render --scene /dev/zero --out "$t/out"
expect 2 "not a regular file" $hw --set rig.calibration=/dev/zero --out "$t/out"
expect 2 "over the limit of 64 MiB" run --config "$in/big.yaml" --out "$t/out"
expect 2 "over the limit of 64 MiB" render --scene "$in/big.xml" --out "$t/out"
# [5] seeds within [0, 2^53]
item=5
expect 2 "--seed (seed): -1 is out of range" run --seed -1 --out "$t/out"
expect 2 "out of range [0, 9007199254740992]" run --seed 9007199254740993 --out "$t/out"
expect 2 "--seed" render --seed -1 --out "$t/out"
expect 2 "expected a whole number" run --seed 1.5 --out "$t/out"
expect 2 "key 'seed': expected a number" run --set seed=abc --out "$t/out"
# [6] --state: exactly six numbers
item=6
expect 2 "exactly 6" render --state 1,2,3,4,5,6,7 --out "$t/out"
expect 2 "exactly 6" render --state 1,2,3,4,5 --out "$t/out"
expect 2 "'nan' is not a number" render --state -0.05,0,0,0.05,0,nan --out "$t/out"
expect 2 "'' is not a number" render --state ,,,,, --out "$t/out"
expect 2 "stage state refused" render --state 1,0,0,0.05,0,0 --out "$t/out"
# [7] --set needs KEY=VALUE (the dump's round trip is a good-input check below)
item=7
expect 2 "--set expects KEY=VALUE" config --dump --set rig.port
# [8] command-line mistakes: exit 2 naming the flag
item=8
expect 2 "--noise (rig.noise_sigma_dn): expected a number" render --noise nan --out "$t/out"
expect 2 "--noise (rig.noise_sigma_dn): expected a number" render --noise inf --out "$t/out"
expect 2 "--noise (rig.noise_sigma_dn): -1 is out of range" render --noise -1 --out "$t/out"
expect 2 "--sigma (idr.log_sigma_px): 0 is out of range [1, 8]" idr --sigma 0 --out "$t/out"
expect 2 "--patch-size (idr.patch_size_px)" idr --patch-size 0 --out "$t/out"
expect 2 "--unique-share (idr.unique_share): 2 is out of range [0.5, 1]" idr --unique-share 2 --out "$t/out"
expect 2 "--initial-baseline" idr --initial-baseline -1 --out "$t/out"
expect 2 "--point: expected a number, got 'nan'" fixate --point nan 0.9 0 --out "$t/out"
expect 2 "--out: the output path is empty" run --out ''
expect 2 "--baseline (foveal.baseline_m)" fixate --point 0 0.9 0 --baseline 0 --out "$t/out"
expect 2 "--matcher (matcher)" fixate --point 0 0.9 0 --matcher census --out "$t/out"
expect 2 "key 'foveal.rectify': expected true or false" fixate --point 0 0.9 0 --set foveal.rectify=2 --out "$t/out"
expect 2 "--set expects KEY=VALUE" fixate --point 0 0.9 0 --set foveal.rectify --out "$t/out"
expect 2 "--fixations (loop.fixations): 0 is out of range" run --fixations 0 --out "$t/out"
expect 2 "--fixations (loop.fixations): expected a whole number" run --fixations 2.5 --out "$t/out"
expect 2 "--point: expected a number" bench fixation --point 1e999 0 0
expect 2 "key 'nl1.cost': 'census' is not one of window_mean, prenormalized, zero_mean_ssd" bench fixation --set nl1.cost=census
expect 2 "--jobs" sweep "$in/one.yaml" --jobs -1 --out "$t/out"
expect 2 "--square" chessboards --square nan --out "$t/out"
expect 2 "--square" calibrate --left "$in/boards/left_*.png" --right "$in/boards/right_*.png" --board 9x6 --square 0 --out "$t/out.yaml"
expect 2 "--board expects WxH" calibrate --left "$in/boards/left_*.png" --right "$in/boards/right_*.png" --board 8 --square 0.025 --out "$t/out.yaml"
expect 2 "--shard expects I/N" sweep "$in/one.yaml" --shard 3/2 --out "$t/out"
expect 2 "key 'matcher'" run --set matcher=census --out "$t/out"
# [9] configs: a folder, repeated keys, several documents
item=9
expect 2 "is a folder" run --config "$t" --out "$t/out"
expect 2 "key 'loop' appears twice" run --config "$in/dup.yaml" --out "$t/out"
expect 2 "more than one YAML document" run --config "$in/two_docs.yaml" --out "$t/out"
expect 2 "key 'seed' appears twice" sweep "$in/dup_axes.yaml" --out "$t/out"
# [10] scenes with non-finite numbers, named
item=10
expect 2 "'wall' has a non-finite number (NaN or infinity) in geom_size" render --scene "$in/nan_size.xml" --out "$t/out"
expect 2 "'wall' has a non-finite number (NaN or infinity) in geom_pos" render --scene "$in/inf_pos.xml" --out "$t/out"
expect 2 "problem reading attribute 'pos'" run --scene "$in/huge_pos.xml" --out "$t/out"
expect 2 "rig's workspace" render --scene "$in/intruder.xml" --out "$t/out"
# [11] long input is cut in messages
item=11
expect 2 "unknown scene 'xxxxxxxx" run --scene "$long" --out "$t/out"
expect 2 "malformed random scene name" render --scene "random$long" --out "$t/out"
expect 2 "unknown key 'xxxxxxxx" run --set "$long=1" --out "$t/out"
expect 2 "expected a number" run --set "rig.noise_sigma_dn=1$long" --out "$t/out"
expect 2 "--out: the output path is too long" run --out "$t/full/$long"
# [12] sweeps: a grid past the limit is refused at once
item=12
expect 2 "more than 10000" sweep "$in/huge.yaml" --out "$t/out"
# [13] the emulator's and the calibration's arguments
item=13
expect 2 "--seconds" indexer-emulator --seconds nan
expect 2 "--units: address 1 appears twice" indexer-emulator --units 1,1 --seconds 1
expect 2 "shows a board of 9x6 inner corners, not the 9x4" calibrate --left "$in/boards/left_*.png" --right "$in/boards/right_*.png" --board 9x4 --square 0.025 --out "$t/out.yaml"
# issue 22: head calibration refuses what cannot determine the head model
item=22
expect 2 "shows a board of 9x6 inner corners, not the 8x6" calibrate-head --views "$in/head/views.yaml" --board 8x6 --square 0.02 --out "$t/out.yaml"
expect 2 "found in only 5 left images (need 8 or more)" calibrate-head --views "$in/head/few.yaml" --board 9x6 --square 0.02 --out "$t/out.yaml"
expect 2 "cannot determine the left pan zero: its carriage readings span 0 m" calibrate-head --views "$in/head/fixed_carriage.yaml" --board 9x6 --square 0.02 --out "$t/out.yaml"
expect 2 "cannot determine the left camera's mount" calibrate-head --views "$in/head/fixed_tilt.yaml" --board 9x6 --square 0.02 --out "$t/out.yaml"
expect 2 "needs a list 'views'" calibrate-head --views "$in/one.yaml" --board 9x6 --square 0.02 --out "$t/out.yaml"
expect 2 "cannot be read: no such file" calibrate-head --views "$in/head/views.yaml" --board 9x6 --square 0.02 --out "$t/out.yaml" --truth "$t/missing_truth.yaml"
expect 2 "version 3 is not one this program reads" run --set rig.calibration="$in/future_calibration.yaml" --fixations 1 --out "$t/out"
expect 2 "--config, --set, --seed and --states go with --head" chessboards --set rig.distortion_k1=-0.2 --out "$t/out"
expect 2 "views file '/nonexistent/views.yaml'" chessboards --head --states /nonexistent/views.yaml --out "$t/out"
# the rest of the class: other user mistakes, and failures at run time (exit 1)
item=class
expect 2 "unknown scene 'no_such_scene'" render --scene no_such_scene --out "$t/out"
expect 2 "N must be 1 to 30" render --scene random:1:99 --out "$t/out"
expect 2 "is not a sweep folder" collect /nonexistent/folder
expect 2 "neither a run folder" report "$t"
expect 2 "is for 320x240 images" $hw --set rig.calibration="$in/small_calibration.yaml" --out "$t/out"
expect 2 "key 'rig.units': address 5 appears twice" $hw --set rig.units=1,2,3,4,5,5 --out "$t/out"
expect 1 "cannot be opened" $hw --set rig.left_camera=/nonexistent/left_%05d.png --out "$t/out"
expect 1 "cannot fixate" fixate --point 3 0.5 0 --out "$t/out"

make_inputs
# ---- a sweep holds its folder: a second one on it is refused (exit 1) --------
item=12
cases=$((cases + 1))
"$fovea" sweep "$in/one.yaml" --out "$work/held" --jobs 1 --no-report 2> "$work/held.log" &
holder=$!
for _ in $(seq 1 100); do [ -f "$work/held/.sweep.lock" ] && break; sleep 0.1; done
err=$("$fovea" sweep "$in/one.yaml" --out "$work/held" --jobs 1 --resume --no-report 2>&1 >/dev/null)
code=$?
[ "$code" -eq 1 ] && [[ $err == *"in use by another fovea sweep"* ]] ||
  fail "a second sweep on a held folder: exit $code: ${err:0:300}"
wait "$holder" || fail "the holding sweep failed: $(tail -2 "$work/held.log")"
expect 2 "exists and is not empty" collect "$t/full" "$work/held"
# fovea compare: two sweep folders, pairs of runs of one method
expect 2 "is not a sweep folder" compare "$t/full" "$work/held"
expect 2 "no static_sgbm runs pair up" compare "$work/held" "$work/held" --method static_sgbm
out=$("$fovea" compare "$work/held" "$work/held" 2>&1)
[[ $out == *"1 pair of fovea runs by scene and seed"* && $out == *"good_coverage"* ]] ||
  fail "compare of a sweep with itself: ${out:0:300}"
# A sweep folder whose grid.json names a run by a path out of its runs/
# folder (edited by hand, or not fovea's): every reader refuses it (exit 1)
# before writing anything, and collect leaves no DIR behind.
rm -rf "$work/tampered" && cp -r "$work/held" "$work/tampered"
sed -i '0,/"id": "[^"]*"/s//"id": "..\/..\/escape"/' "$work/tampered/grid.json"
grep -q '"id": "../../escape"' "$work/tampered/grid.json" || fail "could not tamper with the grid"
expect 1 "is not a sweep grid: runs[0].id" compare "$work/tampered" "$work/held"
expect 1 "is not a sweep grid: runs[0].id" report "$work/tampered"
expect 1 "is not a sweep grid: runs[0].id" collect "$t/merged" "$work/tampered"
[ ! -e "$work/tampered/report.html" ] && [ ! -e "$work/escape" ] || fail "a tampered grid was written from"

# ---- good inputs that used to fail -------------------------------------------
# [2] a trailing slash names the folder
item=2
"$fovea" run --scene two_planes --set rig.width_px=160 --set rig.height_px=120 --fixations 1 --out "$work/slash/" \
  2> "$work/slash.log" && [ -f "$work/slash/summary.json" ] || fail "run --out DIR/ failed: $(tail -1 "$work/slash.log")"
# [1] --force replaces fovea's own folder, keeps everything around it
item=1
"$fovea" run --scene two_planes --set rig.width_px=160 --set rig.height_px=120 --fixations 1 --out "$work/slash" --force \
  2> "$work/force.log" && [ -f "$work/slash/.fovea-output" ] || fail "--force on fovea's folder failed: $(tail -1 "$work/force.log")"
# [12] a run killed part-way leaves a staging folder that the next run to the same target removes
item=12
mkdir -p "$work/.stale.partial-$(hostname | tr -c '[:alnum:]\n' '_')-999999999"
"$fovea" render --scene two_planes --out "$work/stale" 2> /dev/null || fail "render failed"
ls -a "$work" | grep -q '^\.stale\.partial' && fail "a dead process's staging folder was left"
# [7] the dumped configuration reads back the same, whatever its strings hold
item=7
"$fovea" config --dump --set 'rig.port=/dev/tty #1' --set 'rig.left_camera=a: b' --set "rig.right_camera=x\"y'z" \
  --set 'rig.calibration=null' > "$work/dump1.yaml" && "$fovea" config --dump --config "$work/dump1.yaml" > "$work/dump2.yaml" &&
  cmp -s "$work/dump1.yaml" "$work/dump2.yaml" && grep -q 'port: "/dev/tty #1"' "$work/dump1.yaml" ||
  fail "the dumped config does not read back the same"
# [5] the config a run writes reads back (its seed included)
item=5
"$fovea" config --dump --set seed=9007199254740992 > "$work/seed.yaml" && "$fovea" config --dump --config "$work/seed.yaml" > /dev/null ||
  fail "a dumped config with the largest seed is refused"
# [10] a scene with nothing in view: null error figures, not zeros
item=10
scene nothing '<geom name="behind" type="box" size="0.5 0.01 0.5" pos="0 -2 0"/>'
"$fovea" run --scene "$in/nothing.xml" --fixations 1 --out "$work/nothing" 2> /dev/null &&
  grep -q '"median_abs_error_m": null' "$work/nothing/summary.json" && grep -q '"rmse_m": null' "$work/nothing/summary.json" ||
  fail "an empty map's error figures are not null"
# [12] a sweep says its size and a rough time before it starts
item=12
grep -q "1 runs, 0 already done, 1 to run on 1 parallel jobs (roughly" "$work/held.log" || fail "the sweep did not print its size and time first"

if [ "$failures" -gt 0 ]; then
  echo "FAIL: $failures failed checks over $cases bad-input cases and the good-input checks" >&2
  exit 1
fi
echo "PASS: $cases bad inputs: each the documented exit code, one line of at most 300 characters, nothing written or changed; good inputs that used to fail pass"
