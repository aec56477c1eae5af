#!/usr/bin/python3
"""radar-emu rcs with and without edge diffraction against the Austin RCS Benchmark Suite
(tests/data/austin/README.md: integral-equation reference solutions, licence beside them):
  - IIA: zero-thickness PEC plate 6 in x 10.5 in in the y-z plane, backscatter phi cut at
    theta = 90 deg (phi = 0 normal incidence, 90 grazing along the 10.5 in side), HH and VV, at
    2.56, 5.12, 7 and 10.2 GHz: |difference| at normal incidence and the median |difference|
    over phi = 0..70 deg;
  - IIIA: the PEC NASA almond (length 9.936 in, generated here from its analytic definition,
    Woo et al., IEEE APS Magazine 35(1), 1993), phi cut 0..180 deg at 7 and 10.25 GHz: the median
    |difference| over the directions where the reference is within 20 dB of its peak, and the
    nose-on (phi = 0) HH difference;
  - the method of moments (rcs --method mom, radar/em/mom.hpp) on the almond and on the plate
    at 2.56 and 7 GHz, meshed here at a tenth of a wavelength (an eighth for the almond at
    10.25 GHz, which keeps its matrix to 1.4 GB).
The issue's acceptance figures (plates: 0.2 dB at normal, median <= 2 dB to 70 deg, reached by PO
+ edges with the default edge order 2; almond: median <= 1.0 dB at 10.25 GHz and <= 1.5 dB at
7 GHz, nose-on HH within 3 dB, reached by the method of moments) are asserted. PO + edges on the
almond does not reach them (its nose-on return is travelling and creeping waves, which neither PO
nor wedge edges carry): its figures are printed as NOT REACHED and asserted as regression bounds
(docs/validation.md, "Edge diffraction" and "Method of moments").
Usage: check_austin_rcs.py RADAR_EMU WORK_DIR [--charts DIR]  (--charts: also write the docs
charts austin_plate_{2_56,7}ghz_*.png and austin_almond_{7,10_25}ghz_*.png into DIR)"""
import csv
import math
import os
import statistics
import sys
import time

from cli_check import check, finish, runner, write_series

exe, work = sys.argv[1], sys.argv[2]
charts = sys.argv[4] if len(sys.argv) > 4 and sys.argv[3] == "--charts" else None
os.makedirs(work, exist_ok=True)
data = os.path.join(os.environ.get("RADAR_EMU_SOURCE_DIR",
                                   os.path.join(os.path.dirname(__file__), "..", "..")),
                    "tests", "data", "austin")
run = runner(exe)
INCH = 0.0254


def load_ref(name):
    out = {}
    with open(os.path.join(data, name)) as f:
        for line in f:
            x = line.split()
            if len(x) >= 4:
                out[round(float(x[2]), 3)] = float(x[3])
    return out


def load_csv(path, pol):
    with open(path, newline="") as f:
        rows = list(csv.DictReader(f))
    return {round(float(r["phi_deg"]), 3): float(r[f"rcs_{pol}_dbsm"]) for r in rows}, rows


def write_plate(path):
    # W = 6 in along z, 7W/4 = 10.5 in along y, in the plane x = 0 (two triangles).
    hy, hz = 10.5 * INCH / 2, 6.0 * INCH / 2
    with open(path, "w") as f:
        f.write(f"v 0 {-hy} {-hz}\nv 0 {hy} {-hz}\nv 0 {hy} {hz}\nv 0 {-hy} {hz}\n")
        f.write("f 1 2 3\nf 1 3 4\n")


def write_obj(path, verts, faces):
    """Writes vertices and 1-based triangles as OBJ; returns the triangle count."""
    with open(path, "w") as f:
        for v in verts:
            f.write("v %.9g %.9g %.9g\n" % v)
        for t in faces:
            f.write("f %d %d %d\n" % t)
    return len(faces)


def almond_radii(t, d):
    """The NASA almond (Woo et al. 1993), t = x / d: for -0.416667 < t < 0
    y = 0.193333 d sqrt(1 - (t/0.416667)^2) cos psi, z = 0.064444 d sqrt(...) sin psi; for
    0 < t < 0.583333 y = 4.83345 d (sqrt(1 - (t/2.08335)^2) - 0.96) cos psi,
    z = 1.61115 d (sqrt(...) - 0.96) sin psi. Returns the semi-axes (y, z) at t."""
    if t < 0:
        r = math.sqrt(max(0.0, 1 - (t / 0.416667) ** 2))
        return 0.193333 * d * r, 0.064444 * d * r
    r = max(0.0, math.sqrt(max(0.0, 1 - (t / 2.08335) ** 2)) - 0.96)
    return 4.83345 * d * r, 1.61115 * d * r


def write_almond(path, d=9.936 * INCH, nt=120, npsi=96):
    """The almond of almond_radii, tip toward +x; rings cosine-spaced in t."""
    def radii(t):
        return almond_radii(t, d)
    t0, t1 = -0.416667, 0.583333
    ts = [t0 + (t1 - t0) * (1 - math.cos(math.pi * i / nt)) / 2 for i in range(nt + 1)]
    verts, rings = [(t0 * d, 0.0, 0.0)], []
    for t in ts[1:-1]:
        a, b = radii(t)
        ring = []
        for j in range(npsi):
            p = 2 * math.pi * j / npsi
            verts.append((t * d, a * math.cos(p), b * math.sin(p)))
            ring.append(len(verts))
        rings.append(ring)
    verts.append((t1 * d, 0.0, 0.0))
    tip = len(verts)
    faces = [(1, rings[0][(j + 1) % npsi], rings[0][j]) for j in range(npsi)]
    for ra, rb in zip(rings, rings[1:]):
        for j in range(npsi):
            a0, a1, b0, b1 = ra[j], ra[(j + 1) % npsi], rb[j], rb[(j + 1) % npsi]
            faces += [(a0, a1, b1), (a0, b1, b0)]
    faces += [(tip, rings[-1][j], rings[-1][(j + 1) % npsi]) for j in range(npsi)]
    return write_obj(path, verts, faces)


def write_plate_grid(path, h):
    """The IIA plate meshed for the method of moments: squares of side <= h, each cut in two."""
    ny, nz = math.ceil(10.5 * INCH / h), math.ceil(6.0 * INCH / h)
    with open(path, "w") as f:
        for j in range(nz + 1):
            for i in range(ny + 1):
                f.write(f"v 0 {10.5 * INCH * (i / ny - 0.5):.9g} {6.0 * INCH * (j / nz - 0.5):.9g}\n")
        for j in range(nz):
            for i in range(ny):
                a = j * (ny + 1) + i + 1
                f.write(f"f {a} {a + 1} {a + ny + 2}\nf {a} {a + ny + 2} {a + ny + 1}\n")
    return 2 * ny * nz


def write_almond_uniform(path, h, d=9.936 * INCH):
    """The almond of write_almond meshed for the method of moments: near-equilateral triangles of
    side about h. Rings at equal arc length along the rim's profile (the widest, so the longest
    surface path), each ring's points at equal arc length around its ellipse, neighbouring rings
    stitched by advancing along whichever ring is behind, fans to the back point and the tip."""
    t0, t1 = -0.416667, 0.583333

    def radii(t):
        return almond_radii(t, d)

    # The rim profile (x, a): the elliptic back by its angle, the front by x.
    prof = [(t0 * d * math.cos(th), 0.193333 * d * math.sin(th))
            for th in (k * (math.pi / 2) / 4000 for k in range(4001))]
    prof += [(t * d, radii(t)[0]) for t in (t1 * i / 16000 for i in range(1, 16001))]
    arc = [0.0]
    for (x0, a0), (x1, a1) in zip(prof, prof[1:]):
        arc.append(arc[-1] + math.hypot(x1 - x0, a1 - a0))
    nr = max(4, round(arc[-1] / h))
    verts, rings, j = [(t0 * d, 0.0, 0.0)], [], 0
    for i in range(1, nr):
        target = arc[-1] * i / nr
        while arc[j + 1] < target:
            j += 1
        x = prof[j][0] + (target - arc[j]) / (arc[j + 1] - arc[j]) * (prof[j + 1][0] - prof[j][0])
        a, b = radii(x / d)
        psi = [2 * math.pi * k / 2000 for k in range(2001)]
        around = [0.0]
        for p0, p1 in zip(psi, psi[1:]):
            around.append(around[-1] + math.hypot(a * (math.cos(p1) - math.cos(p0)),
                                                  b * (math.sin(p1) - math.sin(p0))))
        n = max(6, round(around[-1] / h))
        ring, k = [], 0
        for m in range(n):
            target_m = around[-1] * m / n
            while around[k + 1] < target_m:
                k += 1
            p = psi[k] + (target_m - around[k]) / (around[k + 1] - around[k]) * (psi[k + 1] - psi[k])
            verts.append((x, a * math.cos(p), b * math.sin(p)))
            ring.append(len(verts))
        rings.append(ring)
    verts.append((t1 * d, 0.0, 0.0))
    faces = [(1, rings[0][(m + 1) % len(rings[0])], rings[0][m]) for m in range(len(rings[0]))]
    for ra, rb in zip(rings, rings[1:]):
        i = k = 0
        while i < len(ra) or k < len(rb):
            if k >= len(rb) or (i < len(ra) and (i + 1) / len(ra) <= (k + 1) / len(rb)):
                faces.append((ra[i % len(ra)], ra[(i + 1) % len(ra)], rb[k % len(rb)]))
                i += 1
            else:
                faces.append((ra[i % len(ra)], rb[(k + 1) % len(rb)], rb[k % len(rb)]))
                k += 1
    last = rings[-1]
    faces += [(len(verts), last[m], last[(m + 1) % len(last)]) for m in range(len(last))]
    return write_obj(path, verts, faces)


def sweep(mesh, freq, phis, out, *extra):
    run("rcs", "--mesh", mesh, "--freq-hz", str(freq), "--theta-deg", "90", "--phi-deg", phis,
        "--pol", "HH,VV", "--bounces", "1", "--out", out, "-q", *extra)


report = []


def figure(name, value, target, reached_bound):
    """Asserts value <= target when reached, else value <= reached_bound (a regression guard)
    and reports the gap."""
    ok = value <= target
    tag = "reached" if ok else f"NOT REACHED (issue figure {target:g})"
    report.append(f"{name}: {value:.2f} dB  [{tag}]")
    print(report[-1])
    check(value <= (target if ok else reached_bound), f"{name}: {value:.3f} dB")


# --- IIA plates. ------------------------------------------------------------------------------
plate = os.path.join(work, "plate.obj")
write_plate(plate)
# Every plate figure is reached with the default edge order 2 (first-order edge currents plus the
# hard polarisation's double diffraction across the plate, radar/em/edges.hpp). First order alone
# (--edge-order 1) leaves HH at 2.56 GHz (1.3 x 2.3 wavelengths) at a median 2.9 dB and gives
# HH = VV in this principal plane; its figures are printed beside and its two properties asserted.
chart_name = {"f9": "2_56", "fx1": "7"}
for tag, freq in (("f9", 2.56e9), ("f10", 5.12e9), ("fx1", 7e9), ("f11", 10.2e9)):
    on, off = os.path.join(work, f"plate_{tag}.csv"), os.path.join(work, f"plate_{tag}_po.csv")
    first = os.path.join(work, f"plate_{tag}_first.csv")
    sweep(plate, freq, "0:90:181", on)
    sweep(plate, freq, "0:90:181", off, "--no-edges")
    sweep(plate, freq, "0:90:181", first, "--edge-order", "1")
    first_hh, _ = load_csv(first, "HH")
    first_vv, _ = load_csv(first, "VV")
    check(max(abs(first_hh[a] - first_vv[a]) for a in first_hh if a < 89.0) < 0.01,
          "first-order edges: HH = VV in the principal plane (docs/validation.md)")
    for pol, p in (("HH", "H"), ("VV", "V")):
        ref = load_ref(f"ref_rcs.II.A.sx1.{tag}.{p}.txt")
        got, rows = load_csv(on, pol)
        po, _ = load_csv(off, pol)
        one, _ = load_csv(first, pol)
        check(rows[0]["edges"] == "1" and int(rows[0]["edges_used"]) == 4,
              "plate: edges on, its 4 rim edges used")
        med = statistics.median(abs(got[a] - ref[a]) for a in ref if a <= 70.0)
        med_po = statistics.median(abs(po[a] - ref[a]) for a in ref if a <= 70.0)
        med_one = statistics.median(abs(one[a] - ref[a]) for a in ref if a <= 70.0)
        print(f"plate {freq / 1e9:g} GHz {pol}: normal {got[0.0] - ref[0.0]:+.3f} dB "
              f"(PO {po[0.0] - ref[0.0]:+.3f}, first order {one[0.0] - ref[0.0]:+.3f}); median "
              f"|diff| 0-70 deg PO {med_po:.2f} dB, first-order edges {med_one:.2f} dB, "
              f"PO + edges (order 2) {med:.2f} dB")
        figure(f"plate {freq / 1e9:g} GHz {pol} normal |diff|", abs(got[0.0] - ref[0.0]), 0.2,
               0.2)
        figure(f"plate {freq / 1e9:g} GHz {pol} median |diff| 0-70 deg", med, 2.0, 2.0)
        check(med < med_po, f"plate {freq / 1e9:g} GHz {pol}: edges improve on PO")
        # First-order edge currents are in quadrature with PO at normal incidence.
        check(abs(one[0.0] - po[0.0]) < 0.1,
              "at normal incidence first-order edges change < 0.1 dB")
    if charts and tag in chart_name:
        # PO + edges from a fine run; first order, PO alone and the reference as overlays.
        fine = {}
        for name, extra in (("po", ("--no-edges",)), ("first", ("--edge-order", "1"))):
            fine[name] = os.path.join(work, f"chart_{tag}_{name}.csv")
            sweep(plate, freq, "0:90:361", fine[name], *extra)
        for pol, p in (("HH", "H"), ("VV", "V")):
            if tag == "f9" and pol == "VV":
                continue
            overlays = []
            for name, label in (("first", "first-order edges"), ("po", "PO alone")):
                vals, _ = load_csv(fine[name], pol)
                txt = os.path.join(work, f"chart_{tag}_{name}_{pol}.txt")
                write_series(txt, vals)
                overlays += ["--overlay", f"{txt}={label}"]
            ref_txt = os.path.join(work, f"chart_{tag}_ref_{pol}.txt")
            ref = load_ref(f"ref_rcs.II.A.sx1.{tag}.{p}.txt")
            write_series(ref_txt, ref)
            overlays += ["--overlay", f"{ref_txt}=reference (Austin, ARCHIE-AIM)"]
            png = f"austin_plate_{chart_name[tag]}ghz_{pol.lower()}.png"
            run("rcs", "--mesh", plate, "--freq-hz", str(freq), "--theta-deg", "90", "--phi-deg",
                "0:90:361", "--pol", pol, "--bounces", "1", "-q",
                "--out", os.path.join(work, f"chart_{tag}_{pol}.csv"),
                "--plot", os.path.join(charts, png), *overlays)

# --- IIA plates by the method of moments (the EFIE on the open sheet). ------------------------
C = 299792458.0


def sweep_mom(mesh, freq, phis, out):
    run("rcs", "--mesh", mesh, "--freq-hz", str(freq), "--theta-deg", "90", "--phi-deg", phis,
        "--pol", "HH,VV", "--method", "mom", "--out", out, "-q")


for tag, freq in (("f9", 2.56e9), ("fx1", 7e9)):
    mesh = os.path.join(work, f"plate_{tag}_mom.obj")
    n = write_plate_grid(mesh, C / freq / 10)
    out = os.path.join(work, f"plate_{tag}_mom.csv")
    sweep_mom(mesh, freq, "0:90:181", out)
    for pol, p in (("HH", "H"), ("VV", "V")):
        ref = load_ref(f"ref_rcs.II.A.sx1.{tag}.{p}.txt")
        got, _ = load_csv(out, pol)
        med = statistics.median(abs(got[a] - ref[a]) for a in ref if a <= 70.0)
        print(f"plate {freq / 1e9:g} GHz {pol}, method of moments ({n} triangles): normal "
              f"{got[0.0] - ref[0.0]:+.3f} dB, median |diff| 0-70 deg {med:.2f} dB")
        # Measured 0.05-0.22 dB at normal incidence (the current's edge singularity on a tenth-
        # wavelength mesh) and medians 0.11-0.21 dB.
        check(abs(got[0.0] - ref[0.0]) <= 0.3, f"plate MoM {tag} {pol} at normal incidence")
        check(med <= 0.4, f"plate MoM {tag} {pol}: median |diff| {med:.3f} dB")

# --- IIIA almond. -----------------------------------------------------------------------------
almond = os.path.join(work, "almond.obj")
almond_triangles = write_almond(almond)
# PO alone / PO + edges at the default threshold (the almond is smooth: no edge turns by 30 deg,
# so edges add nothing), and with the rim of the faceted almond taken as wedges
# (--edge-turn-deg 5 on this 120 x 96 mesh): figures reached, asserted as regression bounds.
almond_bounds = {"fx3": {"HH": (5.2, 2.9), "VV": (2.9, 2.4)},
                 "fx4": {"HH": (3.9, 1.6), "VV": (2.1, 1.8)}}
chart_almond = {"fx3": "7", "fx4": "10_25"}
for tag, freq, target, per_wavelength in (("fx3", 7e9, 1.5, 10), ("fx4", 10.25e9, 1.0, 8)):
    po_csv = os.path.join(work, f"almond_{tag}_po.csv")
    on_csv = os.path.join(work, f"almond_{tag}.csv")
    rim_csv = os.path.join(work, f"almond_{tag}_rim.csv")
    mom_csv = os.path.join(work, f"almond_{tag}_mom.csv")
    mom_mesh = os.path.join(work, f"almond_{tag}_mom.obj")
    sweep(almond, freq, "0:180:361", po_csv, "--no-edges")
    started = time.monotonic()
    sweep(almond, freq, "0:180:361", on_csv)
    po_s = time.monotonic() - started
    sweep(almond, freq, "0:180:361", rim_csv, "--edge-turn-deg", "5")
    n = write_almond_uniform(mom_mesh, C / freq / per_wavelength)
    started = time.monotonic()
    sweep_mom(mom_mesh, freq, "0:180:361", mom_csv)
    mom_s = time.monotonic() - started
    print(f"almond {freq / 1e9:g} GHz, 361 directions: PO + edges {po_s:.1f} s "
          f"({almond_triangles} triangles), method of moments {mom_s:.1f} s ({n} triangles, "
          f"lambda/{per_wavelength})")
    for pol, p in (("HH", "H"), ("VV", "V")):
        ref = load_ref(f"ref_rcs.III.A.s1.{tag}.{p}.txt")
        peak = max(ref.values())
        lobes = [a for a in ref if ref[a] >= peak - 20.0]
        res = {}
        for name, path in (("PO", po_csv), ("PO+edges", on_csv), ("PO+edges(rim)", rim_csv),
                           ("MoM", mom_csv)):
            got, _ = load_csv(path, pol)
            res[name] = (statistics.median(abs(got[a] - ref[a]) for a in lobes),
                         got[0.0] - ref[0.0])
        print(f"almond {freq / 1e9:g} GHz {pol}: median |diff| over {len(lobes)} lobe directions: "
              + ", ".join(f"{k} {v[0]:.2f} dB" for k, v in res.items())
              + "; nose-on diff " + ", ".join(f"{k} {v[1]:+.1f} dB" for k, v in res.items()))
        check(res["PO+edges"][0] == res["PO"][0], "almond: no edge at the default threshold")
        figure(f"almond {freq / 1e9:g} GHz {pol} median |diff| (method of moments)",
               res["MoM"][0], target, target)
        bound_po, bound_rim = almond_bounds[tag][pol]
        figure(f"almond {freq / 1e9:g} GHz {pol} median |diff| (PO + edges, default)",
               res["PO+edges"][0], target, bound_po)
        figure(f"almond {freq / 1e9:g} GHz {pol} median |diff| (PO + rim edges, "
               f"--edge-turn-deg 5)", res["PO+edges(rim)"][0], target, bound_rim)
        if pol == "HH":
            # Nose-on the return is the tip and travelling/creeping waves: the currents of the
            # method of moments carry them, PO and wedge edges do not (printed, finite).
            figure(f"almond {freq / 1e9:g} GHz nose-on HH |diff| (method of moments)",
                   abs(res["MoM"][1]), 3.0, 3.0)
            nose = abs(res["PO+edges(rim)"][1])
            report.append(f"almond {freq / 1e9:g} GHz nose-on HH |diff| (PO + rim edges): "
                          f"{nose:.1f} dB  [{'reached' if nose <= 3.0 else 'NOT REACHED'}]")
            print(report[-1])
            check(math.isfinite(nose), "nose-on finite")
        if charts:
            overlays = []
            # The main curve is PO + edges, the default (on the smooth almond: PO alone).
            for name, label in ((mom_csv, "method of moments"),
                                (rim_csv, "PO + rim edges (--edge-turn-deg 5)")):
                vals, _ = load_csv(name, pol)
                txt = os.path.join(work, f"chart_almond_{tag}_{len(overlays)}_{pol}.txt")
                write_series(txt, vals)
                overlays += ["--overlay", f"{txt}={label}"]
            ref_txt = os.path.join(work, f"chart_almond_{tag}_ref_{pol}.txt")
            write_series(ref_txt, ref)
            overlays += ["--overlay", f"{ref_txt}=reference (Austin, ARCHIE-AIM)"]
            png = f"austin_almond_{chart_almond[tag]}ghz_{pol.lower()}.png"
            run("rcs", "--mesh", almond, "--freq-hz", str(freq), "--theta-deg", "90",
                "--phi-deg", "0:180:361", "--pol", pol, "--bounces", "1", "-q",
                "--out", os.path.join(work, f"chart_almond_{tag}_{pol}.csv"),
                "--plot", os.path.join(charts, png), *overlays)

print("\nsummary:\n  " + "\n  ".join(report))
finish()
