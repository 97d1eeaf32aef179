#!/usr/bin/env bash
# The test command: installs what is missing (build and test packages, and the
# Slurm daemons tests/test_slurm runs a one-node cluster with), builds with the
# tests, and runs the whole suite with CTest, then the fuzz targets' replay
# under ASan + UBSan. Idempotent. Exit code: CTest's, or 1 when only the replay failed.
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/install-deps.sh build test slurm
bash scripts/build.sh --no-deps -DCELLBAKE_BUILD_TESTS=ON -DCELLBAKE_BUILD_BENCH=OFF
build_dir="${CELLBAKE_BUILD_DIR:-build}"
echo "[test] running ctest"
status=0
(cd "${build_dir}" && ctest --output-on-failure -j "$(nproc)" --timeout 900) || status=$?
# The fuzz targets again, built apart with ASan + UBSan (gcc, -O1): their seeds
# and fixed pseudo-random mutants (scripts/fuzz.sh replay, docs/reliability.md).
# CELLBAKE_QUICK=1 skips it.
if [ "${CELLBAKE_QUICK:-0}" != 1 ]; then
  CELLBAKE_FUZZ_REPLAY_DIR="${CELLBAKE_FUZZ_REPLAY_DIR:-${build_dir}-fuzz-replay}" bash scripts/fuzz.sh replay || status=1
fi
exit ${status}
