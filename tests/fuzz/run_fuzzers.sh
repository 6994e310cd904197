#!/usr/bin/env bash
# Builds the scene-format and protocol fuzz targets with clang (ASan + UBSan + libFuzzer) into build-fuzz/
# and runs each for SECONDS (default 60), seeded from tests/data and tests/corpus. Findings
# (crash-*, leak-*, timeout-*, oom-*) land in build-fuzz/fuzz-out/<target>/; the script exits
# non-zero if any target found something.
#
#   tests/fuzz/run_fuzzers.sh                 all targets, 60 s each
#   SECONDS_PER_TARGET=600 tests/fuzz/run_fuzzers.sh fuzz_nvm fuzz_openmvg
set -euo pipefail
cd "$(dirname "$0")/../.."
ROOT=$PWD
BUILD=${BUILD_DIR:-build-fuzz}
SECONDS_PER_TARGET=${SECONDS_PER_TARGET:-60}
TARGETS=("$@")
[ ${#TARGETS[@]} -eq 0 ] && TARGETS=(fuzz_colmap_text fuzz_colmap_binary fuzz_nvm fuzz_bundler
  fuzz_openmvg fuzz_strecha fuzz_middlebury fuzz_image_header fuzz_protocol_coordinator
  fuzz_protocol_worker)

cmake -S . -B "$BUILD" -G Ninja -DCMAKE_BUILD_TYPE=RelWithDebInfo -DCMAKE_C_COMPILER=clang \
  -DCMAKE_CXX_COMPILER=clang++ -DMANISWEEP_FUZZ=ON -DMANISWEEP_BUILD_BENCH=OFF >/dev/null
cmake --build "$BUILD" -j "$(nproc)" --target "${TARGETS[@]}"

# Seeds: the valid fixtures, and the malformed corpus, in each target's input layout.
SEEDS=$BUILD/fuzz-seeds
rm -rf "$SEEDS"
D=$ROOT/tests/data C=$ROOT/tests/corpus
seed() { mkdir -p "$SEEDS/$1"; cat > "$SEEDS/$1/$2"; }
cat_if() { if [ -f "$1" ]; then cat "$1"; fi; }
for kind in text bin; do
  ext=$([ $kind = text ] && echo txt || echo bin)
  target=fuzz_colmap_$([ $kind = text ] && echo text || echo binary)
  m=$D/colmap/$kind
  { printf '\3'; cat "$m/cameras.$ext"; printf '@@@'; cat "$m/images.$ext"; printf '@@@'; cat "$m/points3D.$ext"; } | seed $target all
  i=0
  for f in cameras images points3D; do { printf "\\$i"; cat "$m/$f.$ext"; } | seed $target $f; i=$((i + 1)); done
  corpus=$C/colmap-$([ $kind = text ] && echo text || echo binary)
  for case in "$corpus"/*/; do
    n=$(basename "$case")
    { printf '\3'; cat_if "$case/cameras.$ext"; printf '@@@'; cat_if "$case/images.$ext"
      printf '@@@'; cat_if "$case/points3D.$ext"; } | seed $target "corpus_$n"
  done
done
for f in "$D"/nvm/*.nvm "$C"/nvm/*.nvm; do { printf '\0'; cat "$f"; } | seed fuzz_nvm "$(basename "$f")"; done
{ cat "$D/bundler/colmap.bundle.out"; printf '@@@'; cat "$D/bundler/colmap.list.txt"; } | seed fuzz_bundler fixture
for c in "$C"/bundler/*/; do cat "$c/bundle.out" | seed fuzz_bundler "$(basename "$c")"; done
for f in "$D"/openmvg/*.json "$C"/openmvg/*.json; do
  [ "$(basename "$f")" = deep_nesting.json ] && continue
  seed fuzz_openmvg "$(basename "$f")" < "$f"
done
for f in "$D"/strecha/*.camera "$C"/strecha/*/*.camera; do seed fuzz_strecha "$(echo "$f" | tr / _)" < "$f"; done
for f in "$D"/middlebury/*_par.txt "$C"/middlebury/*_par.txt; do seed fuzz_middlebury "$(basename "$f")" < "$f"; done
for f in "$D"/images/* "$C"/image/*; do seed fuzz_image_header "$(basename "$f")" < "$f"; done
# A real JPEG header for the image target.
[ -f "$ROOT/../shared/data/fountain-P11/images/0000.jpg" ] &&
  head -c 4096 "$ROOT/../shared/data/fountain-P11/images/0000.jpg" | seed fuzz_image_header fountain.jpg

# The protocol targets write their own seeds: valid frames (a job, a result, a heartbeat).
for t in fuzz_protocol_coordinator fuzz_protocol_worker; do
  if [ -x "$BUILD/tests/fuzz/$t" ]; then
    MS_WRITE_SEEDS="$SEEDS/$t" "$BUILD/tests/fuzz/$t" -runs=0 >/dev/null 2>&1 || true
  fi
done

# UBSan only reports by default; make its findings stop the run like ASan's.
export UBSAN_OPTIONS=${UBSAN_OPTIONS:-halt_on_error=1:print_stacktrace=1}
status=0
for t in "${TARGETS[@]}"; do
  out=$BUILD/fuzz-out/$t
  mkdir -p "$out/corpus"
  echo "== $t: ${SECONDS_PER_TARGET} s"
  if ! "$BUILD/tests/fuzz/$t" "$out/corpus" "$SEEDS/$t" -max_total_time="$SECONDS_PER_TARGET" \
      -timeout=10 -rss_limit_mb=2048 -max_len=65536 -artifact_prefix="$out/" -print_final_stats=1 \
      > "$out/log.txt" 2>&1; then
    echo "   FOUND SOMETHING: see $out/log.txt and $out/crash-* / leak-* / timeout-* / oom-*"
    status=1
  fi
  grep -E "^stat::number_of_executed_units|^stat::peak_rss_mb|cov:" "$out/log.txt" | tail -3 | sed 's/^/   /'
done
exit $status
