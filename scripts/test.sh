#!/usr/bin/env bash
# The test command: installs what is missing (build and test packages, and the
# Slurm daemons tests/test_slurm runs a one-node cluster with), builds with the
# tests (the runner library as a unity build, as the sanitizer jobs do: its
# files' time is mostly CLI11's inline code, once per file), and runs the
# whole suite with CTest; then the sanitizer jobs
# (scripts/sanitize.sh: asan, whose build also replays the fuzz targets
# under ASan + UBSan, and tsan), each in a build folder of its own
# (BUILD-asan, BUILD-tsan); CELLBAKE_QUICK=1 or CELLBAKE_SANITIZE=0 skips
# them (their measured cost: docs/reliability.md, "What CI runs").
# Idempotent. Exit code 1 when any step failed; the last line names them.
set -euo pipefail
cd "$(dirname "$0")/.."
start=$(date +%s)
bash scripts/install-deps.sh build test slurm
bash scripts/build.sh --no-deps -DCELLBAKE_BUILD_TESTS=ON -DCELLBAKE_BUILD_BENCH=OFF -DCELLBAKE_UNITY_RUNNER=ON
echo "[test] packages and build: $(( $(date +%s) - start )) s"
build_dir="${CELLBAKE_BUILD_DIR:-build}"
failed=()
step() {  # step NAME COMMAND...: runs it, timed; a failure is recorded, not fatal
  local name="$1" start status=0
  shift
  start=$(date +%s)
  echo "[test] ${name}"
  "$@" || status=$?
  echo "[test] ${name}: $([ ${status} = 0 ] && echo ok || echo "FAILED (exit ${status})") in $(( $(date +%s) - start )) s"
  [ ${status} = 0 ] || failed+=("${name}")
}
step "ctest" bash -c "cd '${build_dir}' && ctest --output-on-failure -j '$(nproc)' --timeout 900"
if [ "${CELLBAKE_QUICK:-0}" != 1 ] && [ "${CELLBAKE_SANITIZE:-1}" != 0 ]; then
  # The asan job also replays the fuzz targets (their seeds and fixed
  # pseudo-random mutants) under ASan + UBSan (docs/reliability.md).
  step "sanitize asan" env CELLBAKE_ASAN_DIR="${CELLBAKE_ASAN_DIR:-${build_dir}-asan}" bash scripts/sanitize.sh asan
  step "sanitize tsan" env CELLBAKE_TSAN_DIR="${CELLBAKE_TSAN_DIR:-${build_dir}-tsan}" bash scripts/sanitize.sh tsan
fi
if [ ${#failed[@]} -gt 0 ]; then
  echo "[test] FAILED after $(( $(date +%s) - start )) s: $(IFS=,; echo "${failed[*]}" | sed 's/,/, /g')"
  exit 1
fi
echo "[test] all passed in $(( $(date +%s) - start )) s"
