#!/usr/bin/env bash
# The main job: installs what is missing, builds, then runs the closed loop on the embedded
# default scenario on the software bus. Extra arguments go to `radar-emu run`.
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
"$root/scripts/install-deps.sh"
"$root/scripts/build.sh" "$root/build" -DRADAR_EMU_WERROR=ON
exec "$root/build/app/radar-emu" run --out "${RADAR_EMU_OUT:-$root/out/run}" "$@"
