#!/usr/bin/env bash
# The test suite as CI runs it (.ci/run, the README's second command), after `cmake --build build`:
#   1. the whole suite on the normal build in build/;
#   2. the unit suite again under AddressSanitizer (with LeakSanitizer) and UndefinedBehaviorSanitizer,
#      in build-asan/ (GCPSTEREO_SANITIZE=ON, RelWithDebInfo so that it is not too slow and reports
#      name the source line). Any sanitizer report fails the test that caused it: UBSan is built with
#      -fno-sanitize-recover=undefined and halts, ASan and LSan exit non-zero.
#      Each test may take 1800 s there instead of 600 (GCPSTEREO_TEST_TIMEOUT, CMakeLists.txt).
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
cmake -S . -B build-asan -DCMAKE_BUILD_TYPE=RelWithDebInfo -DGCPSTEREO_SANITIZE=ON \
  -DGCPSTEREO_BUILD_BENCHMARKS=OFF
cmake --build build-asan -j"$jobs"
built=$(date +%s)

supp="$root/tools/sanitizers"
export ASAN_OPTIONS="detect_leaks=1:check_initialization_order=1:strict_init_order=1:halt_on_error=1"
export LSAN_OPTIONS="suppressions=$supp/lsan.supp:print_suppressions=0"
export UBSAN_OPTIONS="halt_on_error=1:print_stacktrace=1"
export GCPSTEREO_DATA="$root/build-asan/no-real-data-under-sanitizers"
ctest --test-dir build-asan --output-on-failure -j"$jobs"
echo "tools/test.sh: sanitizer build $((built - start)) s, sanitizer tests $(($(date +%s) - built)) s"
