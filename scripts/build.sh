#!/usr/bin/env bash
# Installs missing dependencies, then configures and builds cellbake into
# ${CELLBAKE_BUILD_DIR:-build}. Idempotent; extra arguments go to CMake.
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/install-deps.sh
build_dir="${CELLBAKE_BUILD_DIR:-build}"
echo "[build] configuring ${build_dir} (Release)"
cmake -S . -B "${build_dir}" -G Ninja -DCMAKE_BUILD_TYPE=Release "$@" > "${build_dir}.configure.log" 2>&1 \
  || { cat "${build_dir}.configure.log"; exit 1; }
echo "[build] compiling with $(nproc) jobs"
cmake --build "${build_dir}" -j "$(nproc)"
echo "[build] done: ${build_dir}/runner/cellbake"
