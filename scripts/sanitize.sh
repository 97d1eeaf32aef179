#!/usr/bin/env bash
# Sanitizer jobs (issue #14; scripts/test.sh runs both after the suite,
# CELLBAKE_QUICK=1 skips them; docs/reliability.md says what they cover):
#   asan  AddressSanitizer + UndefinedBehaviorSanitizer (leaks checked, the
#         first report fatal) over the parser, codec, storage and runner tests,
#         then the fuzz targets' replay (tests/fuzz: their seeds and 10 000
#         mutants each of seed 2, other than the suite's seed 1, 2 500 for
#         the targets parsed mostly by uninstrumented libraries: COLLADA,
#         X3D, images; what `scripts/fuzz.sh replay` runs in a build of its own), in
#         ${CELLBAKE_ASAN_DIR:-build-asan};
#   tsan  ThreadSanitizer over the bake graph (GL and Embree bakes on 2
#         threads), parallel ingest, merge, the bake lock and concurrent
#         schema creation, in ${CELLBAKE_TSAN_DIR:-build-tsan}; first it checks
#         that TSan still reports races planted in TBB tasks
#         (tests/sanitizers/tsan_canary.cpp).
# Each job builds with the default compiler (gcc), -O1 (the test programs'
# own code -O0: it compiles faster and no test spends its time there), only
# `cellbake` (the tests run it) and its test executables (asan: and the fuzz targets, fuzz_all;
# the runner library as a unity build,
# CELLBAKE_UNITY_RUNNER), then runs the selected tests with CTest; a sanitizer
# report fails the test that made it. Known third-party reports are suppressed
# (tests/sanitizers/*.supp), never cellbake's own.
#   scripts/sanitize.sh [asan] [tsan]        (default: both)
# Exit code 1 when a job failed; the last line names the failed jobs.
set -euo pipefail
cd "$(dirname "$0")/.."
jobs=("$@")
[ ${#jobs[@]} -gt 0 ] || jobs=(asan tsan)

# What each job builds (whole test executables) and which of their tests it
# skips (docs/reliability.md, with the measured cost): the kill -9 bake (the
# slowest; test_kill_resume is the suite's), and under TSan the bakes whose
# threads the others already run (what they check beyond is single-threaded):
# of test_integrity, TSan runs only the bake lock, the concurrent schema
# creation and the hot-journal recovery; its damage checks bake, cut a blob and
# check it on one thread (171 of the job's 405 test-seconds in a fresh clone).
asan_tests=(test_readers test_input_checks test_bake_config test_cli_values test_encode test_encode_triangle_list
            test_geometry_store test_cell_db_migration test_output_guards test_ingest test_integrity test_merge test_bake
            test_sample_backends test_cell_cache)
asan_exclude='^Bake\.KilledBakeResumesToTheSameDatabase$'
tsan_tests=(test_geometry_store test_cell_db_migration test_integrity test_merge test_bake test_bake_backends
            test_cell_cache)
tsan_exclude='^(Bake\.(KilledBakeResumesToTheSameDatabase|ChangedParametersRecomputeOnlyWhatTheyAffect)|Merge\.(MergingTheSameShardsAgainChangesNothing|ResumesIntoTheEmptyFileOfAMergeKilledBeforeItsSchema|RefusesShardsFromOtherParametersOrStores|ShardsPartitionTheCellsEvenly)|Integrity\.(CellsTotalIsTheConfigurationsCountAndStatusShowsPending|RecomputedContentHashesMatchTheBakesStamps|CheckCellDecodesEveryBlobAndRecomputesTheHash|CutOrWrongSizedFaceImagesAreDamagedThoughTheHashIsRestamped|FacesWithoutTrianglesStoreNoImageAndAreCheckedForIt|StatusCheckListsACellWithAHalvedJpegAndRepairRedoesIt|StatusRepairMarksDamagedCellsPendingAndTheBakeRedoesThem|MergeRefusesADamagedShardNamingIt|ADamagedNearChunkListOrMetaValueGivesALocatedError))$'

bash scripts/install-deps.sh build test

supp="${PWD}/tests/sanitizers"
# The fuzz replay's ASan options (scripts/fuzz.sh replay): one allocation over
# 2560 MiB a finding (libFuzzer's -rss_limit_mb); the image decoder's test adds
# full unwinding on malloc for its suppression (tests/fuzz/CMakeLists.txt).
fuzz_asan_options="detect_leaks=1:max_allocation_size_mb=2560:${ASAN_OPTIONS:-}"
# ASan's fast (frame-pointer) unwinding on malloc: it reaches the library frames
# lsan.supp names (OpenImageIO's leaked error string), and unlike the full
# unwinder (fast_unwind_on_malloc=0, scripts/fuzz.sh) it never takes libgcc's
# unwind lock, so bakes can draw with llvmpipe: with full unwinding they hung
# once llvmpipe had registered its JIT code's unwind tables (libgcc mallocs
# under that lock) and needed the much slower softpipe.
export ASAN_OPTIONS="detect_leaks=1:strict_string_checks=1:${ASAN_OPTIONS:-}"
export LSAN_OPTIONS="suppressions=${supp}/lsan.supp:print_suppressions=0:${LSAN_OPTIONS:-}"
export UBSAN_OPTIONS="suppressions=${supp}/ubsan.supp:print_stacktrace=1:halt_on_error=1:${UBSAN_OPTIONS:-}"
export TSAN_OPTIONS="suppressions=${supp}/tsan.supp:halt_on_error=1:second_deadlock_stack=1:${TSAN_OPTIONS:-}"

# configure_and_build JOB DIR FLAGS TESTS...: DIR with FLAGS; builds cellbake and TESTS.
configure_and_build() {
  local job="$1" dir="$2" flags="$3"
  shift 3
  echo "[sanitize] ${job}: building ${dir} (${flags}, -O1): cellbake $*"
  cmake -S . -B "${dir}" -G Ninja -DCMAKE_BUILD_TYPE=None \
    -DCMAKE_C_FLAGS="-O1 -g1 ${flags}" -DCMAKE_CXX_FLAGS="-O1 -g1 ${flags}" \
    -DCMAKE_EXE_LINKER_FLAGS="${flags}" -DCMAKE_SHARED_LINKER_FLAGS="${flags}" \
    -DCELLBAKE_BUILD_TESTS=ON -DCELLBAKE_BUILD_BENCH=OFF -DCELLBAKE_BUILD_VIEWER_APP=OFF -DCELLBAKE_UNITY_RUNNER=ON \
    -DCELLBAKE_TEST_TIMEOUT=1800 -DCELLBAKE_FUZZ_REPLAY_SEED=2 -DCELLBAKE_FUZZ_REPLAY_LIBRARY_RUNS=2500 \
    -DCELLBAKE_TEST_CODE_FLAGS=-O0 > "${dir}.configure.log" 2>&1 \
    || { cat "${dir}.configure.log"; return 1; }
  cmake --build "${dir}" -j "$(nproc)" --target cellbake "$@"
}

# run_tests DIR EXCLUDE TESTS...: CTest over TESTS' tests (each test is labelled with
# its executable, tests/CMakeLists.txt) but those matching EXCLUDE.
run_tests() {
  local dir="$1" exclude="$2" labels
  shift 2
  labels="^($(IFS='|'; echo "$*"))$"
  (cd "${dir}" && ctest --output-on-failure -j "$(nproc)" --timeout 1800 -L "${labels}" -E "${exclude}")
}

# The tsan job's check of itself: a race between TBB bodies (parallel_for and a
# flow-graph node) must be reported with these suppressions, and the same
# counter through std::atomic must not.
tsan_canary() {
  local dir="$1" mode log
  g++ -std=c++20 -O1 -g1 -fsanitize=thread -I. tests/sanitizers/tsan_canary.cpp runner/parallel.cpp -ltbb \
    -o "${dir}/tsan_canary" || return 1
  for mode in parallel_for flow_graph clean; do
    log="${dir}/tsan_canary.${mode}.log"
    "${dir}/tsan_canary" "${mode}" > "${log}" 2>&1 || true
    if [ "${mode}" = clean ] && grep -q "WARNING: ThreadSanitizer" "${log}"; then
      echo "[sanitize] tsan: the race-free canary was reported:"; cat "${log}"; return 1
    fi
    if [ "${mode}" != clean ] && ! grep -q "tsan_canary.cpp" "${log}"; then
      echo "[sanitize] tsan: the race planted in a TBB ${mode} body was not reported:"; cat "${log}"; return 1
    fi
  done
  echo "[sanitize] tsan: canary ok (planted races in a parallel_for and a flow-graph body reported, the atomic one not)"
}

run_job() {
  local job="$1" start status=0 built
  start=$(date +%s)
  case "${job}" in
    asan)
      local dir="${CELLBAKE_ASAN_DIR:-build-asan}"
      configure_and_build asan "${dir}" "-fsanitize=address,undefined -fno-sanitize-recover=undefined -fno-omit-frame-pointer" \
        "${asan_tests[@]}" fuzz_all || return 1
      built=$(date +%s)
      echo "[sanitize] asan: built in $(( built - start )) s; running ${asan_tests[*]} (except ${asan_exclude})"
      run_tests "${dir}" "${asan_exclude}" "${asan_tests[@]}" || status=1
      local fuzz_start
      fuzz_start=$(date +%s)
      echo "[sanitize] asan: fuzz replay (ctest -L fuzz_replay)"
      (cd "${dir}" && ASAN_OPTIONS="${fuzz_asan_options}" ctest --output-on-failure -j "$(nproc)" --timeout 900 \
        -L '^fuzz_replay$') || status=1
      echo "[sanitize] asan: fuzz replay $(( $(date +%s) - fuzz_start )) s" ;;
    tsan)
      local dir="${CELLBAKE_TSAN_DIR:-build-tsan}"
      configure_and_build tsan "${dir}" "-fsanitize=thread" "${tsan_tests[@]}" || return 1
      built=$(date +%s)
      tsan_canary "${dir}" || return 1
      echo "[sanitize] tsan: built in $(( built - start )) s; running ${tsan_tests[*]} (except ${tsan_exclude})"
      run_tests "${dir}" "${tsan_exclude}" "${tsan_tests[@]}" || status=1 ;;
    *) echo "[sanitize] unknown job '${job}' (asan, tsan)"; exit 2 ;;
  esac
  echo "[sanitize] ${job}: $([ ${status} = 0 ] && echo "no reports" || echo FAILED) (build $(( built - start )) s, tests $(( $(date +%s) - built )) s)"
  return ${status}
}

failed=()
for job in "${jobs[@]}"; do
  run_job "${job}" || failed+=("${job}")
done
if [ ${#failed[@]} -gt 0 ]; then
  echo "[sanitize] FAILED: ${failed[*]}"
  exit 1
fi
echo "[sanitize] ${jobs[*]}: no reports"
