#!/usr/bin/env bash
# The whole test suite, as CI runs it (after scripts/install-deps.sh):
#  1. the Release build in build/ and every test (ctest), the fuzz targets' replays included;
#  2. the suite built with AddressSanitizer + UndefinedBehaviorSanitizer in build-asan/, minus
#     the end-to-end tests labelled `slow` (they train networks, which ASan makes several times
#     slower; the unit tests and fuzz replays it runs cover the same code). Any sanitizer report
#     fails the test that triggered it.
#   --no-sanitizers  only step 1 (a quicker local run)
# Each step stops the script on failure.
set -euo pipefail
cd "$(dirname "$0")/.."
jobs="${CGSR_TEST_JOBS:-2}"

cmake -S . -B build -G Ninja -DCMAKE_BUILD_TYPE=Release
cmake --build build
ctest --test-dir build --output-on-failure -j"$jobs"

if [ "${1:-}" != "--no-sanitizers" ]; then
  cmake -S . -B build-asan -G Ninja -DCMAKE_BUILD_TYPE=Release -DCGSR_SANITIZE=ON -DCGSR_BUILD_BENCH=OFF
  cmake --build build-asan
  ctest --test-dir build-asan --output-on-failure -j"$jobs" -LE slow
fi
