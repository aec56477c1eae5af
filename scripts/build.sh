#!/usr/bin/env bash
# Configures (once) and builds radar-emu. Usage: scripts/build.sh [BUILD_DIR] [extra cmake args]
# RADAR_EMU_TARGETS="t1 t2": build only those targets (and what they need); default: everything
# the configuration enables (with tests and benchmarks unless switched off).
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
dir="${1:-$root/build}"
shift || true
gen=()
if command -v ninja >/dev/null 2>&1 && [ ! -f "$dir/CMakeCache.txt" ]; then gen=(-G Ninja); fi
cmake -S "$root" -B "$dir" "${gen[@]}" "$@" >/dev/null
targets=()
for t in ${RADAR_EMU_TARGETS:-}; do targets+=(--target "$t"); done
cmake --build "$dir" -j "$(nproc)" "${targets[@]}"
