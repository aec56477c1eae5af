#!/usr/bin/python3
"""radar-emu rcs / profile end to end through the real binary, checked in Python against the
closed forms of physics.md (computed here, independently of the C++ code):
  - a 0.5 m x 0.3 m plate written in millimetres and read with --scale 0.001: the PO pattern
    sigma = 4 pi (ab)^2 / lambda^2 cos^2(theta) sinc^2(k a sin theta) at 10 GHz, both
    polarisations, the CSV's complex amplitude consistent with its dBsm column, the plot a PNG;
  - fluctuation statistics written for a window;
  - a range profile of a triangular trihedral peaks at its apex (range 0) with resolution c/2B;
  - forward scatter of a box (receiver straight behind it): 4 pi A_shadow^2 / lambda^2, and the
    CSV's per-direction lighting and bounce-cap columns; --bounces above 16 (up to 64);
  - the small-ka warning, and a degenerate triangle reported with file, triangle and line.
The closed forms are those of PO alone: those runs pass --no-edges (edge diffraction is checked
in tests/radar/edges_test.cpp and against the Austin benchmarks, check_austin_rcs.py).
Usage: check_rcs_cli.py RADAR_EMU WORK_DIR"""
import csv
import math
import os
import subprocess
import sys

from cli_check import check, finish, runner

exe, work = sys.argv[1], sys.argv[2]
os.makedirs(work, exist_ok=True)
C = 299792458.0
run = runner(exe)


plate = os.path.join(work, "plate_mm.obj")
run("scene", "target", "plate", "--a-m", "500", "--b-m", "300", "--out", plate)
out = os.path.join(work, "plate.csv")
png = os.path.join(work, "plate.png")
run("rcs", "--mesh", plate, "--no-edges", "--scale", "0.001", "--freq-hz", "10e9", "--theta-deg", "0:20:41",
    "--pol", "HH,VV,HV", "--bounces", "1", "--out", out, "--plot", png, "--window-deg", "4", "-q")
with open(out, newline="") as f:
    rows = list(csv.DictReader(f))
check(len(rows) == 41, f"41 rows expected, got {len(rows)}")
check(list(rows[0].keys())[:3] == ["freq_hz", "theta_deg", "phi_deg"], "CSV columns")
for p in ("HH", "VV", "HV"):
    check(f"rcs_{p}_dbsm" in rows[0] and f"re_{p}" in rows[0] and f"im_{p}" in rows[0],
          f"columns for {p}")
lam = C / 10e9
k = 2 * math.pi / lam
a, b = 0.5, 0.3
worst = 0.0
for r in rows:
    th = math.radians(float(r["theta_deg"]))
    x = k * a * math.sin(th)
    sinc = 1.0 if x == 0 else math.sin(x) / x
    expected = 4 * math.pi * (a * b) ** 2 / lam ** 2 * math.cos(th) ** 2 * sinc ** 2
    if expected < 1e-5 * 4 * math.pi * (a * b) ** 2 / lam ** 2:
        continue
    for p in ("HH", "VV"):
        got = float(r[f"rcs_{p}_dbsm"])
        worst = max(worst, abs(got - 10 * math.log10(expected)))
        amp2 = float(r[f"re_{p}"]) ** 2 + float(r[f"im_{p}"]) ** 2
        check(abs(10 * math.log10(amp2) - got) < 1e-4, f"{p} amplitude vs dBsm at {th}")
    check(float(r["rcs_HV_dbsm"]) < float(r["rcs_VV_dbsm"]) - 100, "plate has no cross-pol")
print(f"plate pattern via CLI: worst deviation {worst:.2e} dB")
check(worst < 0.2, f"plate pattern within 0.2 dB (worst {worst})")
with open(png, "rb") as f:
    check(f.read(8) == b"\x89PNG\r\n\x1a\n", "plot is a PNG")
# Two swept dimensions (theta and frequency): a map per polarisation, panels 560 pixels high one
# under the other (docs/plotting.md); the PNG's size from its IHDR chunk.
map_png = os.path.join(work, "plate_map.png")
run("rcs", "--mesh", plate, "--no-edges", "--scale", "0.001", "--freq-sweep-hz", "9e9:11e9:5",
    "--theta-deg", "0:20:11", "--pol", "HH,VV", "--bounces", "1", "--out",
    os.path.join(work, "plate_map.csv"), "--plot", map_png, "-q")
with open(map_png, "rb") as f:
    head = f.read(24)
check(head[:8] == b"\x89PNG\r\n\x1a\n" and head[12:16] == b"IHDR", "map is a PNG")
mw, mh = int.from_bytes(head[16:20], "big"), int.from_bytes(head[20:24], "big")
check((mw, mh) == (1000, 2 * 560), f"two map panels of 1000 x 560, got {mw} x {mh}")
stats = os.path.join(work, "plate_stats.csv")
check(os.path.exists(stats), "fluctuation statistics written next to the CSV")
with open(stats, newline="") as f:
    srows = list(csv.DictReader(f))
check(len(srows) == 41 and "median_VV_dbsm" in srows[0], "statistics rows and columns")
for r in srows:  # the median of a window lies between its 10th and 90th percentiles
    check(float(r["p10_VV_dbsm"]) <= float(r["median_VV_dbsm"]) + 1e-9 <= float(r["p90_VV_dbsm"]) + 2e-9,
          "p10 <= median <= p90")

tri = os.path.join(work, "tri.stl")
run("scene", "target", "trihedral-tri", "--a-m", "0.2", "--out", tri)
prof = os.path.join(work, "profile.csv")
r = run("profile", "--mesh", tri, "--no-edges", "--freq-sweep-hz", "8e9:12e9:201", "--theta-deg", "54.7356103",
        "--phi-deg", "45", "--out", prof, "--plot", os.path.join(work, "profile.png"))
with open(prof, newline="") as f:
    prow = list(csv.DictReader(f))
peak = max(prow, key=lambda row: float(row["amplitude_dbsm"]))
bandwidth = 201 * (4e9 / 200)
resolution = C / (2 * bandwidth)
bin_m = float(prow[1]["range_m"]) - float(prow[0]["range_m"])
print(f"trihedral profile peak at {float(peak['range_m']):.4f} m, bin {bin_m:.4f} m")
check(abs(float(peak["range_m"])) <= bin_m + 1e-9, "trihedral peak at its apex (+-1 bin)")
check(f"{resolution:.4g}" in r.stdout, f"resolution c/2B = {resolution:.4g} m printed")

# Forward scatter: a 0.2 x 0.15 x 0.1 m PEC box lit from +z (theta 0), the receiver straight
# behind it (theta 180): physical optics gives sigma = 4 pi A^2 / lambda^2 with A the shadow
# (0.2 x 0.15 = 0.03 m^2): 11.0 dBsm at 10 GHz (Knott, Shaeffer & Tuley, Radar Cross Section,
# 2004, sec. 5).
box = os.path.join(work, "box.stl")
run("scene", "target", "box", "--a-m", "0.2", "--b-m", "0.15", "--c-m", "0.1", "--out", box)
fwd = os.path.join(work, "forward.csv")
r = run("rcs", "--mesh", box, "--no-edges", "--freq-hz", "10e9", "--theta-deg", "0", "--phi-deg", "0",
        "--bistatic-theta-deg", "180", "--bistatic-phi-deg", "0", "--pol", "HH,VV", "--bounces",
        "40", "--out", fwd)
with open(fwd, newline="") as f:
    frow = list(csv.DictReader(f))
check(len(frow) == 1, "one forward-scatter row")
shadow = 0.2 * 0.15
expected = 10 * math.log10(4 * math.pi * shadow ** 2 / lam ** 2)
for p in ("HH", "VV"):
    got = float(frow[0][f"rcs_{p}_dbsm"])
    print(f"box forward scatter {p}: {got:.4f} dBsm, 4 pi A^2 / lambda^2 = {expected:.4f} dBsm")
    check(abs(got - expected) < 0.1, f"forward scatter {p} within 0.1 dB ({got} vs {expected})")
check(int(frow[0]["facets_lit"]) == 2 and int(frow[0]["facets_partial"]) == 0,
      "the lit face's two triangles, wholly lit: " + str(frow[0]))
check(int(frow[0]["tubes_cut_off"]) == 0, "a convex box keeps no tube bouncing")
check("tubes cut off at the bounce cap (40)" in r.stdout, "summary names the cap: " + r.stdout)
r = subprocess.run([exe, "rcs", "--mesh", box, "--freq-hz", "10e9", "--bounces", "65", "--out",
                    fwd], capture_output=True, text=True)
check(r.returncode != 0 and "65" in r.stderr, "--bounces 65 is refused: " + r.stderr)

# Electrically small target (sphere ka = 2.1 at 10 GHz): the CLI warns that PO fails there.
sphere = os.path.join(work, "sphere.obj")
run("scene", "target", "sphere", "--a-m", "0.01", "--facet-m", "0.001", "--out", sphere)
r = run("rcs", "--mesh", sphere, "--freq-hz", "10e9", "--out", os.path.join(work, "s.csv"))
check("ka = 2.1" in r.stderr and "physical optics" in r.stderr and "--method mom" in r.stderr,
      "small-ka warning: " + r.stderr)
# The method of moments on the same kind of sphere (radar-emu's own latitude-longitude mesh,
# welded and solved by the EFIE) against the Mie series: -33.48 dBsm for a = 10 mm at 10 GHz
# (ka = 2.0958; computed once with scipy.special's spherical Bessel functions, independent of
# radar/reference/mie.cpp). Measured -33.67 dBsm on 960 triangles of about lambda / 15.
small = os.path.join(work, "sphere_mom.obj")
run("scene", "target", "sphere", "--a-m", "0.01", "--facet-m", "0.002", "--out", small)
mom_csv = os.path.join(work, "sphere_mom.csv")
r = run("rcs", "--mesh", small, "--freq-hz", "10e9", "--theta-deg", "30", "--phi-deg", "20",
        "--method", "mom", "--out", mom_csv)
with open(mom_csv, newline="") as f:
    row = list(csv.DictReader(f))[0]
check(abs(float(row["rcs_VV_dbsm"]) + 33.48) < 0.3 and abs(float(row["rcs_HH_dbsm"]) + 33.48) < 0.3,
      f"MoM sphere {row['rcs_VV_dbsm']} / {row['rcs_HH_dbsm']} dBsm vs Mie -33.48")
check("1440 unknowns" in r.stdout and "EFIE" in r.stdout, "MoM summary: " + r.stdout)
# Settings of the other method are refused, and so are what the MoM cannot model.
for args, expect in (
        (["--method", "mom", "--bounces", "2"], "--bounces: a setting of --method po"),
        (["--method", "mom", "--no-edges"], "--no-edges: a setting of --method po"),
        (["--mom-equation", "cfie"], "--mom-equation: used with --method mom only"),
        (["--method", "mom", "--mom-max-unknowns", "1000"], "exceed the limit of 1000"),
        (["--method", "mom", "--material", "metal=4,0.1"], "models PEC surfaces only")):
    r = subprocess.run([exe, "rcs", "--mesh", small, "--freq-hz", "10e9", "--out",
                        os.path.join(work, "refused.csv"), *args], capture_output=True, text=True)
    check(r.returncode != 0 and expect in r.stderr, f"{args} refused: {r.stderr}")
# A degenerate triangle in an OBJ is reported with the file, triangle and line.
bad = os.path.join(work, "degenerate.obj")
with open(bad, "w") as f:
    f.write("v 0 0 0\nv 1 0 0\nv 0 1 0\nv 2 0 0\nf 1 2 3\nf 1 2 4\n")
r = run("rcs", "--mesh", bad, "--freq-hz", "10e9", "--out", os.path.join(work, "d.csv"))
check(f"{bad}: triangle 1 (line 6) is degenerate" in r.stderr, "degenerate report: " + r.stderr)

finish()
print("rcs/profile CLI: ok")
