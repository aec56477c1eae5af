#!/usr/bin/env bash
# The test job: installs what is missing, builds with warnings as errors, runs every CTest
# suite, then rebuilds with AddressSanitizer + UndefinedBehaviorSanitizer and runs the suites
# that touch parsing and codecs (CTest label "sanitize") under it, then builds the libFuzzer
# harnesses with clang (ASan + UBSan too) and runs each for a few seconds (scripts/fuzz.sh runs
# them long; tests/fuzz/README.md).
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
jobs="$(nproc)"
"$root/scripts/install-deps.sh"

echo "== build (release, -Werror) =="
"$root/scripts/build.sh" "$root/build" -DRADAR_EMU_WERROR=ON
echo "== tests =="
ctest --test-dir "$root/build" --output-on-failure -j "$jobs"

echo "== build (ASan+UBSan): the sanitize-labelled suites only =="
RADAR_EMU_TARGETS=sanitize_tests "$root/scripts/build.sh" "$root/build-asan" -DRADAR_EMU_WERROR=ON -DRADAR_EMU_SANITIZE=ON \
  -DRADAR_EMU_BUILD_BENCHMARKS=OFF -DCMAKE_BUILD_TYPE=Debug -DRADAR_EMU_LINE_DEBUG_INFO=ON
echo "== tests under ASan+UBSan (label: sanitize) =="
ASAN_OPTIONS=detect_leaks=1:abort_on_error=1 UBSAN_OPTIONS=print_stacktrace=1 \
  ctest --test-dir "$root/build-asan" --output-on-failure -j "$jobs" -L sanitize

# RADAR_EMU_CI_FUZZ_S: seconds per harness (default 5; 0 skips the stage and its clang build).
fuzz_s="${RADAR_EMU_CI_FUZZ_S:-5}"
if [ "$fuzz_s" != "0" ]; then
  echo "== fuzzing, bounded: each harness $fuzz_s s (clang, libFuzzer + ASan + UBSan) =="
  "$root/scripts/fuzz.sh" --time "$fuzz_s" --parallel "$jobs" --build "$root/build-fuzz"
fi
