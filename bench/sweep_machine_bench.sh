#!/usr/bin/env bash
# One command for the sweep's figures on any machine, meant for an NVIDIA GPU node: sets up and
# builds (deploy/setup.sh), then writes to one file
#   - the machine (nvidia-smi, CPU, `manisweep info`: GL renderer and the kernel auto picks);
#   - bench/sweep_kernels_bench: hypotheses/s of the GLSL kernel (the GPU where there is one) and
#     of the CPU kernel on all cores, at 640x480, 1536x1024 and 3072x2048;
#   - fountain-P11 `reconstruct` (../shared/data, its COLMAP sparse model) with the auto kernel
#     at half size (1536x1024) and full size (3072x2048), with 1 worker (all cores) and with 2
#     workers (the cores shared): seconds per iteration;
#   - refinement of the half-size run's final.ply at 1536x1024 (3 iterations, one level) with
#     --refine.kernel auto (GLSL on a GPU) and cpu: seconds per iteration.
#
#   bench/sweep_machine_bench.sh [RESULTS_FILE]      (default bench_results/sweep_HOST_DATE.txt)
# Environment: ITERATIONS (2), WORKERS (worker counts, "1 2"), KERNEL (auto), SKIP_SETUP=1 (use
# build/ as it is), BIN_DIR (run the programs there instead, no setup: e.g. the bin/ of a
# deploy/bundle.sh folder on a node without Debian's packages), DATA (../shared/data).
set -euo pipefail
cd "$(dirname "$0")/.."
root=$(pwd)
results=${1:-bench_results/sweep_$(hostname)_$(date +%Y%m%d_%H%M%S).txt}
mkdir -p "$(dirname "$results")"
results=$(cd "$(dirname "$results")" && pwd)/$(basename "$results")
iterations=${ITERATIONS:-2}
worker_counts=${WORKERS:-1 2}
kernel=${KERNEL:-auto}
data=${DATA:-$root/../shared/data}
if [[ -n ${BIN_DIR:-} ]]; then
  manisweep=$BIN_DIR/manisweep
  bench=$BIN_DIR/sweep_kernels_bench
else
  [[ -n ${SKIP_SETUP:-} ]] || deploy/setup.sh
  manisweep=$root/build/app/manisweep
  bench=$root/build/bench/sweep_kernels_bench
fi
for tool in "$manisweep" "$bench"; do
  [[ -x $tool ]] || { echo "error: $tool not built (run deploy/setup.sh)" >&2; exit 1; }
done

exec > >(tee "$results") 2>&1
echo "# sweep figures, $(date -Is), $(hostname), commit $(git rev-parse --short HEAD 2>/dev/null || echo unknown)"
echo "## machine"
nvidia-smi --query-gpu=name,driver_version,memory.total --format=csv,noheader 2>/dev/null ||
  echo "no nvidia-smi: no NVIDIA GPU"
lscpu | grep -E '^(Model name|CPU\(s\))' || true
"$manisweep" info

echo "## kernels (sweep_kernels_bench, medians of 3 interleaved rounds)"
"$bench" --sizes 640x480,1536x1024,3072x2048 --kernels "glsl,cpu:$(nproc)" --rounds 3

fountain=$data/fountain-P11/sparse
if [[ ! -d $fountain ]]; then
  echo "## fountain-P11: not found at $fountain (set DATA)"
  exit 0
fi
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
for size in 1600 0; do
for workers in $worker_counts; do
  label=$([[ $size == 0 ]] && echo "full size 3072x2048" || echo "half size 1536x1024")
  run=$work/run_${size}_$workers
  echo "## fountain-P11 reconstruct, $label, $iterations iterations, $workers workers, --kernel $kernel"
  "$manisweep" reconstruct --input "$fountain" --output "$run" --workers "$workers" \
    --kernel "$kernel" --max-iterations "$iterations" --sweep.max-image-dimension "$size" --no-refine \
    > "$run.log" 2>&1 || { tail -20 "$run.log"; exit 1; }
  grep -E "joined \(kernel" "$run.log" | head -1 || true
  python3 - "$run/summary.json" <<'PY'
import json, sys
summary = json.load(open(sys.argv[1]))
print("iteration  total_s  sweep_s  kernel_s(sum over jobs)  insert_s  points_found  vertices")
for it in summary["iterations"]:
    if it["iteration"] == 0:
        continue
    print(f'{it["iteration"]:9d}  {it["seconds_total"]:7.2f}  {it["seconds_sweep"]:7.2f}  '
          f'{it["seconds_kernel"]:23.1f}  {it["seconds_insert"]:8.2f}  {it["points_found"]:12d}  '
          f'{it["vertices"]:8d}')
PY
done
done

# Refinement's kernels on the last half-size run's mesh.
last_workers=${worker_counts##* }
mesh=$work/run_1600_$last_workers/final.ply
for refine_kernel in auto cpu; do
  echo "## fountain-P11 refine of that final.ply, 3 iterations at 1536x1024, --refine.kernel $refine_kernel"
  log=$work/refine_$refine_kernel.log
  "$manisweep" refine --input "$fountain" --mesh "$mesh" --output "$work/refined_$refine_kernel.ply" \
    --refine.iterations 3 --refine.levels 1 --refine.kernel "$refine_kernel" > "$log" 2>&1 ||
    { tail -20 "$log"; exit 1; }
  grep -E "gradients by|iteration [0-9]+ \(level|^refined" "$log" || tail -5 "$log"
done
echo "# written to $results"
