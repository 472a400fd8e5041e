#!/bin/bash
# A sweep on a real Slurm: starts a single-node cluster on this machine (its
# own munge key, socket, slurm.conf, ports and spool, all under WORK_DIR;
# nothing of the system's is touched), submits experiments/slurm/sweep.sbatch
# as a job array over the sweep, merges the shards with fovea collect and
# compares the CSV with the unsharded sweep's in every column but the
# wall-clock times. The daemons are stopped on every exit; each wait is
# bounded.
# Usage: slurm_test.sh FOVEA SWEEP_FILE SBATCH_SCRIPT WORK_DIR
# Needs Debian's slurm-wlm and munge (quickstart.sh test installs them).
set -euo pipefail
fovea=$1
sweep=$2
sbatch_script=$3
work=$4
tasks=2
fail() {
  echo "FAIL: $*" >&2
  for log in "$work"/slurmctld.log "$work"/slurmd.log "$work"/munged.log "$work"/jobs/*.log; do
    [ -f "$log" ] && { echo "--- $log (last lines)" >&2; tail -n 15 "$log" >&2; }
  done
  exit 1
}
for tool in munged mungekey slurmctld slurmd sbatch sinfo squeue; do
  command -v "$tool" > /dev/null || fail "$tool is not installed (apt-get install slurm-wlm munge)"
done
source "$(dirname "$0")/csv_strip.sh"
fovea=$(realpath "$fovea")
sweep=$(realpath "$sweep")
sbatch_script=$(realpath "$sbatch_script")
rm -rf "$work"
mkdir -p "$work"/{munge,state,spool,jobs}
work=$(realpath "$work")
chmod 700 "$work/munge"

pids=()
cleanup() {
  for pid in "${pids[@]}"; do kill "$pid" 2>/dev/null || true; done
  for pid in "${pids[@]}"; do
    for _ in $(seq 1 50); do kill -0 "$pid" 2>/dev/null || break; sleep 0.1; done
    kill -9 "$pid" 2>/dev/null || true
  done
}
trap cleanup EXIT

# Two free TCP ports on the loopback (none listening there).
free_port() {
  local p
  for _ in $(seq 1 100); do
    p=$((20000 + RANDOM % 20000))
    (echo > "/dev/tcp/127.0.0.1/$p") 2>/dev/null || { echo "$p"; return; }
  done
  fail "no free port found"
}
ctld_port=$(free_port)
slurmd_port=$(free_port)
[ "$ctld_port" != "$slurmd_port" ] || slurmd_port=$((ctld_port + 1))

echo "== munge"
mungekey --create --keyfile "$work/munge/munge.key"
munged --foreground --force --socket="$work/munge/munge.socket" --key-file="$work/munge/munge.key" \
  --log-file="$work/munged.log" --pid-file="$work/munge/munged.pid" \
  --seed-file="$work/munge/munged.seed" > "$work/munged.out" 2>&1 &
pids+=($!)
for _ in $(seq 1 100); do [ -S "$work/munge/munge.socket" ] && break; sleep 0.1; done
[ -S "$work/munge/munge.socket" ] || fail "munged did not start: $(cat "$work/munged.out")"

echo "== slurm.conf, slurmctld and slurmd"
host=$(hostname -s)
user=$(id -un)
cpus=$(nproc)
cat > "$work/slurm.conf" <<EOF
ClusterName=fovea-test
SlurmctldHost=$host(127.0.0.1)
SlurmUser=$user
SlurmdUser=$user
SlurmctldPort=$ctld_port
SlurmdPort=$slurmd_port
AuthType=auth/munge
AuthInfo=socket=$work/munge/munge.socket
CredType=cred/munge
StateSaveLocation=$work/state
SlurmdSpoolDir=$work/spool
SlurmctldPidFile=$work/slurmctld.pid
SlurmdPidFile=$work/slurmd.pid
SlurmctldLogFile=$work/slurmctld.log
SlurmdLogFile=$work/slurmd.log
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
JobAcctGatherType=jobacct_gather/none
AccountingStorageType=accounting_storage/none
SchedulerType=sched/builtin
SelectType=select/cons_tres
SelectTypeParameters=CR_CPU
MpiDefault=none
ReturnToService=2
NodeName=fovea-node NodeAddr=127.0.0.1 NodeHostname=$host CPUs=$cpus State=UNKNOWN
PartitionName=fovea-test Nodes=fovea-node Default=YES MaxTime=INFINITE State=UP
EOF
export SLURM_CONF=$work/slurm.conf
slurmctld -D -i -f "$SLURM_CONF" > "$work/slurmctld.out" 2>&1 &
pids+=($!)
slurmd -D -f "$SLURM_CONF" -N fovea-node > "$work/slurmd.out" 2>&1 &
pids+=($!)
state=""
for _ in $(seq 1 120); do
  state=$(timeout 5 sinfo -h -N -n fovea-node -o %T 2>/dev/null || true)
  [ "$state" = "idle" ] && break
  sleep 0.5
done
[ "$state" = "idle" ] || fail "the node did not come up idle within 60 s (state '$state')"

echo "== the sweep as a job array of $tasks tasks"
export FOVEA=$fovea
# One core per task, so that the array runs on any machine with two cores.
if ! timeout 900 sbatch --wait --array=1-$tasks --cpus-per-task=1 --chdir="$work" \
  --output="$work/jobs/fovea-sweep-%A_%a.log" "$sbatch_script" "$sweep" "$work/sharded" \
  > "$work/sbatch.out" 2>&1; then
  fail "the job array failed or did not finish in 15 minutes: $(cat "$work/sbatch.out")"
fi
job=$(grep -o 'Submitted batch job [0-9]*' "$work/sbatch.out" | grep -o '[0-9]*$') ||
  fail "sbatch did not say which job it submitted: $(cat "$work/sbatch.out")"
for i in $(seq 1 $tasks); do
  [ -f "$work/jobs/fovea-sweep-${job}_$i.log" ] || fail "array task $i left no log"
  [ -d "$work/sharded/shard-$i" ] || fail "array task $i wrote no shard"
done
"$fovea" collect "$work/sharded" "$work"/sharded/shard-* 2> "$work/collect.log" ||
  fail "fovea collect failed: $(cat "$work/collect.log")"

echo "== the same sweep unsharded"
"$fovea" sweep "$sweep" --out "$work/full" --jobs 2 --no-report 2> "$work/full.log"
strip "$work/full/results.csv" > "$work/full.csv"
strip "$work/sharded/results.csv" > "$work/sharded.csv"
rows=$(($(wc -l < "$work/full.csv") - 1))
[ "$rows" -gt 0 ] || fail "the unsharded sweep has no rows"
cmp "$work/full.csv" "$work/sharded.csv" ||
  fail "the Slurm array's collected CSV differs from the unsharded sweep's"
echo "PASS: Slurm job $job, $tasks array tasks on a single-node cluster; $rows runs collected, CSV equal to the unsharded sweep's without wall-clock columns"
