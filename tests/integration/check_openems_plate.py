#!/usr/bin/python3
"""radar-emu rcs with and without edge diffraction against a full-wave (FDTD) reference computed
here with openEMS: a PEC zero-thickness square plate, 100 mm a side, monostatic, theta = 0..85 deg
from the normal in 2.5-deg steps in a principal plane, HH and VV, at 9, 10 and 12 GHz (3.0,
3.33 and 4.0 wavelengths). The table and how it was made (scripts/openems_rcs.py, its check
against the Mie series): tests/data/openems_plate/README.md. This test reads only the
checked-in table.

The issue's figure (median |difference| <= 2 dB over 0-85 deg, both polarisations, PO + edges,
reached everywhere with the default edge order 2) is asserted where it is reached; where it is not, the figure reached is asserted (a regression
guard) and the gap printed as NOT REACHED (docs/validation.md, "Against a full-wave reference
computed here (openEMS): square plate").
Usage: check_openems_plate.py RADAR_EMU WORK_DIR [--charts DIR]  (--charts: also write the
docs charts openems_plate_10ghz_{hh,vv}.png into DIR)"""
import csv
import math
import os
import statistics
import sys

from cli_check import check, finish, runner, write_series

exe, work = sys.argv[1], sys.argv[2]
charts = sys.argv[4] if len(sys.argv) > 4 and sys.argv[3] == "--charts" else None
os.makedirs(work, exist_ok=True)
data = os.path.join(os.environ.get("RADAR_EMU_SOURCE_DIR",
                                   os.path.join(os.path.dirname(__file__), "..", "..")),
                    "tests", "data", "openems_plate")
run = runner(exe)
SIDE_M, C0 = 0.1, 299792458.0


def load_ref():
    """{(freq_hz, pol): {theta_deg: dBsm}} from openems_plate.csv."""
    out = {}
    with open(os.path.join(data, "openems_plate.csv"), newline="") as f:
        for r in csv.DictReader(f):
            check(float(r["phi_deg"]) == 0.0, "reference: phi = 0 cut")
            key = (float(r["freq_hz"]), r["pol"])
            out.setdefault(key, {})[round(float(r["theta_deg"]), 3)] = float(r["rcs_dbsm"])
    return out


def load_csv(path, pol):
    with open(path, newline="") as f:
        rows = list(csv.DictReader(f))
    return {round(float(r["theta_deg"]), 3): float(r[f"rcs_{pol}_dbsm"]) for r in rows}, rows


# The plate of scripts/openems_rcs.py: in the x-y plane, edges along x and y, centred on 0.
plate = os.path.join(work, "plate.obj")
h = SIDE_M / 2
with open(plate, "w") as f:
    f.write(f"v {-h} {-h} 0\nv {h} {-h} 0\nv {h} {h} 0\nv {-h} {h} 0\nf 1 2 3\nf 1 3 4\n")


def sweep(freq, thetas, out, *extra):
    run("rcs", "--mesh", plate, "--freq-hz", str(freq), "--theta-deg", thetas, "--phi-deg", "0",
        "--pol", "HH,VV", "--bounces", "1", "--out", out, "-q", *extra)


report = []


def figure(name, value, target, reached_bound):
    ok = value <= target
    tag = "reached" if ok else f"NOT REACHED (issue figure {target:g})"
    report.append(f"{name}: {value:.2f} dB  [{tag}]")
    print(report[-1])
    check(value <= (target if ok else reached_bound), f"{name}: {value:.3f} dB")


ref = load_ref()
freqs = sorted({k[0] for k in ref})
check(freqs == [9e9, 10e9, 12e9], f"reference frequencies {freqs}")
# The 2 dB is reached at every frequency and both polarisations with the default edge
# order 2. First-order edge currents alone (--edge-order 1, printed beside) give HH = VV in a
# principal plane (the half-plane's backscatter coefficients f and g swap between the leading and
# trailing edge) and miss VV (E in the plane of incidence: hard for the leading and trailing
# edges) by 2.1-2.9 dB: its travelling-wave lobe near 65 deg and its fall toward grazing are the
# double diffraction across the plate (radar/em/edges.hpp).
for freq in freqs:
    on = os.path.join(work, f"plate_{freq / 1e9:g}ghz.csv")
    off = os.path.join(work, f"plate_{freq / 1e9:g}ghz_po.csv")
    sweep(freq, "0:85:35", on)
    sweep(freq, "0:85:35", off, "--no-edges")
    first = os.path.join(work, f"plate_{freq / 1e9:g}ghz_first.csv")
    sweep(freq, "0:85:35", first, "--edge-order", "1")
    # Independent of radar-emu: the reference itself at normal incidence against the PO closed
    # form 4 pi A^2 / lambda^2 (exact for a large plate; edge effects are ~0.1-0.3 dB at 3-4
    # wavelengths).
    closed = 10 * math.log10(4 * math.pi * SIDE_M ** 4 * (freq / C0) ** 2)
    for pol in ("HH", "VV"):
        r = ref[(freq, pol)]
        check(sorted(r) == [2.5 * i for i in range(35)], f"{freq:g} {pol}: theta 0..85 step 2.5")
        check(abs(r[0.0] - closed) < 0.3,
              f"reference at normal {r[0.0]:.2f} dBsm vs closed form {closed:.2f}")
        got, rows = load_csv(on, pol)
        po, _ = load_csv(off, pol)
        check(rows[0]["edges"] == "1" and int(rows[0]["edges_used"]) == 4,
              "plate: edges on, its 4 rim edges used")
        one, _ = load_csv(first, pol)
        d_on = [abs(got[a] - r[a]) for a in r]
        d_po = [abs(po[a] - r[a]) for a in r]
        med, med_po = statistics.median(d_on), statistics.median(d_po)
        med_one = statistics.median(abs(one[a] - r[a]) for a in r)
        worst = max(r, key=lambda a: abs(got[a] - r[a]))
        print(f"plate {freq / 1e9:g} GHz {pol}: normal: reference {r[0.0]:.2f} dBsm (closed form "
              f"{closed:.2f}), PO + edges {got[0.0] - r[0.0]:+.2f} dB; median |diff| 0-85 deg "
              f"PO {med_po:.2f} dB, first-order edges {med_one:.2f} dB, PO + edges {med:.2f} dB; "
              f"0-60 deg PO + edges "
              f"{statistics.median(abs(got[a] - r[a]) for a in r if a <= 60):.2f} dB; max "
              f"|diff| PO + edges {max(d_on):.1f} dB at {worst:g} deg")
        figure(f"plate {freq / 1e9:g} GHz {pol} median |diff| 0-85 deg (PO + edges)", med, 2.0,
               2.0)
        check(med < med_po, f"plate {freq / 1e9:g} GHz {pol}: edges improve on PO")
        if pol == "VV":  # double diffraction parts HH from VV (first order keeps them equal)
            other, _ = load_csv(on, "HH")
            first_hh, _ = load_csv(first, "HH")
            check(max(abs(first_hh[a] - one[a]) for a in one) < 0.01,
                  "first-order edges: HH = VV in the principal plane")
            print(f"  PO + edges: max |HH - VV| {max(abs(other[a] - got[a]) for a in got):.2g} dB; "
                  f"reference: {max(abs(ref[(freq, 'HH')][a] - r[a]) for a in r):.1f} dB")

if charts:
    # PO + edges from the run, PO alone and the openEMS points as overlays (one chart per pol).
    freq = 10e9
    fine_po = os.path.join(work, "chart_po.csv")
    sweep(freq, "0:85:171", fine_po, "--no-edges")
    fine_first = os.path.join(work, "chart_first.csv")
    sweep(freq, "0:85:171", fine_first, "--edge-order", "1")
    for pol in ("HH", "VV"):
        po, _ = load_csv(fine_po, pol)
        one, _ = load_csv(fine_first, pol)
        po_txt, ref_txt = os.path.join(work, f"po_{pol}.txt"), os.path.join(work, f"ref_{pol}.txt")
        one_txt = os.path.join(work, f"first_{pol}.txt")
        write_series(po_txt, po)
        write_series(one_txt, one)
        write_series(ref_txt, ref[(freq, pol)])
        run("rcs", "--mesh", plate, "--freq-hz", str(freq), "--theta-deg", "0:85:171",
            "--phi-deg", "0", "--pol", pol, "--bounces", "1", "-q",
            "--out", os.path.join(work, f"chart_{pol}.csv"),
            "--plot", os.path.join(charts, f"openems_plate_10ghz_{pol.lower()}.png"),
            "--overlay", f"{one_txt}=first-order edges", "--overlay", f"{po_txt}=PO alone",
            "--overlay", f"{ref_txt}=openEMS")

print("\nsummary:\n  " + "\n  ".join(report))
finish()
