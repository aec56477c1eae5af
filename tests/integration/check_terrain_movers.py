#!/usr/bin/python3
"""examples/terrain_movers.toml end to end through the real binary: [[target]] tables on the
terrain database, seen by the default radar.

The scenario file is read here with Python's own TOML parser (tomllib). For every frame this
script puts the ownship on its straight line and each vehicle on its waypoint path (speed x time
along the polyline of the waypoints' (e, n); the path's small slopes change the length by less
than 0.2 %), and checks:
1. truth.json lists the three vehicles, by their table names, in every frame;
2. their true azimuth equals the bearing computed here from the horizontal positions, within
   0.2 deg, and their true range this range within 3 m (the vehicles' heights, dropped onto the
   road by on_ground, are unknown here: the ground is within +-15 m of 0, which moves the range
   by at most 15 x 200 / 2800 ~ 1.1 m);
3. detections.json names each vehicle in at least half of the frames (its echo can also come
   back named after the road that reflected it last), each such detection within the vehicle's
   half-length plus one range cell (c / 2B) of its true range.
The run is at the example's own fidelity (the governor off)."""
import json
import math
import os
import sys
import tomllib

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from cli_check import check, finish, runner  # noqa: E402

exe, source_dir, out = sys.argv[1], sys.argv[2], sys.argv[3]
run = runner(exe)
frames = 20
scenario_path = os.path.join(source_dir, "examples", "terrain_movers.toml")
with open(scenario_path, "rb") as f:
    scenario = tomllib.load(f)
# At the example's own fidelity: the fidelity governor would thin the vehicles' rays to hold the
# 50 ms budget (it has its own tests); appended as a table of its own, which the example lacks.
os.makedirs(out, exist_ok=True)
full_fidelity = os.path.join(out, "terrain_movers_full_fidelity.toml")
with open(scenario_path) as src, open(full_fidelity, "w") as dst:
    dst.write(src.read() + "\n[governor]\nenabled = false\n")
run("run", full_fidelity, "--quiet", "--frames", str(frames), "--out", out)
with open(os.path.join(out, "truth.json")) as f:
    truth = json.load(f)
with open(os.path.join(out, "detections.json")) as f:
    dets = json.load(f)

c_mps = 299792458.0
range_cell_m = c_mps / (2.0 * 50.0e6)  # the default [radar] bandwidth_hz
half_length_m = {"truck": 4.0, "vehicle": 3.5, "jeep": 2.0}  # default sizes, docs/scene_format.md
own = scenario["ownship"]
start, vel = own["start_enu_m"], own["velocity_enu_mps"]
heading = math.radians(own["heading_deg"])
elevation = math.radians(own["pitch_deg"] - 5.0)  # the default antenna depression, 5 deg
forward = (math.sin(heading), math.cos(heading))
right = (math.cos(heading), -math.sin(heading))


def on_path(waypoints, speed, t):
    """(e, n) at arc length speed * t along the polyline of the waypoints' (e, n)."""
    s = speed * t
    for a, b in zip(waypoints, waypoints[1:]):
        leg = math.hypot(b[0] - a[0], b[1] - a[1])
        if s <= leg:
            return (a[0] + (b[0] - a[0]) * s / leg, a[1] + (b[1] - a[1]) * s / leg)
        s -= leg
    return tuple(waypoints[-1][:2])


targets = scenario["target"]
names = [t["name"] for t in targets]
listed = [o["object"] for o in truth["objects"]]
for n in names:
    check(n in listed, f"truth.json objects list {n}")
check(len(truth["frames"]) == frames and len(dets["frames"]) == frames, "one record per frame")
named = {n: 0 for n in names}
for ft, fd in zip(truth["frames"], dets["frames"]):
    t = ft["time_s"]
    radar = [start[k] + vel[k] * t for k in range(3)]
    for tgt in targets:
        n = tgt["name"]
        e, no = on_path(tgt["waypoints_enu_m"], tgt["speed_mps"], t)
        de, dn, du = e - radar[0], no - radar[1], 0.0 - radar[2]
        along = (de * forward[0] + dn * forward[1]) * math.cos(elevation) + du * math.sin(elevation)
        across = de * right[0] + dn * right[1]
        az_deg = math.degrees(math.atan2(across, along))
        range_m = math.sqrt(de * de + dn * dn + du * du)
        entry = [o for o in ft["objects"] if o["object"] == n]
        check(len(entry) == 1, f"t {t:.2f} s: {n} in the beam in truth.json")
        if not entry:
            continue
        check(abs(entry[0]["azimuth_deg"] - az_deg) <= 0.2,
              f"t {t:.2f} s: {n} true azimuth {entry[0]['azimuth_deg']:.3f} deg, "
              f"bearing from its waypoints {az_deg:.3f} deg")
        check(abs(entry[0]["range_m"] - range_m) <= 3.0,
              f"t {t:.2f} s: {n} true range {entry[0]['range_m']:.1f} m, from its waypoints "
              f"{range_m:.1f} m")
        hits = [d for d in fd["detections"] if d["object"] == n]
        named[n] += 1 if hits else 0
        for d in hits:
            tol = half_length_m[tgt["builtin"]] + range_cell_m
            check(abs(d["range_m"] - entry[0]["range_m"]) <= tol,
                  f"t {t:.2f} s: {n} detected at {d['range_m']:.1f} m, true range "
                  f"{entry[0]['range_m']:.1f} m (tolerance {tol:.1f} m)")
for n in names:
    print(f"{n}: named in the detections of {named[n]} of {frames} frames")
    check(named[n] >= frames // 2, f"{n} named in at least half of the frames ({named[n]})")
finish()
