#!/usr/bin/env bash
# deploy/bundle.sh makes a folder that runs without Debian's packages:
#   - every library the bundled manisweep loads resolves inside the bundle, glibc apart, and no
#     symbol is left undefined (the GDAL/GDCM stubs export what OpenCV takes from them);
#   - its launcher runs `manisweep info`;
#   - as root, in a root file system holding only glibc and the bundle (chroot, in a private
#     mount namespace), it reconstructs a small synthetic pyramid (made outside, with OpenGL) for
#     one iteration with a worker process and the CPU kernel, reading the PNG images through
#     OpenCV. Without root or namespaces that part says so and is skipped; the rest still runs.
#
#   tests/deploy/bundle_test.sh MANISWEEP_BINARY SOURCE_DIR WORK_DIR
set -euo pipefail
manisweep=$1 source=$2 work=$3
rm -rf "$work"
mkdir -p "$work"
bundle=$work/bundle
"$source/deploy/bundle.sh" "$bundle" "$manisweep" > "$work/bundle.log"
program=$bundle/libexec/$(basename "$manisweep")

glibc='^(libc|libm|libpthread|libdl|librt|libutil|libresolv)\.so|ld-linux|linux-vdso'
outside=$(LD_LIBRARY_PATH=$bundle/lib ldd "$program" |
  awk -v lib="$bundle/lib/" '$2 == "=>" && index($3, lib) != 1 {print $1 " => " $3}' |
  grep -Ev "$glibc" || true)
if [[ -n $outside ]]; then
  echo "FAIL: libraries found outside the bundle:" >&2
  echo "$outside" >&2
  exit 1
fi
undefined=$(LD_LIBRARY_PATH=$bundle/lib ldd -r "$program" 2>&1 | grep -i "undefined symbol" || true)
if [[ -n $undefined ]]; then
  echo "FAIL: undefined symbols:" >&2
  echo "$undefined" >&2
  exit 1
fi
"$bundle/bin/$(basename "$manisweep")" info > "$work/info.log" 2>&1 ||
  { echo "FAIL: the launcher's manisweep info" >&2; cat "$work/info.log" >&2; exit 1; }
grep -q "^  sweep " "$work/info.log" || { echo "FAIL: no sweep line in info" >&2; exit 1; }
echo "bundle complete: $(ls "$bundle/lib" | wc -l) libraries; the launcher runs"

if [[ $(id -u) -ne 0 ]] || ! unshare --mount true 2> /dev/null; then
  echo "SKIPPED (loudly): the run in a bare root file system needs root and mount namespaces"
  exit 0
fi
root=$work/root
mkdir -p "$root/lib64" "$root/usr/bin" "$root/proc" "$root/dev" "$root/tmp" "$root/out"
multiarch=/lib/$(gcc -print-multiarch)
mkdir -p "$root$multiarch"
for lib in libc.so.6 libm.so.6 libpthread.so.0 libdl.so.2 librt.so.1 libresolv.so.2; do
  cp -L "$multiarch/$lib" "$root$multiarch/"
done
cp -L /lib64/ld-linux-x86-64.so.2 "$root/lib64/"
cp /usr/bin/env "$root/usr/bin/"
cp -a "$bundle" "$root/bundle"
"$manisweep" synth pyramid-down --output "$root/scene" --views 4 --width 320 --height 240 \
  > "$work/synth.log" 2>&1 || { echo "FAIL: synth" >&2; tail -5 "$work/synth.log" >&2; exit 1; }
unshare --mount --propagation private bash -c "
  mount --bind /proc '$root/proc' && mount --rbind /dev '$root/dev' &&
  chroot '$root' /usr/bin/env LD_LIBRARY_PATH=/bundle/lib /bundle/libexec/$(basename "$manisweep") \
    reconstruct --input /scene/sparse --output /out/run --workers 1 --kernel cpu \
    --max-iterations 1 --no-refine" \
  > "$work/chroot.log" 2>&1 ||
  { echo "FAIL: reconstruct in the bare root file system" >&2; tail -20 "$work/chroot.log" >&2; exit 1; }
[[ -s $root/out/run/final.ply ]] || { echo "FAIL: no final.ply" >&2; exit 1; }
grep -q "worker worker-1 joined" "$work/chroot.log" || { echo "FAIL: no worker joined" >&2; exit 1; }
echo "reconstruct ran in a root file system holding only glibc and the bundle"
