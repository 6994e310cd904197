#!/usr/bin/env bash
# deploy/slurm/manisweep.sbatch on a real (throw-away, single-node) Slurm cluster
# (deploy/slurm/local-test-cluster.sh): a job's final mesh equals `manisweep reconstruct`'s, and a
# job cancelled with scancel in the middle of its run and submitted again resumes to the same mesh
# as an uncancelled run. Every daemon it starts is stopped on exit. Exit 77 (a visible ctest
# "skipped") only when Slurm or munge is not installed, or not as root.
#
#   tests/deploy/slurm_test.sh MANISWEEP_BINARY SOURCE_DIR WORK_DIR
set -euo pipefail
manisweep=$1 source=$2 work=$3

skip() { echo "SKIPPED: $*" >&2; exit 77; }
for tool in sbatch scancel squeue slurmctld slurmd munged; do
  command -v "$tool" >/dev/null || skip "$tool is not installed (Debian: slurm-wlm, munge)"
done
[ "$(id -u)" -eq 0 ] || skip "the local Slurm cluster runs its daemons as root"
[ -r /etc/munge/munge.key ] || skip "no /etc/munge/munge.key (the munge package makes it)"

rm -rf "$work"
mkdir -p "$work"
export DIR=$work/cluster
export SLURM_CONF=$DIR/slurm.conf
cleanup() {
  scancel --user=root >/dev/null 2>&1 || true
  sleep 1
  "$source/deploy/slurm/local-test-cluster.sh" stop >/dev/null 2>&1 || true
}
trap cleanup EXIT
"$source/deploy/slurm/local-test-cluster.sh" start >/dev/null
for _ in $(seq 1 30); do
  sinfo -h -o %T 2>/dev/null | grep -q idle && break
  sleep 1
done
sinfo -h -o %T | grep -q idle || { echo "FAIL: the local Slurm node never became idle" >&2; exit 1; }

cd "$work"
"$manisweep" synth pyramid-down --views 8 --width 320 --height 240 --output scene >/dev/null 2>&1
submit() {  # submit OUTPUT ITERATIONS [--wait]
  MANISWEEP=$manisweep sbatch --parsable --nodes=1 --ntasks-per-node=2 --cpus-per-task=1 \
    --output="$work/$1-%j.log" ${3:-} "$source/deploy/slurm/manisweep.sbatch" \
    "$work/scene/scene.h5" "$work/$1" --max-iterations "$2"
}
same_mesh() {  # same_mesh A B WHAT
  if cmp -s "$1" "$2"; then
    echo "ok: $3"
  else
    echo "FAIL: $3: $1 and $2 differ" >&2
    exit 1
  fi
}

# 1. A job to the end equals a local run.
"$manisweep" reconstruct --input scene/scene.h5 --output local2 --max-iterations 2 --workers 2 --no-refine \
  >local2.log 2>&1
submit slurm2 2 --wait >/dev/null || { cat "$work"/slurm2-*.log >&2; echo "FAIL: job 1" >&2; exit 1; }
same_mesh local2/final.ply slurm2/final.ply "a Slurm job gives reconstruct's mesh"
grep -q "CURVE security on" "$work"/slurm2-*.log || { echo "FAIL: the job ran without CURVE" >&2; exit 1; }

# 2. scancel after the first checkpoint, submit again: it resumes to an uncancelled run's mesh.
"$manisweep" reconstruct --input scene/scene.h5 --output local4 --max-iterations 4 --workers 2 --no-refine \
  >local4.log 2>&1
job=$(submit slurm4 4)
for _ in $(seq 1 240); do
  grep -q '"iterations_completed": [1-9]' slurm4/summary.json 2>/dev/null && break
  sleep 0.5
done
scancel "$job"
for _ in $(seq 1 60); do
  squeue -h -j "$job" 2>/dev/null | grep -q . || break
  sleep 0.5
done
completed=$(grep -o '"iterations_completed": [0-9]*' slurm4/summary.json | grep -o '[0-9]*$')
echo "cancelled job $job after $completed iteration(s)"
submit slurm4 4 --wait >/dev/null || { cat "$work"/slurm4-*.log >&2; echo "FAIL: job 3" >&2; exit 1; }
grep -q '"resumed": true' slurm4/summary.json || { echo "FAIL: the second job did not resume" >&2; exit 1; }
same_mesh local4/final.ply slurm4/final.ply "a cancelled and resubmitted job gives the uncancelled mesh"
