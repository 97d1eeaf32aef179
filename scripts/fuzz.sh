#!/usr/bin/env bash
# Fuzzing: builds the libFuzzer targets of tests/fuzz with clang
# (-fsanitize=fuzzer,address,undefined) in ${CELLBAKE_FUZZ_DIR:-build-fuzz}
# and runs each for SECONDS (default 60), one after another, from seed corpora
# that fuzz_seeds writes (plus configs/*.toml). Installs clang and the
# project's Debian packages when missing. Exit 1 when any target finds a
# crash, leak, timeout or out-of-memory; the input is kept as
# ${dir}/crashes/TARGET-*, to be fixed and added to the unit tests.
#   scripts/fuzz.sh [SECONDS] [TARGET...]     (targets: fuzz_obj_reader, ...)
#
# `replay` mode (no clang; CI replays the same targets in the asan job of
# scripts/sanitize.sh instead, docs/reliability.md): the same targets built
# with the default compiler, -O1 and ASan + UBSan, each linked with the replay
# driver (tests/fuzz/fuzz_replay.cpp: seeds + RUNS fixed pseudo-random mutants,
# default 10000) in ${CELLBAKE_FUZZ_REPLAY_DIR:-build-fuzz-replay}, run with
# CTest (`fuzz_replay.*`). A finding fails its test; the input is kept as
# ${dir}/tests/fuzz/fuzz-finding-TARGET.
#   scripts/fuzz.sh replay [RUNS]
set -euo pipefail
cd "$(dirname "$0")/.."

if [ "${1:-}" = replay ]; then
  runs="${2:-10000}"
  dir="${CELLBAKE_FUZZ_REPLAY_DIR:-build-fuzz-replay}"
  bash scripts/install-deps.sh
  start=$(date +%s)
  echo "[fuzz] replay: building ${dir} (ASan + UBSan, -O1)"
  cmake -S . -B "${dir}" -G Ninja -DCMAKE_BUILD_TYPE=None -DCMAKE_C_FLAGS="-O1 -g1" -DCMAKE_CXX_FLAGS="-O1 -g1" \
    -DCELLBAKE_FUZZ=ON -DCELLBAKE_FUZZ_ENGINE=replay -DCELLBAKE_FUZZ_REPLAY_RUNS="${runs}" \
    -DCELLBAKE_BUILD_TESTS=OFF -DCELLBAKE_BUILD_BENCH=OFF > "${dir}.configure.log" 2>&1 \
    || { cat "${dir}.configure.log"; exit 1; }
  cmake --build "${dir}" --target fuzz_all -j "$(nproc)"
  built=$(date +%s)
  echo "[fuzz] replay: built in $(( built - start )) s; ${runs} mutants per target"
  # Leaks and third-party reports as scripts/sanitize.sh; one allocation over
  # 2560 MiB is a finding (scripts/fuzz.sh's -rss_limit_mb); full unwinding on
  # malloc only where a suppression needs it (tests/fuzz/CMakeLists.txt).
  export ASAN_OPTIONS="detect_leaks=1:max_allocation_size_mb=2560:${ASAN_OPTIONS:-}"
  export LSAN_OPTIONS="suppressions=${PWD}/tests/sanitizers/lsan.supp:print_suppressions=0:${LSAN_OPTIONS:-}"
  export UBSAN_OPTIONS="suppressions=${PWD}/tests/sanitizers/ubsan.supp:print_stacktrace=1:halt_on_error=1:${UBSAN_OPTIONS:-}"
  status=0
  (cd "${dir}" && ctest --output-on-failure -j "$(nproc)" --timeout 900 -L '^fuzz_replay$') || status=1
  echo "[fuzz] replay: $([ ${status} = 0 ] && echo "no findings" || echo FAILED) (run $(( $(date +%s) - built )) s)"
  exit ${status}
fi

seconds="${1:-60}"
shift || true
dir="${CELLBAKE_FUZZ_DIR:-build-fuzz}"

bash scripts/install-deps.sh
if ! command -v clang++ > /dev/null || ! dpkg-query -W -f='${Status}' libclang-rt-dev 2>/dev/null | grep -q "ok installed"; then
  echo "[fuzz] installing clang"
  SUDO=""
  if [ "$(id -u)" -ne 0 ]; then SUDO="sudo"; fi
  DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -q --no-install-recommends clang libclang-rt-dev
fi

echo "[fuzz] building ${dir} (clang, libFuzzer + ASan + UBSan)"
cmake -S . -B "${dir}" -G Ninja -DCMAKE_BUILD_TYPE=RelWithDebInfo -DCMAKE_C_COMPILER=clang \
  -DCMAKE_CXX_COMPILER=clang++ -DCELLBAKE_FUZZ=ON -DCELLBAKE_FUZZ_ENGINE=libfuzzer -DCELLBAKE_BUILD_TESTS=OFF -DCELLBAKE_BUILD_BENCH=OFF \
  > "${dir}.configure.log" 2>&1 || { cat "${dir}.configure.log"; exit 1; }
cmake --build "${dir}" --target fuzz_all -j "$(nproc)"

targets=("$@")
if [ ${#targets[@]} -eq 0 ]; then
  for t in tests/fuzz/fuzz_*.cpp; do
    name="$(basename "${t}" .cpp)"
    [ "${name}" = fuzz_seeds ] || [ "${name}" = fuzz_replay ] || targets+=("${name}")
  done
fi

corpus="${dir}/corpus"
mkdir -p "${corpus}" "${dir}/crashes"
"${dir}/tests/fuzz/fuzz_seeds" "${corpus}"
mkdir -p "${corpus}/fuzz_bake_config"
cp configs/*.toml "${corpus}/fuzz_bake_config/"

# Leak reports from third-party code (OpenImageIO's PNG error string) are
# suppressed; full unwinding on malloc lets the suppressions see library frames.
export ASAN_OPTIONS="detect_leaks=1:fast_unwind_on_malloc=0:${ASAN_OPTIONS:-}"
export LSAN_OPTIONS="suppressions=${PWD}/tests/sanitizers/lsan.supp:print_suppressions=0:${LSAN_OPTIONS:-}"
export UBSAN_OPTIONS="print_stacktrace=1:halt_on_error=1:${UBSAN_OPTIONS:-}"
failed=()
for t in "${targets[@]}"; do
  mkdir -p "${corpus}/${t}"
  echo "[fuzz] ${t}: ${seconds} s"
  start=$(date +%s)
  if "${dir}/tests/fuzz/${t}" -max_total_time="${seconds}" -timeout=20 -rss_limit_mb=2560 -max_len=65536 \
       -print_final_stats=1 -artifact_prefix="${dir}/crashes/${t}-" "${corpus}/${t}" > "${dir}/${t}.log" 2>&1; then
    echo "[fuzz] ${t}: ok ($(grep -m1 -o 'stat::number_of_executed_units: *[0-9]*' "${dir}/${t}.log" | grep -o '[0-9]*$') runs, $(( $(date +%s) - start )) s)"
  else
    echo "[fuzz] ${t}: FAILED, input kept in ${dir}/crashes/; last lines of ${dir}/${t}.log:"
    tail -40 "${dir}/${t}.log"
    failed+=("${t}")
  fi
done
if [ ${#failed[@]} -gt 0 ]; then
  echo "[fuzz] findings in: ${failed[*]}"
  exit 1
fi
echo "[fuzz] all ${#targets[@]} targets ran ${seconds} s without findings"
