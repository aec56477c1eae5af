#!/usr/bin/python3
"""RCS sweep of the builtin vehicle from Python: the same engine and units as `radar-emu rcs`.

Writes the vehicle mesh (as `radar-emu scene target vehicle`), sweeps the azimuth around it at
10 GHz in the horizontal plane (theta = 90 deg), and prints the HH and VV RCS per angle, with
an ASCII bar; with matplotlib installed and --plot FILE, a PNG too.
Usage: rcs_sweep.py [--plot FILE] [--points N]"""
import argparse
import os
import tempfile

import numpy as np

import radar_emu

parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
parser.add_argument("--plot", help="PNG of the sweep (needs matplotlib)")
parser.add_argument("--points", type=int, default=19, help="azimuth points over 0-180 deg")
args = parser.parse_args()

with tempfile.TemporaryDirectory() as tmp:
    mesh = os.path.join(tmp, "vehicle.obj")
    triangles = radar_emu.write_target("vehicle", mesh, a_m=7.0, b_m=3.5, c_m=2.5)
    target = radar_emu.Target(mesh, bounces=3)
    print(f"vehicle: {triangles} triangles, bounding radius {target.bounding_radius_m:.2f} m")
    rows = target.rcs(10e9, theta_deg=90.0, phi_deg=f"0:180:{args.points}", pol="HH,VV")

print(f"{'phi_deg':>8} {'HH dBsm':>9} {'VV dBsm':>9}")
for r in rows:
    bar = "#" * max(0, int(round((r["rcs_VV_dbsm"] + 10) / 2)))
    print(f"{r['phi_deg']:8.1f} {r['rcs_HH_dbsm']:9.2f} {r['rcs_VV_dbsm']:9.2f}  {bar}")
# The median over aspect: the figure a detection budget would use for this target.
power = 10 ** (rows["rcs_VV_dbsm"] / 10)
print(f"median VV RCS over aspect: {10 * np.log10(np.median(power)):.1f} dBsm")

if args.plot:
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    plt.plot(rows["phi_deg"], rows["rcs_HH_dbsm"], label="HH")
    plt.plot(rows["phi_deg"], rows["rcs_VV_dbsm"], label="VV")
    plt.xlabel("azimuth phi [deg]")
    plt.ylabel("RCS [dBsm]")
    plt.legend()
    plt.savefig(args.plot)
    print(f"wrote {args.plot}")
