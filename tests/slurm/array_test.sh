#!/usr/bin/env bash
# A one-node Slurm cluster on this machine (munged, slurmctld and slurmd as root, all their files in a
# temporary directory): the docs' array script, scripts/slurm/array.sbatch, runs slurm_small.yaml as 4
# array tasks, scripts/slurm/merge.sbatch merges them after the array, and the merged results.csv
# must be byte-identical to a one-process `flexfarm run`; then the docs' nightly job,
# scripts/nightly/nightly.sbatch, submitted with `sbatch --begin` on two nights, the model changed
# between them: the first job completes, the second fails with exit code 1 (a regression) and leaves
# its diff.md and report.html. Usage: array_test.sh FLEXFARM_BINARY.
# Exits 77 (ctest: skipped) without root or Slurm, unless FLEXFARM_REQUIRE_SLURM=1 (.ci/slurm).
set -euo pipefail
flexfarm=$(realpath "${1:?usage: $0 FLEXFARM_BINARY}")
root=$(cd "$(dirname "$0")/../.." && pwd)
study=$root/tests/data/studies/slurm_small.yaml
PATH=$PATH:/usr/sbin:/sbin
# An enclosing Slurm job's variables would steer sbatch (SBATCH_*) or describe the wrong job.
unset $(compgen -e | grep -E '^(SBATCH|SLURM)_' || true)

# Skip (or fail, where Slurm is required) without root or the daemons and commands.
for cmd in munged mungekey slurmctld slurmd sbatch squeue sinfo scontrol scancel; do
  if [[ $(id -u) -ne 0 ]] || ! command -v "$cmd" >/dev/null; then
    echo "slurm test: needs root, slurm-wlm and munge (apt-get install slurm-wlm munge)"
    [[ ${FLEXFARM_REQUIRE_SLURM:-0} == 1 ]] && exit 1 || exit 77
  fi
done

tmp=$(mktemp -d /tmp/flexfarm-slurm.XXXXXX)
mkdir "$tmp/munge" "$tmp/state" "$tmp/spool"
chmod 755 "$tmp" "$tmp/munge"  # munged wants its socket's directories searchable by all
pids=()
# Teardown, on success and failure alike: cancel any job, stop the daemons and the reference run,
# show the logs if the test failed, remove the directory.
cleanup() {
  local rc=$?
  cd /
  if [[ ${#pids[@]} -gt 1 && -n $(timeout 5 squeue -h 2>/dev/null) ]]; then
    timeout 5 scancel --full --user=root || true
    for ((i = 0; i < 25; i++)); do [[ -z $(timeout 5 squeue -h 2>/dev/null) ]] && break; sleep 0.2; done
  fi
  [[ ${#pids[@]} -gt 0 ]] && kill "${pids[@]}" ${reference:-} 2>/dev/null || true
  for ((i = 0; i < 50; i++)); do [[ -z $(jobs -rp) ]] && break; sleep 0.1; done
  [[ -z $(jobs -rp) ]] || kill -9 $(jobs -rp) 2>/dev/null || true  # a daemon stuck in its shutdown
  wait 2>/dev/null || true
  if [[ $rc -ne 0 ]]; then
    for f in "$tmp"/*.log; do echo "== $f"; tail -n 40 "$f"; done
  fi
  rm -rf "$tmp"
  exit "$rc"
}
trap cleanup EXIT

# MUNGE with a key of its own, listening on a socket in the directory.
mungekey --create --keyfile="$tmp/munge/munge.key"
munged --foreground --socket="$tmp/munge/socket" --key-file="$tmp/munge/munge.key" \
  --pid-file="$tmp/munge/munged.pid" --seed-file="$tmp/munge/seed" --log-file="$tmp/munged.log" 2>/dev/null &
pids+=($!)

# slurm.conf: this host as controller and the one node, no cgroups (linuxproc, no task plugin), no
# accounting; each CPU shared by two jobs (the array's 4 tasks at once on 2 cores).
host=$(hostname -s)
export SLURM_CONF=$tmp/slurm.conf
cat >"$SLURM_CONF" <<EOF
ClusterName=flexfarmtest
SlurmctldHost=$host(127.0.0.1)
SlurmctldPort=16817
SlurmdPort=16818
SlurmUser=root
SlurmdUser=root
AuthType=auth/munge
AuthInfo=socket=$tmp/munge/socket
CredType=cred/munge
StateSaveLocation=$tmp/state
SlurmdSpoolDir=$tmp/spool
SlurmctldPidFile=$tmp/slurmctld.pid
SlurmdPidFile=$tmp/slurmd.pid
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
JobAcctGatherType=jobacct_gather/none
AccountingStorageType=accounting_storage/none
SelectType=select/cons_tres
SelectTypeParameters=CR_CPU
ReturnToService=2
NodeName=$host NodeAddr=127.0.0.1 CPUs=$(nproc) State=UNKNOWN
PartitionName=test Nodes=ALL Default=YES MaxTime=INFINITE State=UP OverSubscribe=FORCE:2
EOF
for ((i = 0; i < 50; i++)); do [[ -S $tmp/munge/socket ]] && break; sleep 0.1; done

# The daemons in the foreground of background jobs (so their ids are ours to stop), and meanwhile
# the one-process reference run.
slurmctld -D -c -f "$SLURM_CONF" >"$tmp/slurmctld.log" 2>&1 &
pids+=($!)
slurmd -D -f "$SLURM_CONF" -N "$host" >"$tmp/slurmd.log" 2>&1 &
pids+=($!)
"$flexfarm" run "$study" --out "$tmp/ref" --threads 2 >"$tmp/reference-run.log" 2>&1 &
reference=$!

# Wait (at most 30 s) for the node to be idle, i.e. registered and ready.
deadline=$((SECONDS + 30))
while ((SECONDS < deadline)); do
  [[ $(timeout 5 sinfo -h -o %t 2>/dev/null) == idle ]] && break
  sleep 0.2
done
[[ $(sinfo -h -o %t) == idle ]] || { echo "slurm test: the node did not come up"; sinfo; exit 1; }

# The array (4 tasks of one core) and the merge after it, as the docs submit them.
export FLEXFARM=$flexfarm FLEXFARM_STUDY=$study FLEXFARM_OUT=$tmp/out
cd "$tmp"
array=$(sbatch --parsable --array=0-3 --cpus-per-task=1 --output="$tmp/array-%a.log" \
  "$root/scripts/slurm/array.sbatch")
merge=$(sbatch --parsable --dependency="afterok:$array" --output="$tmp/merge.log" \
  "$root/scripts/slurm/merge.sbatch")

# Each job in turn (at most a minute): out of the queue, and every one of its tasks completed.
for job in "$array" "$merge"; do
  deadline=$((SECONDS + 60))
  while ((SECONDS < deadline)) && [[ -n $(timeout 5 squeue -h -j "$job" 2>/dev/null) ]]; do sleep 0.2; done
  states=$(scontrol -o show job "$job" | grep -o 'JobState=[A-Z]*' | sort -u)
  [[ $states == JobState=COMPLETED ]] || { echo "slurm test: job $job: $states"; scontrol show job "$job"; exit 1; }
done

# The 4 shards' journals, and the merged table equals the one-process run's byte for byte.
wait "$reference" || { echo "slurm test: the reference run failed"; exit 1; }
ls "$tmp"/out/journal-shard-{0,1,2,3}-of-4.csv >/dev/null
cmp "$tmp/ref/results.csv" "$tmp/out/results.csv"
echo "slurm test: 4 array tasks + merge give the one-process results.csv, byte for byte"

# The nightly job (docs/nightly.md) on two nights: the second with the derivative gain cut by a third.
mkdir -p "$tmp/nightly"
cp "$root/configs/fbtb.yaml" "$tmp/nightly/fbtb.yaml"
cat >"$tmp/nightly/sweep.yaml" <<EOF
name: nightly
model: fbtb.yaml
set: {trajectory.moves: [{target: 0.5, hold: 12.0}], simulation.integrator: sdirk2}
variables:
  - {path: payload.mass, distribution: {type: truncated_normal, mean: 328.7, std: 40.0, lower: 200.0, upper: 460.0}}
design: {type: monte_carlo, samples: 32}
tolerances:
  m1_peak_torque_Nm: {increase: 3%}
EOF
export FLEXFARM_ROOT=$root FLEXFARM_HISTORY=$tmp/history FLEXFARM_NIGHTLY_ONCE=1
for night in 1 2; do
  [[ $night == 2 ]] && sed -i 's/  kd: 3.0e4 /  kd: 2.0e4 /' "$tmp/nightly/fbtb.yaml"
  job=$(FLEXFARM_NIGHT=night$night sbatch --parsable --begin=now --cpus-per-task=2 --output="$tmp/nightly-$night.log" \
    "$root/scripts/nightly/nightly.sbatch" nightly/sweep.yaml nightly/out)
  deadline=$((SECONDS + 120))
  while ((SECONDS < deadline)) && [[ -n $(timeout 5 squeue -h -j "$job" 2>/dev/null) ]]; do sleep 0.2; done
  exit_code=$(scontrol -o show job "$job" | grep -o ' ExitCode=[0-9:]*')
  expected=$([[ $night == 1 ]] && echo " ExitCode=0:0" || echo " ExitCode=1:0")
  [[ $exit_code == "$expected" ]] || { echo "slurm test: nightly job $night:$exit_code, not$expected"; cat "$tmp/nightly-$night.log"; exit 1; }
done
grep -q "| controller.kd | 3.0e4 | 2.0e4 |" "$tmp/nightly/out/night2/diff.md"
grep -q "regressions since the last run" "$tmp/nightly/out/night2/report.html"
echo "slurm test: the nightly sbatch job completes on night 1 and flags the changed model on night 2 (exit 1)"
