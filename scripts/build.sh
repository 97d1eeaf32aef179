#!/usr/bin/env bash
# Configures and builds cellbake into ${CELLBAKE_BUILD_DIR:-build}, after
# installing the build dependencies that are missing (scripts/install-deps.sh:
# nothing when all are present; without root or sudo it prints the apt-get
# line to run). Idempotent; extra arguments go to CMake.
#   scripts/build.sh [--no-deps] [-DCELLBAKE_BUILD_TESTS=ON ...]
# --no-deps: skip the package check (packages installed by other means).
# Tests and benchmarks are built only when asked (-DCELLBAKE_BUILD_TESTS=ON,
# -DCELLBAKE_BUILD_BENCH=ON). Install: cmake --install build --prefix ~/.local
set -euo pipefail
cd "$(dirname "$0")/.."
deps=1
if [ "${1:-}" = --no-deps ]; then deps=0; shift; fi
if [ $deps -eq 1 ]; then bash scripts/install-deps.sh build; fi
build_dir="${CELLBAKE_BUILD_DIR:-build}"
echo "[build] configuring ${build_dir} (Release)"
cmake -S . -B "${build_dir}" -G Ninja -DCMAKE_BUILD_TYPE=Release "$@" > "${build_dir}.configure.log" 2>&1 \
  || { cat "${build_dir}.configure.log"; exit 1; }
echo "[build] compiling with $(nproc) jobs"
cmake --build "${build_dir}" -j "$(nproc)"
echo "[build] done: ${build_dir}/runner/cellbake"
