#!/usr/bin/env bash
# Fuzzes a reader with libFuzzer (clang, ASan + UBSan), docs/fuzzing.md:
#   scripts/fuzz.sh TARGET [SECONDS] [-- libFuzzer flags...]
#   TARGET: mesh_reader (ReadMesh: OBJ/PLY/STL/OFF) | experiment (the experiment parser)
# Builds build-fuzz/ (clang, -DQUIJIBO_FUZZ=ON), fuzzes for SECONDS (default 600) starting from the
# kept corpus tests/fuzz/corpus/TARGET plus the seeds in tests/fuzz/seeds/TARGET, then merges what
# it found back into the kept corpus (-merge=1 keeps only inputs that add coverage). A crash leaves
# its input in build-fuzz/findings/TARGET/ and the script fails.
set -euo pipefail
cd "$(dirname "$0")/.."
TARGET=${1:?usage: scripts/fuzz.sh mesh_reader|experiment [SECONDS] [-- flags]}
SECONDS_TO_RUN=${2:-600}
shift $(( $# >= 2 ? 2 : 1 ))
[[ "${1:-}" == "--" ]] && shift
case "$TARGET" in mesh_reader|experiment) ;; *) echo "fuzz.sh: unknown target '$TARGET' (mesh_reader or experiment)" >&2; exit 2;; esac

./scripts/install-deps.sh
missing=()
for p in clang-14 libclang-rt-14-dev libomp-14-dev; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if ((${#missing[@]})); then
  export DEBIAN_FRONTEND=noninteractive
  apt-get update -qq && apt-get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null
fi

CC=clang-14 CXX=clang++-14 cmake -S . -B build-fuzz -G Ninja -DCMAKE_BUILD_TYPE=RelWithDebInfo \
  -DQUIJIBO_FUZZ=ON >/dev/null
cmake --build build-fuzz --target "fuzz_$TARGET" -j "$(nproc)"

KEPT=tests/fuzz/corpus/$TARGET
WORK=build-fuzz/corpus/$TARGET
FINDINGS=build-fuzz/findings/$TARGET
mkdir -p "$KEPT" "$WORK" "$FINDINGS"
DICT=()
[[ -f tests/fuzz/$TARGET.dict ]] && DICT=(-dict="tests/fuzz/$TARGET.dict")
# UBSan reports are fatal (-fno-sanitize-recover); leaks are reported at exit.
export ASAN_OPTIONS=detect_leaks=1:abort_on_error=1
export LSAN_OPTIONS=suppressions=$PWD/tests/fuzz/lsan.supp:print_suppressions=0
export UBSAN_OPTIONS=print_stacktrace=1
status=0
"build-fuzz/tests/fuzz_$TARGET" "$WORK" "$KEPT" tests/fuzz/seeds/"$TARGET" "${DICT[@]}" \
  -max_total_time="$SECONDS_TO_RUN" -rss_limit_mb=4096 -timeout=30 -max_len=65536 \
  -artifact_prefix="$FINDINGS/" -print_final_stats=1 "$@" || status=$?
# Keep a minimal corpus that covers what this run covered.
"build-fuzz/tests/fuzz_$TARGET" -merge=1 -artifact_prefix="$FINDINGS/" "$KEPT" "$WORK" tests/fuzz/seeds/"$TARGET" "${DICT[@]}" \
  >/dev/null 2>&1 || true
echo "fuzz.sh: $TARGET: kept corpus $(ls "$KEPT" | wc -l) files; findings in $FINDINGS: $(ls "$FINDINGS" | wc -l)" >&2
exit $status
