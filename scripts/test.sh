#!/usr/bin/env bash
# README command 2: install what is missing, build, and run the whole test suite.
#   --sanitize   also build with AddressSanitizer + UndefinedBehaviorSanitizer in build-asan/ and
#                run the suite there
set -euo pipefail
cd "$(dirname "$0")/.."
./scripts/install-deps.sh
./scripts/build.sh
ctest --test-dir build --output-on-failure -j "$(nproc)"
if [[ "${1:-}" == "--sanitize" ]]; then
  QUIJIBO_BUILD_DIR=build-asan ./scripts/build.sh -DCMAKE_BUILD_TYPE=RelWithDebInfo -DQUIJIBO_SANITIZE=ON
  ASAN_OPTIONS=detect_leaks=1 UBSAN_OPTIONS=print_stacktrace=1 \
    ctest --test-dir build-asan --output-on-failure -j "$(nproc)"
fi
