#!/usr/bin/env bash
# The test job: installs what is missing, builds with warnings as errors (gcc), runs every CTest
# suite, then builds one clang tree with AddressSanitizer + UndefinedBehaviorSanitizer (and
# libFuzzer's coverage instrumentation) holding both the suites that touch parsing and codecs
# (CTest label "sanitize") and the libFuzzer harnesses, runs those suites under the sanitizers
# and each harness for a few seconds (scripts/fuzz.sh runs them long; docs/fuzzing.md).
# One sanitizer tree rather than a gcc ASan tree beside a clang fuzz tree: the libraries are
# compiled once for both (CI from a clean clone: docs/performance.md, "CI time"). That tree
# compiles at -O0 (a few seconds of fuzzing each, where compiling is most of the stage);
# scripts/fuzz.sh builds its own tree at -O1 for long campaigns.
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
jobs="$(nproc)"
"$root/scripts/install-deps.sh"

echo "== build (release, -Werror) =="
"$root/scripts/build.sh" "$root/build" -DRADAR_EMU_WERROR=ON
echo "== tests =="
ctest --test-dir "$root/build" --output-on-failure -j "$jobs"

# RADAR_EMU_CI_FUZZ_S: seconds per harness (default 5; 0 skips fuzzing and the harnesses' build).
fuzz_s="${RADAR_EMU_CI_FUZZ_S:-5}"
san_targets="sanitize_tests"
[ "$fuzz_s" != "0" ] && san_targets="sanitize_tests fuzz_all"
echo "== build (clang, ASan+UBSan, -Werror): the sanitize-labelled suites and the fuzz harnesses =="
RADAR_EMU_TARGETS="$san_targets" "$root/scripts/build.sh" "$root/build-sanitize" \
  -DCMAKE_C_COMPILER=clang -DCMAKE_CXX_COMPILER=clang++ -DRADAR_EMU_FUZZ=ON -DRADAR_EMU_WERROR=ON \
  -DRADAR_EMU_BUILD_BENCHMARKS=OFF -DCMAKE_BUILD_TYPE=Debug -DRADAR_EMU_LINE_DEBUG_INFO=ON \
  -DRADAR_EMU_FUZZ_OPT=-O0
echo "== tests under ASan+UBSan (label: sanitize) =="
ASAN_OPTIONS=detect_leaks=1:abort_on_error=1 UBSAN_OPTIONS=print_stacktrace=1 \
  ctest --test-dir "$root/build-sanitize" --output-on-failure -j "$jobs" -L sanitize

if [ "$fuzz_s" != "0" ]; then
  echo "== fuzzing, bounded: each harness $fuzz_s s (libFuzzer + ASan + UBSan) =="
  "$root/scripts/fuzz.sh" --no-build --time "$fuzz_s" --parallel "$jobs" --build "$root/build-sanitize"
fi
