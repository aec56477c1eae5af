#!/usr/bin/python3
"""A scripted engagement: the closed loop of `radar-emu run` stepped from Python, with the
ownship flown by this script instead of the scenario's INS.

The aircraft starts 4 km short of the runway threshold at 230 m and flies a 3-degree glide
path at 70 m/s; after half the run it levels off (a go-around decision made in Python). Each
frame prints the detections, the objects in the beam, and the strongest detection with the
scene object that dominates it and that object's true range (truth).
Usage: engagement.py [SCENARIO.toml] [--frames N]"""
import argparse

import numpy as np

import radar_emu

parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
parser.add_argument("scenario", nargs="?", help="scenario TOML (default: the embedded one)")
parser.add_argument("--frames", type=int, default=20)
args = parser.parse_args()

loop = radar_emu.Loop(args.scenario, frames=args.frames)
dt = 1.0 / loop.rate_hz
names = loop.object_names
position = np.array([0.0, -4000.0, 230.0])
glide = np.radians(3.0)
print(f"{loop.name}: {loop.frames} frames at {loop.rate_hz:g} Hz")
print(f"{'frame':>5} {'t_s':>5} {'north_m':>8} {'up_m':>6} {'dets':>4} {'in beam':>7}  strongest detection")
for k in range(loop.frames):
    level = k >= loop.frames // 2
    velocity = np.array([0.0, 70.0, 0.0 if level else -70.0 * np.tan(glide)])
    frame = loop.step(dict(position_enu_m=position, velocity_enu_mps=velocity,
                           heading_deg=0.0, pitch_deg=0.0 if level else 2.0, roll_deg=0.0))
    dets, truth = frame["detections"], frame["truth"]
    strongest = ""
    if len(dets):
        d = dets[np.argmax(dets["snr_db"])]
        what = "clutter" if d["object_id"] < 0 else names[d["object_id"]]
        strongest = f"{d['range_m']:.1f} m {d['snr_db']:.1f} dB: {what}"
        match = truth[truth["object_id"] == d["object_id"]]
        if len(match):
            strongest += f" (true range {match['range_m'][0]:.1f} m)"
    print(f"{k:5d} {frame['time_s']:5.2f} {position[1]:8.1f} {position[2]:6.1f} {len(dets):4d} "
          f"{len(truth):7d}  {strongest}")
    position = position + velocity * dt
summary = loop.finish()
print(f"{summary['frames']} frames, {summary['detections_total']} detections, "
      f"{summary['sink_lists']} lists reassembled by the avionics sink")
