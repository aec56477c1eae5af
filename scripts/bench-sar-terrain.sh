#!/usr/bin/env bash
# The SAR case over the generated database (examples/sar_terrain.toml), timed: wall and CPU time
# of the whole run (GNU time) and sar.json's stage times, against the 3-minute goal on the
# project's 2-core machine. Not a unit test (timings depend on the machine's load).
#   scripts/bench-sar-terrain.sh [BUILD_DIR] [OUT_DIR]
set -euo pipefail
here="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
build="${1:-$here/build}"
out="${2:-$(mktemp -d)}"
start=$(date +%s.%N)
/usr/bin/time -f "cpu %U s user + %S s system, peak %M KiB" \
  "$build/app/radar-emu" sar "$here/examples/sar_terrain.toml" --out "$out" -q
end=$(date +%s.%N)
wall=$(echo "$end - $start" | bc)
python3 - "$out/sar.json" "$wall" <<'PY'
import json, sys
j = json.load(open(sys.argv[1]))
wall = float(sys.argv[2])
print("stages [s]:", {k: round(v, 2) for k, v in j["timing_s"].items()})
for r in j["regions"]:
    print(f"  {r['material']:9s} {r['pixels']:7d} px  image {r['image_sigma0_db']:8.2f} dB  "
          f"catalogue {r['catalogue_sigma0_db']:9.2f} dB")
print(f"wall {wall:.1f} s (goal: under 180 s on the 2-core machine): "
      + ("met" if wall < 180 else "NOT met"))
PY
