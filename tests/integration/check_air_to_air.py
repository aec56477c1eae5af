#!/usr/bin/python3
"""The air-to-air example (examples/air_to_air.toml) run end to end, its outcome table checked.

1. The frames each target spends in the beam, from the geometry alone: the ownship at
   (0, 150 t, 3000) m looking level north, the field of view +-8 deg in azimuth, +-4 deg in
   elevation and out to max_range_m 6000 m, each target's reference point (the centre of its
   box: the origin is on the box's floor, so half its height above) at t = k / 20 s,
   k = 0..199. The crossing airliner (-300 + 60 t, 4500, 2995 + 5.9) and the hovering
   helicopter (-250, 3500, 2950 + 2.2) stay in the beam all 200 frames; the climbing jet, from
   (200, 6000, 2850) toward (200, 4800, 3150) at 120 m/s, starts 6001.8 m away, just beyond the
   swath, and is in the beam from frame 1. report.json's frames_in_beam must be those counts.
2. The two large, broadside targets at 3 to 4.5 km (SNR tens of dB) are detected in at least
   90 % of their frames; the head-on climbing jet in at least 20 % (it fades as it pitches up);
   every mean range error is within the target's half-length (its scatterers are on it).
3. The summary on stdout prints the size of each [[target]] and one outcome row per target.

usage: check_air_to_air.py RADAR_EMU SOURCE_DIR WORK_DIR
"""
import json
import math
import os
import subprocess
import sys

import cli_check
from cli_check import check, finish

exe, src, work = sys.argv[1], sys.argv[2], sys.argv[3]
os.makedirs(work, exist_ok=True)
cli_check.verbose = True  # an "ok" line for every check that passes


out = os.path.join(work, "out")
r = subprocess.run([exe, "run", os.path.join(src, "examples", "air_to_air.toml"), "--out", out],
                   capture_output=True, text=True, timeout=600)
check(r.returncode == 0, f"run: exit status {r.returncode}: {r.stderr[-400:]!r}")
with open(os.path.join(out, "report.json")) as f:
    outcome = json.load(f)["outcome"]
targets = {t["object"]: t for t in outcome["targets"]}


def frames_in_beam(centre):
    n = 0
    for k in range(200):
        t = k / 20.0
        dx, dy, dz = (c - o for c, o in zip(centre(t), (0.0, 150.0 * t, 3000.0)))
        az = math.degrees(math.atan2(dx, dy))
        el = math.degrees(math.atan2(dz, math.hypot(dx, dy)))
        n += abs(az) <= 8.0 and abs(el) <= 4.0 and math.sqrt(dx * dx + dy * dy + dz * dz) <= 6000.0
    return n


a, b = (200.0, 6000.0, 2850.0), (200.0, 4800.0, 3150.0)


def jet(t):
    s = min(120.0 * t / math.dist(a, b), 1.0)
    return tuple(p + (q - p) * s for p, q in zip(a, b))[:2] + (a[2] + (b[2] - a[2]) * s + 2.0,)


expected = {
    "crossing_airliner": (frames_in_beam(lambda t: (-300.0 + 60.0 * t, 4500.0, 2995.0 + 5.9)),
                          0.9, 37.6 / 2),
    "climbing_jet": (frames_in_beam(jet), 0.2, 15.0 / 2),
    "hovering_helicopter": (frames_in_beam(lambda t: (-250.0, 3500.0, 2950.0 + 2.2)), 0.9,
                            12.7 / 2),
}
for name, (beam, pd_min, half_length_m) in expected.items():
    t = targets.get(name)
    check(t is not None, f"{name}: in report.json's outcome")
    if t is None:
        continue
    check(t["frames_in_beam"] == beam,
          f"{name}: {t['frames_in_beam']} frames in the beam, the geometry's {beam}")
    check(t["pd"] is not None and t["pd"] >= pd_min, f"{name}: Pd {t['pd']} >= {pd_min}")
    err = t["range_error_m"]
    check(err is not None and abs(err["mean"]) <= half_length_m,
          f"{name}: mean range error {err and err['mean']:.2f} m within {half_length_m} m")
check(expected["climbing_jet"][0] == 199 and expected["crossing_airliner"][0] == 200,
      "the geometry: the jet enters the beam at frame 1, the others are in it throughout")
for line in ("target crossing_airliner: transport_aircraft 37.6 x 35.8 x 11.8 m",
             "target climbing_jet: transport_aircraft 15 x 10 x 4 m",
             "target hovering_helicopter: helicopter 12.7 x 14.6 x 4.4 m"):
    check(line in r.stdout, f"stdout: '{line}'")
for name in expected:
    check(any(l.strip().startswith(name + " ") for l in r.stdout.splitlines()),
          f"stdout: the outcome row of {name}")

finish()
