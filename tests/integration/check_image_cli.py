#!/usr/bin/python3
"""`radar-emu image` end to end through the real binary, its files read here.

1. examples/ev_radar_94ghz.toml at 52 s with --plot: image.csv has one line per pixel of the
   200 x 66 grid (0.15 deg: azimuth -14.925 .. 14.925, elevation 4.925 down), each row's
   ranges are those of a flat ground seen from image.json's ownship height (R = h / sin psi of
   the row's edges, psi from the antenna's 3 deg below the horizon), image.json matches, and
   image.png is a PNG of the size the layout gives (read from its IHDR chunk).
2. The 10-look intensity over the grass right of the runway: I / <I> (both from the CSV) has
   coefficient of variation 1/sqrt(10) within 10 %, computed here with statistics.
3. The same with 1 look: 1 within 10 %."""
import csv
import json
import math
import os
import statistics
import struct
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from cli_check import check, finish, runner  # noqa: E402
from figure_checks import check_figure  # noqa: E402

exe, source_dir, out = sys.argv[1], sys.argv[2], sys.argv[3]
run = runner(exe)
scenario = os.path.join(source_dir, "examples", "ev_radar_94ghz.toml")


def image(looks, d):
    run("image", scenario, "--time-s", "52", "--looks", str(looks), "--out", d, "--plot", "-q")
    with open(os.path.join(d, "image.json")) as f:
        meta = json.load(f)
    with open(os.path.join(d, "image.csv")) as f:
        rows = list(csv.DictReader(f))
    return meta, rows


def grass_cv(rows):
    # Azimuth 9-14 deg, ranges 300-700 m: grass only (the runway ends at 22.5 m east, the remote
    # stand's link starts at x = 85 m, 688 m north of the threshold).
    x = [10 ** ((float(r["intensity_dbsm"]) - float(r["mean_dbsm"])) / 10) for r in rows
         if 9.0 <= float(r["azimuth_deg"]) <= 14.0 and float(r["range_near_m"]) > 300.0
         and float(r["range_far_m"]) < 700.0]
    return statistics.pstdev(x) / statistics.fmean(x), len(x)


meta, rows = image(10, os.path.join(out, "looks10"))
g = meta["grid"]
check(g["columns"] == 200 and g["rows"] == 66, f"grid {g['columns']} x {g['rows']}, want 200 x 66")
check(len(rows) == 200 * 66, f"{len(rows)} CSV lines, want {200 * 66}")
check(meta["looks"] == 10 and meta["speckle_seed"] == 20261124, "looks and seed in image.json")
h = meta["ownship_enu_m"][2] - meta["ground_height_m"]
check(abs(h - (230.0 - 3.67 * 52)) < 1e-6, f"ownship height {h}")
# The antenna: pitch 2 deg, depression 5 deg: boresight 3 deg below the horizon. Centre column
# (azimuth -0.075 deg, cos ~ 1): the ray at antenna elevation e meets the ground at
# h / sin(3 deg - e) (small-azimuth flat earth; 1e-3 relative covers the 0.075 deg offset).
worst = 0.0
for r in rows:
    if r["column"] != "99":
        continue
    e_far = float(r["elevation_deg"]) + 0.075
    e_near = float(r["elevation_deg"]) - 0.075
    for e, key in ((e_far, "range_far_m"), (e_near, "range_near_m")):
        psi = math.radians(3.0 - e)
        if psi > 0.001 and math.isfinite(float(r[key])):
            worst = max(worst, abs(float(r[key]) / (h / math.sin(psi)) - 1.0))
check(worst < 1e-3, f"row ranges against h / sin(psi): worst relative error {worst:.2e}")
cv, n = grass_cv(rows)
check(n > 300, f"{n} grass pixels")
check(abs(cv * math.sqrt(10) - 1.0) < 0.1, f"10 looks: CV {cv:.4f} over {n} pixels, want "
      f"{1 / math.sqrt(10):.4f} within 10 %")
with open(os.path.join(out, "looks10", "image.png"), "rb") as f:
    head = f.read(24)
check(head[:8] == b"\x89PNG\r\n\x1a\n", "image.png is a PNG")
w, hgt = struct.unpack(">II", head[16:24])
# Two panels side by side, 2000 x 400 (tools/image.cpp: the radar image in grey with its colour
# bar [dBsm], the optical preview), labels with units (figure_checks.py).
check((w, hgt) == (2000, 400), f"image.png is {w} x {hgt}, want 2000 x 400")
for f in check_figure(os.path.join(out, "looks10", "image.png"), size=(2000, 400), colour_bars=1,
                      texts=["azimuth [deg]", "elevation [deg]", "pixel [dBsm]"]):
    check(False, f)

meta1, rows1 = image(1, os.path.join(out, "looks1"))
cv1, n1 = grass_cv(rows1)
check(abs(cv1 - 1.0) < 0.1, f"1 look: CV {cv1:.4f} over {n1} pixels, want 1 within 10 %")
print(f"CV over {n} grass pixels: 10 looks {cv:.4f} (1/sqrt(10) = {1 / math.sqrt(10):.4f}), "
      f"1 look {cv1:.4f}; row ranges within {worst:.1e} of h / sin(psi)")
finish()
