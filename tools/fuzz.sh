#!/usr/bin/env bash
# Copyright (C) 2026 the gcpstereo authors. SPDX-License-Identifier: GPL-3.0-or-later
# Builds the libFuzzer harnesses of tests/fuzz/ with clang (ASan + UBSan) in build-fuzz/ and runs
# each for SECONDS (default 60) from its seed corpus (tests/fuzz/make_corpus.py; the config harness
# also starts from configs/*.yaml). Prints, per harness, the executions run and the findings (crash,
# leak, timeout and out-of-memory files, kept in build-fuzz/findings/<harness>/); exits 1 when
# there is any.
#
#   tools/fuzz.sh [SECONDS] [HARNESS...]     e.g. tools/fuzz.sh 120, tools/fuzz.sh 30 pfm ply
#
# Environment: CC / CXX (default clang-14 / clang++-14), JOBS (build jobs, default nproc),
# FUZZ_BUILD_DIR (default build-fuzz). Run it under `nice -n 19` on a shared machine.
set -euo pipefail
SECONDS_PER_HARNESS="${1:-60}"
shift || true
ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
BUILD="${FUZZ_BUILD_DIR:-$ROOT/build-fuzz}"
CC="${CC:-clang-14}"
CXX="${CXX:-clang++-14}"
ALL_HARNESSES=(ply pcd kitti_bin pfm strecha_camera middlebury kitti_calibration kitti_timestamps
               config colmap_bin colmap_txt oriented_cloud known_centres)
if [[ $# -gt 0 ]]; then HARNESSES=("$@"); else HARNESSES=("${ALL_HARNESSES[@]}"); fi

# Largest input per harness: a little above its largest seed, so that mutations stay in the
# header-and-a-few-records regime where the parsers branch.
max_len() {
  case "$1" in
    middlebury) echo 4096 ;;
    colmap_bin | colmap_txt | config) echo 8192 ;;
    *) echo 2048 ;;
  esac
}

command -v "$CXX" > /dev/null || { echo "fuzz.sh: $CXX not found (apt-get install clang-14)" >&2; exit 2; }
mkdir -p "$BUILD"
cmake -S "$ROOT" -B "$BUILD" -DGCPSTEREO_FUZZ=ON -DGCPSTEREO_BUILD_TESTS=OFF \
  -DGCPSTEREO_BUILD_BENCHMARKS=OFF -DCMAKE_BUILD_TYPE=RelWithDebInfo \
  -DCMAKE_CXX_FLAGS_RELWITHDEBINFO="-O1 -g" -DCMAKE_C_FLAGS_RELWITHDEBINFO="-O1 -g" \
  -DCMAKE_C_COMPILER="$CC" -DCMAKE_CXX_COMPILER="$CXX" > "$BUILD/configure.log" 2>&1 ||
  { cat "$BUILD/configure.log" >&2; exit 2; }
targets=()
for h in "${HARNESSES[@]}"; do targets+=("fuzz_$h"); done
cmake --build "$BUILD" -j"${JOBS:-$(nproc)}" --target "${targets[@]}"

python3 "$ROOT/tests/fuzz/make_corpus.py" "$BUILD/seeds"
cp "$ROOT"/configs/*.yaml "$BUILD/seeds/config/"
# The readers' scratch files go to a tmpfs folder when there is one.
export TMPDIR
TMPDIR="$(mktemp -d "$( [[ -d /dev/shm ]] && echo /dev/shm || echo "${TMPDIR:-/tmp}")/gcpstereo-fuzz.XXXXXX")"
trap 'rm -rf "$TMPDIR"' EXIT
# Leaks in PCL / OpenCV internals are not ours to fix; ours are caught by the unit suite's ASan run.
export ASAN_OPTIONS="${ASAN_OPTIONS:-detect_leaks=1:allocator_may_return_null=0}"
export UBSAN_OPTIONS="${UBSAN_OPTIONS:-print_stacktrace=1:halt_on_error=1}"

total=0
printf '\n%-18s %12s %9s  %s\n' harness executions findings "files"
for h in "${HARNESSES[@]}"; do
  corpus="$BUILD/corpus/$h"
  findings="$BUILD/findings/$h"
  rm -rf "$findings"  # this run's findings only
  mkdir -p "$corpus" "$findings"
  log="$BUILD/logs/$h.log"
  mkdir -p "$(dirname "$log")"
  # -rss_limit_mb / -malloc_limit_mb: a reader that allocates what a header claims is a finding.
  set +e
  "$BUILD/tests/fuzz/fuzz_$h" "$corpus" "$BUILD/seeds/$h" -max_total_time="$SECONDS_PER_HARNESS" \
    -max_len="$(max_len "$h")" -timeout=10 -rss_limit_mb=2048 -malloc_limit_mb=1024 \
    -artifact_prefix="$findings/" -print_final_stats=1 > "$log" 2>&1
  set -e
  execs="$(grep -o 'stat::number_of_executed_units: *[0-9]*' "$log" | grep -o '[0-9]*$' | tail -1)"
  if [[ -z "$execs" ]]; then
    execs="$(grep -o '^#[0-9]*' "$log" | tail -1 | tr -d '#')"
  fi
  found=("$findings"/*)
  [[ -e "${found[0]}" ]] || found=()
  total=$((total + ${#found[@]}))
  printf '%-18s %12s %9d  %s\n' "$h" "${execs:-?}" "${#found[@]}" \
    "$(for f in "${found[@]}"; do basename "$f"; done | tr '\n' ' ')"
done
echo "logs: $BUILD/logs/<harness>.log; findings kept in $BUILD/findings/<harness>/"
if [[ $total -gt 0 ]]; then
  echo "fuzz.sh: $total finding(s)" >&2
  exit 1
fi
