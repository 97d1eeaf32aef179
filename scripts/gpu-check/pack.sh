#!/usr/bin/env bash
# Prepares issue #12's GPU check for a bare GPU machine that has none of our
# Debian packages and no network (run.sh runs it there): builds cellbake,
# bench_gl_backends and bench_raycast_raw into build-gpu (EGL only, no OSMesa,
# linked --as-needed), packs them with every shared library they load except
# glibc, libstdc++/libgcc and glvnd's GL/EGL into .gpu/cb.tar.xz, and fetches
# Debian's glvnd packages (libEGL and friends, unpacked there over /) into
# .gpu/gl/. .gpu/ is git-ignored; give it to the machine beside the checkout.
#   scripts/gpu-check/pack.sh      (~10 min on 2 cores for a fresh build-gpu)
# OpenImageIO links readers no run there uses (video, OpenCV, HEIF, RAW,
# JPEG 2000, GIF); they travel as stand-ins (stubs.py) without their own
# dependencies, which keeps the pack near 45 MB (the device tool takes 64 MiB).
set -euo pipefail
cd "$(dirname "$0")/../.."
cmake -S . -B build-gpu -G Ninja -DCMAKE_BUILD_TYPE=Release -DCELLBAKE_WITH_OSMESA=OFF -DCELLBAKE_BUILD_BENCH=ON \
  "-DCMAKE_EXE_LINKER_FLAGS=-Wl,--as-needed" > build-gpu.configure.log
ninja -C build-gpu runner/cellbake bench/bench_gl_backends bench/bench_raycast_raw
P=$(mktemp -d)
trap 'rm -rf "$P"' EXIT
mkdir -p "$P/pack/bin" "$P/pack/lib" "$P/pack/extra" "$P/stubs" .gpu/gl
cp build-gpu/runner/cellbake build-gpu/bench/bench_gl_backends build-gpu/bench/bench_raycast_raw "$P/pack/bin/"
strip "$P"/pack/bin/*
python3 scripts/gpu-check/stubs.py "$P/stubs" libavcodec.so.59 libavformat.so.59 libavutil.so.57 libswscale.so.6 \
  libopencv_core.so.406 libopencv_imgproc.so.406 libopencv_videoio.so.406 libheif.so.1 libraw_r.so.20 \
  libopenjp2.so.7 libgif.so.7
for b in "$P"/pack/bin/*; do LD_LIBRARY_PATH="$P/stubs" ldd "$b"; done | awk '/=>/ {print $3}' | sort -u |
  while read -r lib; do
    case "$(basename "$lib")" in
      libc.so* | libm.so* | libpthread.so* | libdl.so* | librt.so* | ld-linux* | libresolv.so*) ;;
      libEGL.so* | libGL.so* | libGLX.so* | libOpenGL.so* | libGLdispatch.so* | libGLESv2.so*) ;;
      libstdc++.so* | libgcc_s.so*) cp -L "$lib" "$P/pack/extra/" ;;  # used only if the machine's are older
      *) cp -L "$lib" "$P/pack/lib/" ;;
    esac
  done
tar -C "$P/pack" -cf - . | xz -T0 -9 > .gpu/cb.tar.xz
gl_debs="libegl1 libglvnd0 libopengl0 libgl1 libglx0 libgles2"
(cd .gpu/gl && rm -f ./*.deb && { apt-get download $gl_debs || { apt-get update && apt-get download $gl_debs; }; } > /dev/null)
du -sh .gpu/cb.tar.xz .gpu/gl
