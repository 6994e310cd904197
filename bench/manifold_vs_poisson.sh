#!/usr/bin/env bash
# Manifold reconstruction vs the Poisson baseline on the same points, one run, one table:
#   bench/manifold_vs_poisson.sh [BUILD_DIR] [sizes...]      default: build 10000 100000 1000000
# Time and peak memory of each; check-mesh (the project's independent checker) on both
# outputs: exact topology only here (--no-self-intersections; --allow-float-issues, which the
# Poisson meshes would fail as well), the comparison being about manifoldness. Numbers go to docs/design/performance.md.
set -euo pipefail
BUILD=${1:-build}; shift || true
SIZES=${*:-10000 100000 1000000}
OUT=$(mktemp -d /tmp/manisweep_bench.XXXXXX)
MS="$BUILD/app/manisweep"
printf "%-9s | %-34s | %-52s\n" points "manifold: s, peak MB, check-mesh" "poisson (open3d, depth 10): s, peak MB, check-mesh"
for n in $SIZES; do
  /usr/bin/time -f "%e %M" -o "$OUT/time_m" "$BUILD/bench/manifold_bench" "$n" --insert=0 \
    --export="$OUT" > "$OUT/manifold_$n.txt"
  read -r m_s m_kb < "$OUT/time_m"
  m_check=$("$MS" check-mesh "$OUT/blob_${n}_manifold.ply" --no-self-intersections --allow-float-issues --log-level warn \
    >/dev/null 2>&1 && echo "closed manifold" || echo "NOT manifold (exit $?)")
  /usr/bin/time -f "%e %M" -o "$OUT/time_p" /usr/bin/python3 "$(dirname "$0")/poisson_baseline.py" \
    "$OUT/blob_${n}_points.ply" "$OUT/blob_${n}_poisson.ply" > "$OUT/poisson_$n.json"
  read -r p_s p_kb < "$OUT/time_p"
  p_check=$("$MS" check-mesh "$OUT/blob_${n}_poisson.ply" --no-self-intersections --allow-float-issues --log-level warn \
    > "$OUT/poisson_check_$n.txt" 2>&1 && echo "closed manifold" || echo "NOT manifold (exit $?)")
  printf "%-9s | %6.1f s %8.0f MB  %-16s | %6.1f s %8.0f MB  %s\n" "$n" "$m_s" "$((m_kb / 1024))" \
    "$m_check" "$p_s" "$((p_kb / 1024))" "$p_check"
  cat "$OUT/manifold_$n.txt" | sed 's/^/    /'
  sed 's/^/    poisson: /' "$OUT/poisson_$n.json"
  grep -iE "boundary|non-manifold|self" "$OUT/poisson_check_$n.txt" | head -5 | sed 's/^/    poisson check: /' || true
done
echo "outputs in $OUT"
