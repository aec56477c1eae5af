#!/usr/bin/env bash
# The main job: installs what is missing, builds the radar-emu executable (only it and the
# libraries it links: no test or benchmark), then runs the closed loop on the embedded default
# scenario on the software bus. Extra arguments go to `radar-emu run`.
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
"$root/scripts/install-deps.sh"
RADAR_EMU_TARGETS=radar-emu "$root/scripts/build.sh" "$root/build" -DRADAR_EMU_WERROR=ON
exec "$root/build/app/radar-emu" run --out "${RADAR_EMU_OUT:-$root/out/run}" "$@"
