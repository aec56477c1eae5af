#!/usr/bin/env bash
# The fidelity governor on a scene heavier than the machine: examples/terrain_movers.toml (three
# vehicles on the 207k-polygon terrain database) run at RATE_HZ frames a second (default 100: a
# 10 ms budget, where a full-physics frame of that scene takes about 25 times as long on a
# 2-core machine) with the governor on, FRAMES frames (default 200). Prints the summary's budget
# and governor lines, and from report.json the frames over budget, the overruns, the frames at
# each governor level and the outcome of the scenario's [[target]] vehicles (docs/outcome.md), so that what the governor gave
# up to hold the period can be read beside whether it held it.
#
# usage: scripts/governor-heavy.sh [FRAMES] [RATE_HZ]
# environment: RADAR_EMU (default build/app/radar-emu), OUT (default out/governor-heavy), PULSES
# (pulses per beam position; default the most whose timeline fits the period)
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
frames="${1:-200}"
rate="${2:-100}"
exe="${RADAR_EMU:-$root/build/app/radar-emu}"
out="${OUT:-$root/out/governor-heavy}"
if ! [[ "$frames" =~ ^[0-9]+$ ]] || [ "$frames" -lt 1 ]; then
  echo "usage: scripts/governor-heavy.sh [FRAMES] [RATE_HZ]" >&2
  exit 2
fi
[ -x "$exe" ] || { echo "governor-heavy: $exe not found: build first (scripts/build.sh)" >&2; exit 2; }
mkdir -p "$out"
scenario="$out/terrain_movers_${rate}hz.toml"
pulses="${PULSES:-$(/usr/bin/python3 -c "print(min(32, int(1000.0 / $rate / (16 * 0.05) + 1e-9)))")}"
{
  cat "$root/examples/terrain_movers.toml"
  # The radar's timeline (beams x pulses x PRI) must fit the period, or the run is refused
  # with its numbers: the default's 16 beams x 32 pulses x 0.05 ms (25.6 ms) take PULSES per
  # beam (default: the most that fit, 12 at 100 Hz: 9.6 ms and a 2.7 m/s velocity bin); the
  # scene, the scan, the beam and the physics stay the scenario's.
  printf '\n[run]\nrate_hz = %s\n\n[radar]\npulses = %s\n\n[governor]\nenabled = true\n' \
    "$rate" "$pulses"
} >"$scenario"
echo "governor-heavy: $frames frames of examples/terrain_movers.toml at $rate Hz ($pulses pulses per beam), governor on ($(nproc) cores)"
"$exe" run "$scenario" --frames "$frames" --out "$out/run" | grep -E "budget|governor|frame  |trace|sensor|movers" || true
/usr/bin/python3 - "$out/run/report.json" "$scenario" <<'PY'
import json, sys, tomllib
r = json.load(open(sys.argv[1]))
s, g = r["schedule"], r["governor"]
print(f"report.json: period {s['period_ms']:.1f} ms, {s['frames_over_budget']} frames over budget, "
      f"{s['overruns']} overruns; {g['frames_degraded']} of {r['frames']} frames degraded; "
      f"frames at each level 0..{g['max_level']}: {g['frames_at_level']}")
names = {t["name"] for t in tomllib.load(open(sys.argv[2], "rb")).get("target", [])}
for t in r["outcome"]["targets"]:
    if t["object"] in names:
        print(f"  {t['object']}: in the beam {t['frames_in_beam']} frames, detected in "
              f"{t['frames_detected']} (Pd {t['pd']})")
PY
