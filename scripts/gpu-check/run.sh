#!/bin/bash
# Issue #12's GPU check on a bare GPU machine (pack.sh prepares .gpu/), run
# there from the repository root with OUT set to a folder for the results:
# the 12.7 M plant generated there, then bench_gl_backends (sampler on EGL
# against raw GL on the same cells), then one-sample bakes of the demo region
# with egl and embree on 16 threads, a default bake with auto, and raw
# Embree (bench_raycast_raw) on this machine's CPU. With this workplace's
# device tool: command "bash scripts/gpu-check/run.sh 2>&1 | tee $OUT/log.txt",
# carry [".gpu"], timeout 540 s (about 5 minutes of work on an H200 machine).
# TRIANGLES=N picks a smaller plant for a dry run on a CPU machine.
set -u
TRIANGLES=${TRIANGLES:-12700000}
T0=$(date +%s)
say() { echo "[$(( $(date +%s) - T0 )) s] $*"; }
for f in .gpu/gl/*.deb; do dpkg -x "$f" /; done; ldconfig
mkdir -p /tmp/cb && python3 -c "import tarfile; tarfile.open('.gpu/cb.tar.xz').extractall('/tmp/cb')" || exit 2
export LD_LIBRARY_PATH=/tmp/cb/lib
nv=/usr/local/nvidia/share/glvnd/egl_vendor.d/10_nvidia.json
[ -f "$nv" ] && export __EGL_VENDOR_LIBRARY_FILENAMES=$nv
head -2 /etc/os-release; nproc; free -g | head -2
nvidia-smi --query-gpu=name,driver_version,clocks.sm,memory.used --format=csv 2>&1
CB=/tmp/cb/bin/cellbake; BG=/tmp/cb/bin/bench_gl_backends
if ! $CB --version; then
  export LD_LIBRARY_PATH=/tmp/cb/lib:/tmp/cb/extra
  $CB --version || { ldd $CB | grep -i "not found"; exit 3; }
fi
say "EGL probe"
timeout 60 $BG --benchmark_filter='CreateContext/1' 2>&1 | tail -4
say "generate $TRIANGLES triangles"
( time timeout 180 $CB generate plant --triangles $TRIANGLES --seed 1 --out /tmp/p12.ply --store /tmp/p12.store.db ) 2>&1 | tail -8
ls -la /tmp/p12.store.db || exit 4
say "bench"
export CELLBAKE_BENCH_STORE=/tmp/p12.store.db
export CELLBAKE_BENCH_EYES="6,8,1.7;10,8,1.7;14,8,1.7;18,8,1.7;22,8,1.7;26,8,1.7;30,8,1.7;34,8,1.7"
timeout 150 $BG --benchmark_filter='CubeMapStore/1|RawGl' --benchmark_repetitions=5 \
  --benchmark_enable_random_interleaving=true --benchmark_out=$OUT/bench.json --benchmark_out_format=json 2>&1
nvidia-smi --query-gpu=clocks.sm,memory.used --format=csv 2>&1
one="--set samples.initial=centre --set samples.max=1 --threads 16"
for b in egl embree; do
  say "bake one-sample $b"
  ( time timeout 90 $CB bake configs/plant-demo.toml --store /tmp/p12.store.db $one --set sample.backend=$b \
      --out /tmp/one_$b.db -q ) 2>&1 | tail -6
done
say "bake default, auto"
( time timeout 150 $CB bake configs/plant-demo.toml --store /tmp/p12.store.db --threads 16 --out /tmp/auto.db -q ) 2>&1 | tail -6
for d in /tmp/one_egl.db /tmp/one_embree.db /tmp/auto.db; do
  [ -f $d ] && timeout 60 $CB status $d 2>&1 | head -14
done
say "raw Embree on this CPU (BVH build per thread-second; one tracing thread)"
timeout 100 /tmp/cb/bin/bench_raycast_raw 512 3 2>&1
say "end"
