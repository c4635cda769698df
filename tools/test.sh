#!/usr/bin/env bash
# The test suite as CI runs it (.ci/run, the README's second command), after `cmake --build build`:
#   1. the whole suite on the normal build in build/;
#   2. the unit suite again under AddressSanitizer (with LeakSanitizer) and UndefinedBehaviorSanitizer,
#      in build-asan/ (GCPSTEREO_SANITIZE=ON, -O1 -g1 so that it is not too slow and reports name
#      the source line). Each GoogleTest executable runs whole, in shards side by side, without
#      the tests listed (with their reasons) in tools/sanitizers/skipped_tests.txt; logs in
#      build-asan/sanitizer-logs/. Any sanitizer report fails the shard that caused it: UBSan is
#      built with -fno-sanitize-recover=undefined and halts, ASan and LSan exit non-zero. Each
#      shard may take 1800 s (environment GCPSTEREO_TEST_TIMEOUT). The Snakemake test
#      (pipeline.Workflow, a Python script driving the gcpstereo command) is ctest's only and runs
#      in part 1 alone: it orchestrates the scene run that TinySceneRun covers here.
#
# Under the sanitizers the tests on the real data in ../shared/data are skipped (GCPSTEREO_DATA is
# pointed at a missing folder, so they skip with their usual message): they run the same readers and
# stages as the synthetic tests on images many times larger, which under ASan would not fit CI's
# budget; the normal build runs them.
#
# Usage: tools/test.sh [--no-sanitize]
# Environment: JOBS (parallel builds and tests; default: the number of processors).
set -euo pipefail
cd "$(dirname "$0")/.."
root=$(pwd)
jobs=${JOBS:-$(nproc)}

sanitize=1
for arg in "$@"; do
  case "$arg" in
    --no-sanitize) sanitize=0 ;;
    -h | --help)
      sed -n '2,/^set -euo/p' "$0" | sed '$d; s/^# \{0,1\}//'
      exit 0
      ;;
    *)
      echo "tools/test.sh: unknown argument '$arg' (see --help)" >&2
      exit 2
      ;;
  esac
done

ctest --test-dir build --output-on-failure -j"$jobs"
[ "$sanitize" = 1 ] || exit 0

echo "tools/test.sh: the unit suite under ASan + UBSan (build-asan/)"
start=$(date +%s)
# -O1 -g1: 40 % less compile time than RelWithDebInfo's -O2 -g; reports still name the line.
cmake -S . -B build-asan -DCMAKE_BUILD_TYPE=RelWithDebInfo -DGCPSTEREO_SANITIZE=ON \
  -DGCPSTEREO_BUILD_BENCHMARKS=OFF \
  "-DCMAKE_CXX_FLAGS_RELWITHDEBINFO=-O1 -g1 -DNDEBUG" "-DCMAKE_C_FLAGS_RELWITHDEBINFO=-O1 -g1 -DNDEBUG"
cmake --build build-asan -j"$jobs"
built=$(date +%s)

supp="$root/tools/sanitizers"
export ASAN_OPTIONS="detect_leaks=1:check_initialization_order=1:strict_init_order=1:halt_on_error=1"
export LSAN_OPTIONS="suppressions=$supp/lsan.supp:print_suppressions=0"
export UBSAN_OPTIONS="halt_on_error=1:print_stacktrace=1"
export GCPSTEREO_DATA="$root/build-asan/no-real-data-under-sanitizers"

# Each test executable runs whole (GoogleTest shards of it side by side), not one process per test
# as ctest does: a process of these executables starts in 0.3-0.5 s (the shared libraries' symbols),
# several times that under ASan, and there are 500 tests. The tests named in
# tools/sanitizers/skipped_tests.txt are left out (each with its reason there).
exclude=$(sed -e 's/#.*//' -e 's/[[:space:]]//g' "$supp/skipped_tests.txt" | grep -v '^$' | paste -sd: -)
logs="$root/build-asan/sanitizer-logs"
rm -rf "$logs" && mkdir -p "$logs"
# Shards per executable: its share of the suite's time.
shards_of() {
  case "$(basename "$1")" in
    gcpstereo_pipeline_test) echo 6 ;;
    gcpstereo_align_test | gcpstereo_gcp_test) echo 2 ;;
    *) echo 1 ;;
  esac
}
run_shard() {  # EXE INDEX COUNT
  local name log rc t0
  name="$(basename "$1")-$(($2 + 1))of$3"
  log="$logs/$name.log"
  t0=$(date +%s)
  rc=0
  (cd "$(dirname "$1")" && GTEST_SHARD_INDEX=$2 GTEST_TOTAL_SHARDS=$3 \
    timeout "${GCPSTEREO_TEST_TIMEOUT:-1800}" "$1" --gtest_filter="-$exclude" >"$log" 2>&1) || rc=$?
  if [ "$rc" = 0 ]; then
    echo "  passed $name ($(grep -m1 -oE 'PASSED  \] [0-9]+' "$log" | grep -oE '[0-9]+$') tests, $(($(date +%s) - t0)) s)"
  else
    echo "  FAILED $name (exit $rc, $(($(date +%s) - t0)) s): $log"
    echo "$log" >>"$logs/failed.txt"
    return 1
  fi
}
export -f run_shard
export logs exclude
shard_jobs=()
# The longest first, so that the last shards to start are short ones.
for exe in build-asan/tests/pipeline/gcpstereo_pipeline_test build-asan/tests/align/gcpstereo_align_test \
  build-asan/tests/gcp/gcpstereo_gcp_test $(ls build-asan/tests/*/gcpstereo_*_test | grep -vE '/(pipeline|align|gcp)/'); do
  n=$(shards_of "$exe")
  for ((i = 0; i < n; ++i)); do shard_jobs+=("$root/$exe" "$i" "$n"); done
done
# A pattern that names no test any more would leave nothing out, silently: refuse it.
listed=$(for exe in build-asan/tests/*/gcpstereo_*_test; do "$exe" --gtest_list_tests; done |
  awk '/^[^ ]/ {suite = $1} /^  / {print suite $1}')
for pattern in ${exclude//:/ }; do
  if ! grep -qx -- "$(sed -e 's/\./\\./g' -e 's/\*/.*/g' <<<"$pattern")" <<<"$listed"; then
    echo "tools/test.sh: tools/sanitizers/skipped_tests.txt: '$pattern' names no test" >&2
    exit 1
  fi
done
status=0
printf '%s\n' "${shard_jobs[@]}" | xargs -n3 -P"$jobs" bash -c 'run_shard "$@"' _ || status=$?
if [ "$status" != 0 ]; then
  for log in $(cat "$logs/failed.txt"); do
    echo "==== $log"
    tail -n 80 "$log"
  done
fi
echo "tools/test.sh: sanitizer build $((built - start)) s, sanitizer tests $(($(date +%s) - built)) s"
exit "$status"
