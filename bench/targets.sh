#!/usr/bin/env bash
# Issue 13's targets, every figure of docs/performance.md's "Targets" section, in one command:
#   bench/targets.sh [BUILD_DIR]        (default: build; ~6 min on 2 cores; run on a quiet machine)
# 1. end to end: `flexfarm run` of 512 rig variants against MuJoCo's stepping loop (run_vs_mujoco);
# 2. the fraction of the core's FP64 peak in the step loop at N = 6 (midpoint) and N = 48 (SDIRK2):
#    FLOPs per variant-step counted under callgrind (count_flops.py on kernel_bench's BM_FlopCount,
#    the difference of a 2 s and a 1 s run), divided by the time per variant-step (kernel_bench,
#    one core), against fp_peak's measured rate at the same width;
# 3. scaling: 2 threads against 1 (kernel_bench's BM_Sdirk2Threads and `flexfarm run`), 2 MPI ranks
#    against 1 (`mpirun flexfarm run --threads 1`).
set -euo pipefail
cd "$(dirname "$0")/.."
B=${1:-build}
cmake --build "$B" -j2 --target flexfarm kernel_bench fp_peak run_vs_mujoco > /dev/null
echo "== machine: $(nproc) cores, load average $(cut -d' ' -f1-3 /proc/loadavg); $("$B"/flexfarm --version)"

echo "== 1. end to end against MuJoCo"
"$B"/bench/run_vs_mujoco --reps 3 --mujoco-variants 128

echo "== 2. fraction of the FP64 peak"
peak=$("$B"/bench/fp_peak --benchmark_format=csv 2>/dev/null | python3 -c '
import csv, sys
rows = [r for r in csv.DictReader(sys.stdin) if r.get("FLOP/s")]
print(max(float(r["FLOP/s"]) for r in rows))')
echo "peak (fp_peak, widest width, no FMA): $(python3 -c "print(f'{$peak/1e9:.1f} GFLOP/s')")"
count() {  # FLOPs per variant-step of BM_FlopCount's N, integrator (1000 samples x 8 lanes between T = 1 and 2)
  local one two
  one=$(python3 bench/count_flops.py "$B"/bench/kernel_bench --benchmark_filter="BM_FlopCount/N:$1/T:1/sdirk2:$2/" | tail -1)
  two=$(python3 bench/count_flops.py "$B"/bench/kernel_bench --benchmark_filter="BM_FlopCount/N:$1/T:2/sdirk2:$2/" | tail -1)
  python3 -c "print(($two - $one) / 8000)"
}
rate() {  # variant-samples/s of kernel_bench's benchmark $1 on one core
  "$B"/bench/kernel_bench --benchmark_filter="$1" --benchmark_format=csv --benchmark_repetitions=3 \
    --benchmark_report_aggregates_only=true 2>/dev/null | python3 -c '
import csv, sys
for r in csv.DictReader(sys.stdin):
    if r["name"].endswith("_median"): print(r["variant_samples/s"])'
}
isa=$("$B"/flexfarm --version | sed -E 's/.*kernels ([a-z0-9]+) .*/\1/')
code=$(case $isa in avx512) echo 2;; avx2) echo 1;; *) echo 0;; esac)
for c in "6 0 BM_MidpointWidth/N:6/W:8/isa:$code midpoint" "48 1 BM_Sdirk2Width/N:48/W:8/isa:$code SDIRK2"; do
  set -- $c
  f=$(count "$1" "$2")
  r=$(rate "$3")
  python3 -c "f, r, p = $f, $r, $peak; print(f'N = $1, $4 W = 8: {f:.0f} FLOP a variant-step x {r/1e6:.3f} M variant-steps/s = {f*r/1e9:.2f} GFLOP/s = {100*f*r/p:.1f} % of the peak')"
done

echo "== 3. scaling"
"$B"/bench/kernel_bench --benchmark_filter=BM_Sdirk2Threads --benchmark_repetitions=3 \
  --benchmark_report_aggregates_only=true --benchmark_counters_tabular=true 2>/dev/null | grep -E "median|Benchmark"
dir=$(mktemp -d)
trap 'rm -rf "$dir"' EXIT
python3 - "$dir/study.yaml" "$PWD/configs/fbtb.yaml" <<'EOF'
import sys
pay = [328.7 * (0.7 + 0.6 * i / 31) for i in range(32)]
k = [39.5e3 * (0.8 + 0.4 * i / 7) for i in range(8)]
open(sys.argv[1], "w").write(
    "name: scaling\nseed: 1\nmodel: %s\nset:\n  trajectory.moves: [{target: 0.5, hold: 17.0}]\n"
    "  simulation.integrator: sdirk2\nvariables:\n  - path: payload.mass\n    levels: %s\n"
    "  - path: joints.stiffness\n    levels: %s\ndesign: {type: grid}\n" % (sys.argv[2], pay, k))
EOF
wall() {  # median wall seconds of three runs of a command line that writes $dir/out
  for i in 1 2 3; do
    rm -rf "$dir/out"
    /usr/bin/time -f %e -o "$dir/t" bash -c "$1" > /dev/null 2>&1
    cat "$dir/t"
  done | sort -n | sed -n 2p
}
root=""
[ "$(id -u)" = 0 ] && root="--allow-run-as-root"
export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1
mpi="mpirun $root --oversubscribe --mca btl self,vader --mca btl_vader_single_copy_mechanism none"
t1=$(wall "$B/flexfarm run $dir/study.yaml --out $dir/out --threads 1")
t2=$(wall "$B/flexfarm run $dir/study.yaml --out $dir/out --threads 2")
r1=$(wall "$mpi -np 1 $B/flexfarm run $dir/study.yaml --out $dir/out --threads 1")
r2=$(wall "$mpi -np 2 $B/flexfarm run $dir/study.yaml --out $dir/out --threads 1")
python3 -c "print(f'flexfarm run, 256 variants (SDIRK2, N = 6, 20 s): 1 thread {$t1} s, 2 threads {$t2} s: {$t1/$t2:.2f}x; 1 rank {$r1} s, 2 ranks {$r2} s: {$r1/$r2:.2f}x')"
