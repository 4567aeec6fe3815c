#!/usr/bin/env bash
# README command 2: install what is missing, build, and run the whole test suite.
#   --sanitize   also build with AddressSanitizer + UndefinedBehaviorSanitizer in build-asan/ and
#                run the suite there, but for the end-to-end tests (ctest label e2e: the shipped
#                experiments at a small scale, thread-count determinism), the browser test (label
#                browser: report.html in headless chromium) and the Blender script's (label blender,
#                only where Blender is installed), which the release pass runs: none of them tests
#                more under the sanitizers. The sanitizer tree is built without MPI (QUIJIBO_WITH_MPI=OFF), so CI also
#                checks that build, and without the Python module (an ASan-instrumented extension
#                only loads into an interpreter started with LD_PRELOAD=libasan; the release pass
#                runs the Python tests). Its libraries are compiled at -O1 -g1 (ASan's advice; line
#                tables are enough for its stack traces) and its tests and command line at -O0
#                (quijibo_run_once_code in CMakeLists.txt). The sanitizer pass leaves out the tests
#                that only repeat whole optimizer runs in child processes (kill and resume of both
#                back ends, every precision through Optimize) and three that take minutes there
#                (the kernel fit's spacing rule, 200 to 1000 roots; the shipped meshes' SDFs; the
#                bunny's modulus mesh): the release pass runs them all, and the code they drive runs
#                under the sanitizers in the other tests of the same code (docs/benchmarks.md §10).
# Each phase's time goes to stderr ("test.sh: ... N s"), to see where CI time goes.
set -euo pipefail
cd "$(dirname "$0")/.."
phase() {
  local name=$1 t0=$SECONDS
  shift
  "$@"
  echo "test.sh: $name $((SECONDS - t0)) s" >&2
}
phase "install" ./scripts/install-deps.sh
phase "release build" ./scripts/build.sh
phase "release tests" ctest --test-dir build --output-on-failure -j "$(nproc)"
if [[ "${1:-}" == "--sanitize" ]]; then
  export QUIJIBO_BUILD_DIR=build-asan
  phase "sanitizer build" ./scripts/build.sh -DCMAKE_BUILD_TYPE=RelWithDebInfo -DQUIJIBO_SANITIZE=ON \
    "-DCMAKE_CXX_FLAGS_RELWITHDEBINFO=-O1 -g1 -DNDEBUG" -DQUIJIBO_E2E_TESTS=OFF -DQUIJIBO_WITH_MPI=OFF \
    -DQUIJIBO_PYTHON=OFF
  export ASAN_OPTIONS=detect_leaks=1 UBSAN_OPTIONS=print_stacktrace=1
  phase "sanitizer tests" ctest --test-dir build-asan --output-on-failure -j "$(nproc)" -LE 'e2e|browser|blender' \
    -E 'KillResume|PrecisionsThroughOptimize|RunTest\.KilledAndResumed|KernelFit\.ThinParts|SdfShippedMeshes\.BunnyAndTooth|ModulusCli\.BunnyModulusMesh'
fi
