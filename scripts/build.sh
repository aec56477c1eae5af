#!/usr/bin/env bash
# Configures (once) and builds radar-emu. Usage: scripts/build.sh [BUILD_DIR] [extra cmake args]
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
dir="${1:-$root/build}"
shift || true
gen=()
if command -v ninja >/dev/null 2>&1 && [ ! -f "$dir/CMakeCache.txt" ]; then gen=(-G Ninja); fi
cmake -S "$root" -B "$dir" "${gen[@]}" "$@" >/dev/null
cmake --build "$dir" -j "$(nproc)"
