#!/usr/bin/env bash
# Packs built manisweep programs with the shared libraries they load into one folder that runs on
# an x86-64 Linux node without Debian's packages: a GPU node that has only NVIDIA's driver, or a
# cluster node whose image nobody may change. glibc is the node's own (it must be as new as the
# build machine's); everything else travels.
#
#   deploy/bundle.sh [OUT_DIR] [PROGRAM...]
#       OUT_DIR   default build/bundle
#       PROGRAM   default build/app/manisweep build/bench/sweep_kernels_bench
#   then on the node:  OUT_DIR/bin/manisweep info
#
# Debian's OpenCV links GDAL and GDCM (DICOM) for image formats manisweep never reads;
# their trees are 120 MB. They are replaced by stubs that define the symbols OpenCV imports from
# them, so the folder stays near 70 MB.
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
out=${1:-$root/build/bundle}
shift || true
programs=("$@")
[[ ${#programs[@]} -gt 0 ]] ||
  programs=("$root/build/app/manisweep" "$root/build/bench/sweep_kernels_bench")
for p in "${programs[@]}"; do
  [[ -x $p ]] || { echo "error: $p is not built (run deploy/setup.sh)" >&2; exit 1; }
done

multiarch=/lib/$(gcc -print-multiarch)
imgcodecs=$multiarch/libopencv_imgcodecs.so.406
unread_formats=(libgdal.so.32 libgdcmMSFF.so.3.0 libgdcmDSED.so.3.0)

rm -rf "$out"
mkdir -p "$out/bin" "$out/libexec" "$out/lib" "$out/stub-src"
cp "${programs[@]}" "$out/libexec/"

# Stubs: each symbol OpenCV takes from an unread format library returns 0. OpenCV registers
# these decoders at its first imread (GDALAllRegister), and a stubbed open returns no file.
imported=$(nm -D --undefined-only "$imgcodecs" | awk '{print $2}' | sort -u)
for lib in "${unread_formats[@]}"; do
  src=$out/stub-src/$lib.S
  echo ".text" > "$src"
  comm -12 <(echo "$imported") \
    <(nm -D --defined-only "$multiarch/$lib" | awk '{sub(/@.*/, "", $3); print $3}' | sort -u) |
    while read -r symbol; do
      printf '.globl %s\n.type %s,@function\n%s:\n  xor %%eax, %%eax\n  ret\n' \
        "$symbol" "$symbol" "$symbol"
    done >> "$src"
  gcc -shared -nostdlib -Wl,-soname,"$lib" -o "$out/lib/$lib" "$src"
done

# Everything else the programs load, except glibc and the loader.
glibc='^(libc|libm|libpthread|libdl|librt|libutil|libresolv|ld-linux-x86-64)\.so'
LD_LIBRARY_PATH=$out/lib ldd "$out"/libexec/* | awk '$2 == "=>" && $3 ~ /^\// {print $1, $3}' |
  sort -u | while read -r name path; do
    [[ $name =~ $glibc || -e $out/lib/$name ]] || cp -L "$path" "$out/lib/$name"
  done

needed_glibc=$(objdump -T "$out"/libexec/* "$out"/lib/* 2>/dev/null | grep -o 'GLIBC_2\.[0-9]*' |
  sort -t. -k2 -n -u | tail -1 | sed 's/GLIBC_//')
# One launcher for every program: the bundle's libraries and NVIDIA's EGL for this process and
# the workers it starts, nothing for the caller's shell.
cat > "$out/launcher" <<LAUNCHER
#!/usr/bin/env bash
bundle=\$(cd "\$(dirname "\$(readlink -f "\${BASH_SOURCE[0]}")")" && pwd)
needed_glibc=$needed_glibc
have_glibc=\$(getconf GNU_LIBC_VERSION | awk '{print \$2}')
if [[ \$(printf '%s\n' "\$needed_glibc" "\$have_glibc" | sort -V | head -1) != "\$needed_glibc" ]]; then
  echo "error: this node's glibc is \$have_glibc; the manisweep bundle needs \$needed_glibc or newer" >&2
  exit 1
fi
export LD_LIBRARY_PATH=\$bundle/lib\${LD_LIBRARY_PATH:+:\$LD_LIBRARY_PATH}
for dir in /usr/local/nvidia/lib64 /usr/local/nvidia/lib; do
  [[ -d \$dir ]] && LD_LIBRARY_PATH+=:\$dir
done
for vendor in /usr/local/nvidia/share/glvnd/egl_vendor.d/10_nvidia.json \\
    /usr/share/glvnd/egl_vendor.d/10_nvidia.json /etc/glvnd/egl_vendor.d/10_nvidia.json; do
  if [[ -f \$vendor ]]; then export __EGL_VENDOR_LIBRARY_FILENAMES=\$vendor; break; fi
done
exec "\$bundle/libexec/\$(basename "\$0")" "\$@"
LAUNCHER
chmod +x "$out/launcher"
for p in "${programs[@]}"; do ln -s ../launcher "$out/bin/$(basename "$p")"; done
echo "bundle: $out ($(du -sh "$out" | cut -f1), $(ls "$out/lib" | wc -l) libraries, glibc >= $needed_glibc)"
