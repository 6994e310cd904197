#!/usr/bin/env bash
# The long chaos run (docs/design/reliability.md): tests/distributed/chaos_test.py for several seeds with
# many kills each, 15 iterations; prints the kills survived per seed and fails on the first run
# whose final mesh differs from the undisturbed one.
#
#   bench/chaos_run.sh [SEEDS (default "11 12 13")] [KILLS per run (default 80)]
set -euo pipefail
cd "$(dirname "$0")/.."
seeds=${1:-11 12 13}
kills=${2:-80}
for seed in $seeds; do
  /usr/bin/python3 tests/distributed/chaos_test.py --manisweep build/app/manisweep \
    --workdir "build/chaos_run/seed$seed" --seed "$seed" --kills "$kills" --iterations 15 \
    --time-limit 600 | tail -2
done
