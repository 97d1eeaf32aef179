#!/usr/bin/env bash
# Sanitizer jobs (issue #14): builds the parser, codec, storage and runner
# tests with AddressSanitizer + UndefinedBehaviorSanitizer (-O1) in
# ${CELLBAKE_ASAN_DIR:-build-asan}, and the runner and storage tests with
# ThreadSanitizer in ${CELLBAKE_TSAN_DIR:-build-tsan}, then runs them with
# CTest. Known third-party reports are suppressed (tests/sanitizers/*.supp).
# Clang (installed when missing, like scripts/fuzz.sh); any report fails the
# test that triggered it. Exit code: 1 when a job failed.
#   scripts/sanitize.sh [asan] [tsan]        (default: both)
set -euo pipefail
cd "$(dirname "$0")/.."
jobs=("$@")
[ ${#jobs[@]} -gt 0 ] || jobs=(asan tsan)

# What each job builds and runs (ctest -R: whole test executables).
asan_tests=(test_readers test_input_checks test_geometry_store test_encode test_bake_config test_cli_values
            test_output_guards test_cell_db_migration test_ingest test_integrity test_merge test_bake)
tsan_tests=(test_geometry_store test_cell_db_migration test_integrity test_merge test_bake)

bash scripts/install-deps.sh build test
if ! command -v clang++ > /dev/null || ! dpkg-query -W -f='${Status}' libclang-rt-dev 2>/dev/null | grep -q "ok installed"; then
  echo "[sanitize] installing clang"
  SUDO=""
  if [ "$(id -u)" -ne 0 ]; then SUDO="sudo"; fi
  DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -q --no-install-recommends clang libclang-rt-dev
fi

supp="${PWD}/tests/sanitizers"
# Leak stacks unwound in full so suppressions see library frames (lsan.supp).
export ASAN_OPTIONS="detect_leaks=1:fast_unwind_on_malloc=0:strict_string_checks=1:${ASAN_OPTIONS:-}"
export LSAN_OPTIONS="suppressions=${supp}/lsan.supp:print_suppressions=0:${LSAN_OPTIONS:-}"
export UBSAN_OPTIONS="suppressions=${supp}/ubsan.supp:print_stacktrace=1:halt_on_error=1:${UBSAN_OPTIONS:-}"
export TSAN_OPTIONS="suppressions=${supp}/tsan.supp:halt_on_error=1:second_deadlock_stack=1:${TSAN_OPTIONS:-}"

# run_job JOB DIR FLAGS TESTS...: configures DIR with clang and FLAGS, builds the
# cellbake binary (tests run it) and TESTS, runs TESTS with CTest.
run_job() {
  local job="$1" dir="$2" flags="$3"
  shift 3
  local tests=("$@") start
  start=$(date +%s)
  echo "[sanitize] ${job}: building ${dir}"
  cmake -S . -B "${dir}" -G Ninja -DCMAKE_BUILD_TYPE=None -DCMAKE_C_COMPILER=clang -DCMAKE_CXX_COMPILER=clang++ \
    -DCMAKE_C_FLAGS="-O1 -g1 ${flags}" -DCMAKE_CXX_FLAGS="-O1 -g1 ${flags}" \
    -DCMAKE_EXE_LINKER_FLAGS="${flags}" -DCMAKE_SHARED_LINKER_FLAGS="${flags}" \
    -DCELLBAKE_BUILD_TESTS=ON -DCELLBAKE_BUILD_BENCH=OFF -DCELLBAKE_TEST_TIMEOUT=3600 > "${dir}.configure.log" 2>&1 \
    || { cat "${dir}.configure.log"; return 1; }
  # (inside `run_job || ...` set -e is off: every step checks its status)
  cmake --build "${dir}" -j "$(nproc)" --target cellbake "${tests[@]}" || return 1
  echo "[sanitize] ${job}: built in $(( $(date +%s) - start )) s; running ${tests[*]}"
  local labels status=0
  labels="^($(IFS='|'; echo "${tests[*]}"))$"  # tests/CMakeLists.txt labels each test with its executable
  (cd "${dir}" && ctest --output-on-failure -j "$(nproc)" --timeout 3600 -L "${labels}") || status=1
  echo "[sanitize] ${job}: $([ ${status} = 0 ] && echo ok || echo FAILED) in $(( $(date +%s) - start )) s"
  return ${status}
}

failed=()
for job in "${jobs[@]}"; do
  case "${job}" in
    # Mesa's softpipe, not llvmpipe: llvmpipe registers its JIT code's unwind
    # tables, and ASan's full unwinding on malloc (fast_unwind_on_malloc=0,
    # for the leak suppressions) then deadlocks in libgcc's _Unwind_Find_FDE,
    # which mallocs while holding its lock (bakes and verify hung until CTest's timeout).
    asan) (export GALLIUM_DRIVER=softpipe
           run_job asan "${CELLBAKE_ASAN_DIR:-build-asan}" \
             "-fsanitize=address,undefined -fno-sanitize-recover=undefined -fno-omit-frame-pointer" \
             "${asan_tests[@]}") || failed+=(asan) ;;
    tsan) run_job tsan "${CELLBAKE_TSAN_DIR:-build-tsan}" "-fsanitize=thread" "${tsan_tests[@]}" || failed+=(tsan) ;;
    *) echo "[sanitize] unknown job '${job}' (asan, tsan)"; exit 2 ;;
  esac
done
if [ ${#failed[@]} -gt 0 ]; then
  echo "[sanitize] failed: ${failed[*]}"
  exit 1
fi
echo "[sanitize] ${jobs[*]}: no reports"
