#!/usr/bin/env bash
# The test suite, as CI runs it (after scripts/install-deps.sh): the Release build in build/ and
# every test (ctest), the fuzz targets' replays included. About 10 minutes on 2 cores.
#   --sanitizers  then also the suite built with AddressSanitizer + UndefinedBehaviorSanitizer in
#                 build-asan/, minus the end-to-end tests labelled `slow` (they train networks,
#                 which ASan makes several times slower; the unit tests and fuzz replays it runs
#                 cover the same code). Any sanitizer report fails the test that triggered it.
#                 Its build alone takes about 14 minutes here, so it is a separate step: run it
#                 before merging a change to a parser, a file format or the fused path.
# Each step stops the script on failure.
set -euo pipefail
cd "$(dirname "$0")/.."
jobs="${CGSR_TEST_JOBS:-2}"
case "${1:-}" in
  ""|--sanitizers) ;;
  *) echo "usage: scripts/test.sh [--sanitizers]" >&2; exit 2 ;;
esac

cmake -S . -B build -G Ninja -DCMAKE_BUILD_TYPE=Release
cmake --build build
ctest --test-dir build --output-on-failure -j"$jobs"

if [ "${1:-}" = "--sanitizers" ]; then
  cmake -S . -B build-asan -G Ninja -DCMAKE_BUILD_TYPE=Release -DCGSR_SANITIZE=ON -DCGSR_BUILD_BENCH=OFF
  cmake --build build-asan
  ctest --test-dir build-asan --output-on-failure -j"$jobs" -LE slow
fi
