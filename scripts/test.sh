#!/usr/bin/env bash
# The test command: installs what is missing, builds, and runs the whole suite
# with CTest. Idempotent. Exit code is CTest's.
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/build.sh -DCELLBAKE_BUILD_TESTS=ON -DCELLBAKE_BUILD_BENCH=OFF
build_dir="${CELLBAKE_BUILD_DIR:-build}"
echo "[test] running ctest"
cd "${build_dir}"
ctest --output-on-failure -j "$(nproc)" --timeout 900
