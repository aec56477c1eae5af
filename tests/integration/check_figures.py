#!/usr/bin/python3
"""Every product's figure, drawn by the plotting layer (plot/charts.hpp -> matplotlib), read back
here independently of the writer (docs/plotting.md): each CLI run with its plot option on a small
fast case, its PNG's size from the IHDR chunk and its SVG parsed with xml.etree: the data
panels' axis labels with a [unit], the colour bars' labels with a [unit] (figure_checks.py).
The products covered here: atten, ambiguity (map and cuts), sigma0 (cut and bistatic map), rcs
(cut, polar cut over a turn, map), profile and ISAR, and a run's detections.png (B-scope) and
timing.png (stacked stages, budget and governor deadline) from the run_default fixture. The EV
image, SAR and tradeoff figures are checked by check_image_cli.py, check_sar_cli.py and
check_tradeoff_cli.py, which make them anyway.
A map's colours are read back through its colour map: the cell centres' PNG colours, inverted
through matplotlib's viridis table, against the CSV's values (within 0.6 dB: the table has 256
steps over the 60 dB scale), the data area's pixel box from the renderer's axes record
(RADAR_EMU_PLOT_AXES=1).
Usage: check_figures.py RADAR_EMU WORK_DIR RUN_DIR"""
import csv
import json
import os
import sys

import matplotlib
import matplotlib.image
import numpy as np

from cli_check import check, finish, runner
from figure_checks import check_figure

exe, work, run_dir = sys.argv[1], sys.argv[2], sys.argv[3]
os.makedirs(work, exist_ok=True)
os.environ["RADAR_EMU_PLOT_AXES"] = "1"
run = runner(exe)
w = lambda name: os.path.join(work, name)  # noqa: E731


def figure(png, **kw):
    for f in check_figure(png, **kw):
        check(False, f)


# atten: a line chart with a log axis.
run("atten", "--freq-hz", "1e9:200e9:40", "--rain-mmh", "10", "--out", w("atten.csv"),
    "--plot", w("atten.png"), "-q")
figure(w("atten.png"), size=(1000, 640), colour_bars=0)

# ambiguity: the map (one colour bar, |chi| in dB) and its cuts against the closed form.
run("ambiguity", "--out", w("amb"), "-q")
figure(w("amb/ambiguity.png"), size=(1000, 640), colour_bars=1, texts=["|chi| [dB]"])
figure(w("amb/cuts.png"), colour_bars=0, texts=["delay, closed"])

# sigma0: a cut against incidence, and a bistatic map per polarisation (two colour bars).
run("sigma0", "--material", "asphalt", "--freq-hz", "94e9", "--theta-deg", "0:88:23",
    "--out", w("s.csv"), "--plot", w("s.png"), "-q")
figure(w("s.png"), size=(1000, 640), colour_bars=0, texts=["sigma0 [dB]"])
run("sigma0", "--eps-r", "5,0.09", "--rms-height-m", "0.0005", "--corr-length-m", "0.005",
    "--freq-hz", "94e9", "--model", "iem", "--theta-s-deg", "0:88:12", "--phi-s-deg", "0",
    "--theta-deg", "10:70:7", "--pol", "VV,HH", "--out", w("bm.csv"), "--plot", w("bm.png"), "-q")
figure(w("bm.png"), size=(1000, 2 * 560), colour_bars=2, texts=["sigma0 [dB]"])

# rcs of a trihedral: a theta cut, a phi cut over a turn (Cartesian and polar), a map.
run("scene", "target", "trihedral-tri", "--a-m", "0.3", "--out", w("tri.stl"))
run("rcs", "--mesh", w("tri.stl"), "--freq-hz", "10e9", "--theta-deg", "0:90:31", "--phi-deg",
    "45", "--pol", "HH,VV", "--out", w("cut.csv"), "--plot", w("cut.png"), "-q")
figure(w("cut.png"), size=(1000, 640), colour_bars=0, texts=["theta [deg]", "RCS [dBsm]"])
run("rcs", "--mesh", w("tri.stl"), "--freq-hz", "10e9", "--theta-deg", "60", "--phi-deg",
    "0:360:73", "--pol", "VV", "--out", w("turn.csv"), "--plot", w("turn.png"), "-q")
figure(w("turn.png"), size=(1500, 700), colour_bars=0, texts=["phi [deg]", "RCS [dBsm]"])
with open(w("turn.axes.json")) as f:
    turn = json.load(f)
check(len(turn["panels"]) == 2, "the turn: a Cartesian and a polar panel")
run("rcs", "--mesh", w("tri.stl"), "--freq-sweep-hz", "8e9:12e9:5", "--theta-deg", "0:90:19",
    "--phi-deg", "45", "--pol", "HH,VV", "--out", w("map.csv"), "--plot", w("map.png"), "-q")
figure(w("map.png"), size=(1000, 2 * 560), colour_bars=2, texts=["RCS [dBsm]"])

# The map's colours back through viridis, HH panel, at every cell centre.
with open(w("map.axes.json")) as f:
    ax = json.load(f)["panels"][0]
img = matplotlib.image.imread(w("map.png"))[:, :, :3]
lut = matplotlib.colormaps["viridis"](np.linspace(0, 1, 256))[:, :3]
with open(w("map.csv"), newline="") as f:
    rows = list(csv.DictReader(f))
lo, hi = ax["value_lo"], ax["value_hi"]
worst, n = 0.0, 0
for r in rows:
    theta, ghz, v = float(r["theta_deg"]), float(r["freq_hz"]) / 1e9, float(r["rcs_HH_dbsm"])
    if not lo + 1 < v < hi - 1:
        continue  # clipped to the scale's ends
    (x0, x1), (y0, y1) = ax["xlim"], ax["ylim"]
    px = ax["x0"] + (theta - x0) / (x1 - x0) * (ax["x1"] - ax["x0"])
    py = ax["y1"] - (ghz - y0) / (y1 - y0) * (ax["y1"] - ax["y0"])
    c = img[int(py), int(px)]
    k = int(np.argmin(((lut - c) ** 2).sum(axis=1)))
    got = lo + (hi - lo) * k / 255
    worst = max(worst, abs(got - v))
    n += 1
check(n >= 40, f"{n} map cells inside the colour scale")
check(worst < 0.6, f"map colours read back through viridis within 0.6 dB (worst {worst:.2f} dB)")
print(f"map: {n} cells read back through the colour map, worst {worst:.2f} dB")

# profile and ISAR: a line and an image in metres (equal scales, scale bar).
run("profile", "--mesh", w("tri.stl"), "--freq-sweep-hz", "9e9:11e9:64", "--theta-deg",
    "54.7356", "--phi-deg", "40:50:16", "--out", w("profile.csv"), "--plot", w("profile.png"),
    "--isar-plot", w("isar.png"), "-q")
figure(w("profile.png"), size=(1000, 640), colour_bars=0, texts=["|profile| [dBsm]"])
figure(w("isar.png"), colour_bars=1,
       texts=["range [m]", "cross-range [m]", "image amplitude [dBsm]"])

# A run's pictures (the run_default fixture): the B-scope coloured by time (a colour bar in s),
# and the stage times with the frame period and the governor's deadline.
figure(os.path.join(run_dir, "detections.png"), size=(1000, 760), colour_bars=1,
       texts=["azimuth [deg], right of boresight", "range [km]", "time from the first frame [s]"])
figure(os.path.join(run_dir, "timing.png"), size=(1000, 1280), colour_bars=0,
       texts=["time [ms]", "frame period (budget)", "governor deadline (trace + sensor)",
              "trace", "sensor"])
finish()
