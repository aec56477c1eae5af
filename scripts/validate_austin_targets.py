#!/usr/bin/python3
"""radar-emu rcs against the Austin RCS Benchmark Suite's realistic PEC targets (issue 30, item 4):
the camera boxes with a cobra duct (IIISB), a cylindrical duct (IIISC) and a straight-blade fan
(IIISD), and the PRIME aircraft with a closed (IVA) and an open (IVC) duct, all at the suite's
smallest size (camera box L = 40 cm, aircraft L = 9.1875 in), backscatter phi cut at
theta = 90 deg, HH and VV, at every frequency the suite gives a reference for (2.56-10.25 GHz).

Not a CI test: a run takes 13-22 minutes on the shared 2-core machine (below; docs/validation.md,
"Realistic targets"). The reference tables (integral-equation solutions, ARCHIE-AIM) and the
measurements are the copies in tests/data/austin/ (README there, the suite's licence beside
them). The geometry is read from the suite itself (--suite: a clone of
https://github.com/UTAustinCEMGroup/AustinCEMBenchmarks, work tree or bare git directory):
  - IIISD and the aircraft: the suite's triangular INP meshes (first line: node and triangle
    counts; then x y z per node; then three 1-based node numbers per triangle, a region number
    after them in the camera boxes), full scale in metres;
  - IIISB and IIISC: the suite gives no mesh, only CAD models; their binary STL (full scale,
    metres) is read, its vertices welded and its cracks closed (the export leaves 4 008 and
    6 904 edges used by one triangle only where CAD patches meet: T-junctions, and chords of a
    curved seam up to 0.1 mm apart at the smallest size; each is split at the other patch's
    vertices, after which both surfaces are closed; left open they are sheet boundaries, which
    always diffract, and cost the cobra box 1-2 dB).
Each mesh is scaled to the smallest size (camera boxes 1/32 of the 12.8 m full scale; aircraft
9.1875 in / 592.763 in), turned 180 deg about z (the suite's phi is measured the other way round
from radar-emu's: with the mesh as given, its phi = 0 is radar-emu's phi = 180; measured on IIISD,
median |diff| 3.5 dB as given, 0.3 dB turned, 10.24 GHz HH), its triangles wound consistently
(the suite's meshes have a few hundred edges whose two triangles disagree) and written as OBJ.

For every target, frequency and polarisation it prints the median |diff| in dB against the
reference over the whole cut, over the lobes (directions where the reference is within 20 dB
of its peak) and over three sectors (phi 0-30, 30-150, 150-180 deg: for the aircraft nose,
side, tail; for the camera boxes the duct's face, the sides, the closed back), for
  - PO + SBR + edges, today's default ("default"),
  - the same without edges (--no-edges),
  - rim as wedges (--edge-turn-deg 5),
  - the method of moments (--method mom) where the mesh the suite provides is small enough,
and the median |diff| of each against the measurement, with the reference's own against it.

Usage: validate_austin_targets.py RADAR_EMU --suite DIR [--work DIR] [--targets IIISB,IVA,...]
       [--step-deg 2] [--iiisc-step-deg 6] [--bounces 3] [--no-mom] [--markdown]
       validate_austin_targets.py - --tables-from WORK/summary.csv   (the docs' tables again)
  --step-deg: angle step of the cut (the reference is every 0.5 deg; default 2, every fourth
              reference angle; 0.5 for the full cut);
  --iiisc-step-deg: the same for IIISC, whose 460 000-triangle CAD export costs ~0.5 s a
              direction (default 6).
Run time on the 2-core machine shared with other work (load ~12): the defaults 12.9 minutes wall
(4.6 of CPU; the method of moments 3.5 of them), --iiisc-step-deg 2 21.6 minutes (7.3 of CPU)."""
import argparse
import csv
import io
import math
import os
import statistics
import subprocess
import sys
import time
import zipfile

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
DATA = os.path.join(HERE, "..", "tests", "data", "austin")
INCH = 0.0254
CB = "Austin-RCS-Benchmarks/Problem IIIS-Camera Boxes/"
PR = "Austin-RCS-Benchmarks/Problem IV-PRIME Aircrafts/"

# Frequencies: the tag in the suite's file names -> Hz (as in the tables' first column).
TARGETS = {
    "IIISB": dict(
        name="PEC cobra-duct camera box", kind="stl", scale=1 / 32,
        po=CB + "Models/Cobra-Duct_Camera_Box_s6 .stl Model.zip", mom=None,
        stem="IIIS.B.s1", meas="meas_rcs", tags=("f9", "f10", "fx1", "f11")),
    "IIISC": dict(
        name="PEC cylindrical-duct camera box", kind="stl", scale=1 / 32,
        po=CB + "Models/Cylindrical-Duct_Camera_Box_s6 .stl Model.zip", mom=None, coarse=True,
        stem="IIIS.C.s1", meas="meas.m1_rcs", tags=("f9", "f10", "fx1", "f11")),
    "IIISD": dict(
        name="PEC straight-blade fan-loaded camera box", kind="inp", scale=1 / 32,
        po=CB + "INP_Meshes/Straight-Blade_Fan-Loaded_Camerabox_model_meshZZ.zip",
        mom=CB + "INP_Meshes/Straight-Blade_Fan-Loaded_Camerabox_model_meshYY.zip",
        stem="IIIS.D.s1", meas="meas.m1_rcs", tags=("f9", "f10", "fx1", "f11")),
    "IVA": dict(
        name="PEC closed-duct PRIME aircraft", kind="inp", scale=9.1875 / 592.763,
        po=PR + "INP_Meshes/Closed-Duct_PRIME_model_meshAB.zip",
        mom=PR + "INP_Meshes/Closed-Duct_PRIME_model_meshAA.zip",
        stem="IV.A.s1", meas="meas.m1_rcs", tags=("fx1", "f10", "fx2", "fx3")),
    "IVC": dict(
        name="PEC open-duct PRIME aircraft", kind="inp", scale=9.0116 / 581.3927,
        po=PR + "INP_Meshes/Open-Duct_PRIME_model_meshAB.zip",
        mom=PR + "INP_Meshes/Open-Duct_PRIME_model_meshAA.zip",
        stem="IV.C.s1", meas="meas.m1_rcs", tags=("f9", "fx1", "f10", "fx2", "f11"),
        meas_by_tag={"f11": "meas.m3_rcs"}),  # the suite's only 10.24 GHz measurement
}
# IIISA (closed-duct camera box) is left out: the suite gives neither a mesh nor a model for it
# (its geometry is a drawing in the problem description).
MOM_LIMIT = 10000  # unknowns: 16 N^2 bytes (1.6 GB); ~9,000 take ~45 s on the 2-core machine


def suite_bytes(suite, path):
    """A file of the suite: from a work tree, else from a (bare) git directory's HEAD."""
    full = os.path.join(suite, path)
    if os.path.isfile(full):
        with open(full, "rb") as f:
            return f.read()
    return subprocess.run(["git", "-C", suite, "show", "HEAD:" + path], check=True,
                          capture_output=True).stdout


def unzip_one(blob, ext):
    z = zipfile.ZipFile(io.BytesIO(blob))
    names = sorted(n for n in z.namelist() if n.lower().endswith(ext))
    if not names:
        raise RuntimeError(f"no *{ext} in the archive ({z.namelist()})")
    # Split meshes (the suite's finest) are parts to concatenate in name order.
    return b"".join(z.read(n) for n in names)


def read_inp(text):
    """The suite's INP mesh: 'Nnodes Ntris [..]', Nnodes lines x y z, Ntris lines i j k [region]."""
    lines = text.decode("ascii").split("\n")
    nn, nt = (int(x) for x in lines[0].split()[:2])
    verts = np.array([[float(x) for x in ln.split()[:3]] for ln in lines[1:1 + nn]])
    tris = np.array([[int(x) for x in ln.split()[:3]] for ln in lines[1 + nn:1 + nn + nt]]) - 1
    return verts, tris


def read_stl(blob):
    """Binary STL (80-byte header, count, 50 bytes a triangle); vertices welded."""
    if blob[:5] == b"solid" and b"facet" in blob[:400]:
        raise RuntimeError("ASCII STL: not expected here")
    n = int(np.frombuffer(blob, "<u4", 1, 80)[0])
    rec = np.frombuffer(blob, np.dtype([("n", "<f4", 3), ("v", "<f4", (3, 3)), ("a", "<u2")]),
                        n, 84)
    pts = rec["v"].reshape(-1, 3).astype(np.float64)
    tol = 1e-6 * np.ptp(pts, axis=0).max()
    key = np.round(pts / tol).astype(np.int64)
    uniq, inv = np.unique(key, axis=0, return_inverse=True)
    verts = np.zeros((len(uniq), 3))
    verts[inv.ravel()] = pts
    tris = inv.reshape(-1, 3)
    keep = (tris[:, 0] != tris[:, 1]) & (tris[:, 1] != tris[:, 2]) & (tris[:, 0] != tris[:, 2])
    return verts, tris[keep]


def close_cracks(verts, tris, rel=1e-4):
    """CAD exports (the camera boxes' STL) leave cracks where two patches meet: a vertex of one
    patch lies on an edge of the other (a T-junction), or within the chord's sagitta of it. Each
    edge used by one triangle only is split at the other boundary vertices within rel x the
    model's extent of it, the triangle fanned from its opposite corner (from an added centre when
    two of its edges are split). Returns the vertices, triangles and the open edges before and
    after."""
    def open_half_edges(tris):
        a = np.concatenate([tris[:, 0], tris[:, 1], tris[:, 2]])
        b = np.concatenate([tris[:, 1], tris[:, 2], tris[:, 0]])
        key = np.minimum(a, b) * (len(verts) + 1) + np.maximum(a, b)
        _, inv, cnt = np.unique(key, return_inverse=True, return_counts=True)
        return a, b, np.nonzero(cnt[inv.ravel()] == 1)[0]

    a, b, bnd = open_half_edges(tris)
    before = len(bnd)
    if before == 0:
        return verts, tris, 0, 0
    nt = len(tris)
    owner, slot = np.tile(np.arange(nt), 3), np.repeat(np.arange(3), nt)
    bv = np.unique(np.concatenate([a[bnd], b[bnd]]))
    pts = verts[bv]
    tol = rel * np.ptp(verts, axis=0).max()
    splits = {}
    for h in bnd:
        p0, d = verts[a[h]], verts[b[h]] - verts[a[h]]
        t = (pts - p0) @ d / (d @ d)
        m = (t > 1e-9) & (t < 1 - 1e-9)
        if not m.any():
            continue
        dist = np.linalg.norm(pts[m] - (p0 + np.outer(t[m], d)), axis=1)
        ok = dist < tol
        if ok.any():
            ids, ts = bv[m][ok], t[m][ok]
            splits.setdefault(owner[h], []).append((slot[h], ids[np.argsort(ts)]))
    out = [tris[i] for i in range(nt) if i not in splits]
    extra = []
    for i, lst in splits.items():
        tri = list(tris[i])
        poly = []
        for s in range(3):
            poly.append(tri[s])
            for ss, ids in lst:
                if ss == s:
                    poly.extend(ids.tolist())
        if len(lst) == 1:
            apex = tri[(lst[0][0] + 2) % 3]
            j = poly.index(apex)
            seq = poly[j + 1:] + poly[:j]
            out += [np.array([apex, seq[q], seq[q + 1]]) for q in range(len(seq) - 1)]
        else:
            centre = len(verts) + len(extra)
            extra.append(verts[tri].mean(axis=0))
            out += [np.array([poly[q], poly[(q + 1) % len(poly)], centre])
                    for q in range(len(poly))]
    if extra:
        verts = np.vstack([verts, np.array(extra)])
    tris = np.array(out)
    return verts, tris, before, len(open_half_edges(tris)[2])


def orient(verts, tris):
    """Winds every connected part consistently (a triangle's neighbour across an edge used by
    exactly two triangles runs that edge the other way) and outward (positive volume). Returns
    the triangles and the number of them flipped."""
    tris = tris.copy()
    nt = len(tris)
    a = np.concatenate([tris[:, 0], tris[:, 1], tris[:, 2]])
    b = np.concatenate([tris[:, 1], tris[:, 2], tris[:, 0]])
    owner = np.tile(np.arange(nt), 3)
    key = np.minimum(a, b) * (len(verts) + 1) + np.maximum(a, b)
    order = np.argsort(key, kind="stable")
    ks = key[order]
    nbr = [[] for _ in range(nt)]
    i = 0
    while i < len(ks):
        j = i
        while j + 1 < len(ks) and ks[j + 1] == ks[i]:
            j += 1
        if j == i + 1:  # a manifold edge
            t0, t1 = owner[order[i]], owner[order[j]]
            same = a[order[i]] == a[order[j]]  # both run it the same way: one must flip
            nbr[t0].append((t1, same))
            nbr[t1].append((t0, same))
        i = j + 1
    flip = np.zeros(nt, bool)
    seen = np.zeros(nt, bool)
    parts = []
    for s in range(nt):
        if seen[s]:
            continue
        seen[s] = True
        stack, part = [s], [s]
        while stack:
            t = stack.pop()
            for u, same in nbr[t]:
                if not seen[u]:
                    seen[u] = True
                    flip[u] = flip[t] ^ same
                    stack.append(u)
                    part.append(u)
        parts.append(np.array(part))
    tris[flip] = tris[flip][:, ::-1]
    for p in parts:
        v0, v1, v2 = (verts[tris[p, k]] for k in range(3))
        if np.einsum("ij,ij->i", v0, np.cross(v1, v2)).sum() < 0:
            tris[p] = tris[p][:, ::-1]
    changed = int(np.count_nonzero(flip))
    return tris, min(changed, nt - changed)


def write_obj(path, verts, tris):
    with open(path, "w") as f:
        f.write("".join("v %.9g %.9g %.9g\n" % tuple(v) for v in verts))
        f.write("".join("f %d %d %d\n" % tuple(t) for t in tris + 1))


def convert(suite, t, which, path):
    """The suite's geometry for target t -> OBJ at the smallest size, turned 180 deg about z.
    Returns (triangles, mean edge length in m, triangles re-wound, a note)."""
    blob = suite_bytes(suite, t[which])
    note = ""
    if t["kind"] == "inp":
        verts, tris = read_inp(unzip_one(blob, ".inp"))
    else:
        verts, tris = read_stl(unzip_one(blob, ".stl"))
        verts, tris, before, after = close_cracks(verts, tris)
        note = f", cracks closed: {before} open edges -> {after}"
    verts = verts * t["scale"]
    verts[:, 0] *= -1.0
    verts[:, 1] *= -1.0
    tris, flipped = orient(verts, tris)
    write_obj(path, verts, tris)
    e = np.linalg.norm(verts[tris] - verts[np.roll(tris, 1, axis=1)], axis=2)
    return len(tris), float(e.mean()), flipped, note


def load_table(name):
    """phi (deg, rounded to 0.01) -> dBsm, and the frequency, from a suite table."""
    out, freq = {}, None
    with open(os.path.join(DATA, name)) as f:
        for line in f:
            x = line.split()
            if len(x) >= 4:
                freq = float(x[0])
                out[round(float(x[2]), 2)] = float(x[3])
    return out, freq


def load_csv(path, pol):
    with open(path, newline="") as f:
        return {round(float(r["phi_deg"]), 2): float(r[f"rcs_{pol}_dbsm"])
                for r in csv.DictReader(f)}


def med(got, ref, keep=lambda p: True):
    d = [abs(got[p] - ref[p]) for p in got if p in ref and keep(p)]
    return statistics.median(d) if d else float("nan")


def reference_vs_measurement():
    """(target, GHz, pol) -> median |reference - measurement| over the reference's angles."""
    out = {}
    for key, t in TARGETS.items():
        for tag in t["tags"]:
            for p in "HV":
                meas = f"{t.get('meas_by_tag', {}).get(tag, t['meas'])}.{t['stem']}.{tag}.{p}.txt"
                if os.path.exists(os.path.join(DATA, meas)):
                    ref, freq = load_table(f"ref_rcs.{t['stem']}.{tag}.{p}.txt")
                    out[(key, round(freq / 1e9, 4), p + p)] = med(ref, load_table(meas)[0])
    return out


def markdown(rows):
    """The docs' tables (docs/validation.md, "Realistic targets") from the rows of a run."""
    refmeas = reference_vs_measurement()
    out = []
    for key in dict.fromkeys(r["target"] for r in rows):
        mine = [r for r in rows if r["target"] == key]
        methods = list(dict.fromkeys(r["method"] for r in mine))
        out.append(f"\n**{key}, {TARGETS[key]['name']}**\n")
        head = ["frequency", "pol"] + [f"median, {m}" for m in methods] + [
            "lobes, default", "lobes, rim-wedges", "default, phi 0-30 / 30-150 / 150-180",
            "default vs measurement",
            "reference vs measurement"]
        out.append("| " + " | ".join(head) + " |")
        out.append("|" + "---|" * len(head))
        for f in dict.fromkeys(r["freq_ghz"] for r in mine):
            for pol in ("HH", "VV"):
                by = {r["method"]: r for r in mine if r["freq_ghz"] == f and r["pol"] == pol}
                if not by:
                    continue
                best = min(v["median"] for v in by.values())
                cells = [f"{f:.4g} GHz", pol]
                for m in methods:
                    v = by[m]["median"] if m in by else float("nan")
                    cells.append("-" if math.isnan(v) else
                                 (f"**{v:.2f}**" if v == best else f"{v:.2f}"))
                rm = refmeas.get((key, round(f, 4), pol), float("nan"))
                d = by["default"]
                cells += [f"{d['lobes']:.2f}", f"{by['rim-wedges']['lobes']:.2f}",
                          f"{d['s0_30']:.1f} / {d['s30_150']:.1f} / {d['s150_180']:.1f}",
                          "-" if math.isnan(by["default"]["meas"]) else
                          f"{by['default']['meas']:.2f}", "-" if math.isnan(rm) else f"{rm:.2f}"]
                out.append("| " + " | ".join(cells) + " |")
        secs = {m: statistics.mean(r["seconds"] for r in mine if r["method"] == m) for m in methods}
        out.append("\nRun time per frequency (both polarisations): " + ", ".join(
            f"{m} {v:.1f} s" for m, v in secs.items()) + "; " + ", ".join(
            f"{int(r['triangles']):d} triangles ({'MoM' if r['method'] == 'mom' else 'PO'})"
            for r in {r["method"] == "mom": r for r in mine}.values()) + ".")
    return "\n".join(out)


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("radar_emu")
    ap.add_argument("--suite")
    ap.add_argument("--work", default="austin-targets")
    ap.add_argument("--targets", default=",".join(["IIISA", *TARGETS]))
    ap.add_argument("--step-deg", type=float, default=2.0)
    ap.add_argument("--iiisc-step-deg", type=float, default=6.0)
    ap.add_argument("--bounces", type=int, default=3)
    ap.add_argument("--no-mom", action="store_true")
    ap.add_argument("--markdown", action="store_true", help="also print the docs' tables")
    ap.add_argument("--tables-from", metavar="CSV",
                    help="only print the docs' tables from the summary.csv of an earlier run")
    args = ap.parse_args()
    if args.tables_from:
        with open(args.tables_from, newline="") as f:
            rows = [{k: (v if k in ("target", "pol", "method") else float(v))
                     for k, v in r.items()} for r in csv.DictReader(f)]
        print(markdown(rows))
        return 0
    if not args.suite:
        ap.error("--suite DIR is needed (a clone of the Austin RCS Benchmark Suite)")
    os.makedirs(args.work, exist_ok=True)
    variants = (("default", ()), ("no-edges", ("--no-edges",)),
                ("rim-wedges", ("--edge-turn-deg", "5")))
    rows, started_all = [], time.monotonic()
    print(f"cut: theta 90 deg, phi 0..180 every {args.step_deg:g} deg (IIISC every "
          f"{args.iiisc_step_deg:g} deg), --bounces {args.bounces}")
    for key in args.targets.split(","):
        if key not in TARGETS:
            print(f"\n{key}: not run" + (": the suite gives neither a mesh nor a model of the "
                                          "closed-duct camera box" if key == "IIISA" else
                                          f" (known: {', '.join(TARGETS)})"))
            continue
        t = TARGETS[key]
        obj = os.path.join(args.work, f"{key}.obj")
        # IIISC's CAD export has 460 000 triangles (~0.5 s a direction, ~10 s to load a run):
        # its own, coarser step by default.
        step = args.iiisc_step_deg if t.get("coarse") else args.step_deg
        phis = f"0:180:{int(round(180 / step)) + 1}"
        try:
            ntri, edge, flipped, note = convert(args.suite, t, "po", obj)
        except Exception as e:  # a geometry that cannot be read is reported, not fatal
            print(f"{key} {t['name']}: geometry not read: {e}")
            continue
        print(f"\n{key} {t['name']}: {os.path.basename(t['po'])}: {ntri} triangles, mean edge "
              f"{edge * 1e3:.1f} mm at the smallest size, {flipped} re-wound{note}")
        mom_obj, mom_n = None, None
        if t["mom"] and not args.no_mom:
            mom_obj = os.path.join(args.work, f"{key}_mom.obj")
            mom_n, mom_edge, _, _ = convert(args.suite, t, "mom", mom_obj)
            unknowns = mom_n * 3 // 2
            if unknowns > MOM_LIMIT:
                print(f"  method of moments: {os.path.basename(t['mom'])} (the suite's coarsest "
                      f"mesh) has {mom_n} triangles, {unknowns} unknowns "
                      f"({16 * unknowns ** 2 / 1e9:.1f} GB): too large here (limit {MOM_LIMIT})")
                mom_obj = None
        for tag in t["tags"]:
            ref = {p: load_table(f"ref_rcs.{t['stem']}.{tag}.{p}.txt") for p in "HV"}
            mname = t.get("meas_by_tag", {}).get(tag, t["meas"])
            meas = {p: load_table(f"{mname}.{t['stem']}.{tag}.{p}.txt")[0]
                    if os.path.exists(os.path.join(DATA, f"{mname}.{t['stem']}.{tag}.{p}.txt"))
                    else None for p in "HV"}
            freq = ref["H"][1]
            runs = []
            for name, extra in variants:
                out = os.path.join(args.work, f"{key}_{tag}_{name}.csv")
                t0 = time.monotonic()
                proc = subprocess.run(
                    ["nice", args.radar_emu, "rcs", "--mesh", obj, "--freq-hz", repr(freq),
                     "--theta-deg", "90", "--phi-deg", phis, "--pol", "HH,VV", "--bounces",
                     str(args.bounces), "--out", out, "-q", *extra],
                    capture_output=True, text=True)
                if proc.returncode != 0:
                    print(f"  {tag} {name}: radar-emu failed: {proc.stderr.strip()}")
                    continue
                runs.append((name, out, time.monotonic() - t0, ntri))
            if mom_obj:
                lam = 299792458.0 / freq
                if mom_edge <= lam / 4:
                    out = os.path.join(args.work, f"{key}_{tag}_mom.csv")
                    t0 = time.monotonic()
                    proc = subprocess.run(
                        ["nice", args.radar_emu, "rcs", "--mesh", mom_obj, "--freq-hz", repr(freq),
                         "--theta-deg", "90", "--phi-deg", phis, "--pol", "HH,VV", "--method",
                         "mom", "--out", out, "-q"], capture_output=True, text=True)
                    if proc.returncode != 0:
                        print(f"  {tag} mom: radar-emu failed: {proc.stderr.strip()}")
                    else:
                        runs.append(("mom", out, time.monotonic() - t0, mom_n))
                else:
                    print(f"  {freq / 1e9:g} GHz: no method of moments (the {mom_n}-triangle mesh's "
                          f"mean edge {mom_edge * 1e3:.1f} mm is over lambda/4)")
            for pol in "HV":
                r = ref[pol][0]
                peak = max(r.values())
                lobe = lambda p, r=r, peak=peak: r[p] >= peak - 20.0
                m = meas[pol]
                line = (f"  {freq / 1e9:g} GHz {pol}{pol}:"
                        + (f" reference vs measurement {med(r, m):.2f} dB;" if m else ""))
                print(line)
                for name, out, secs, nt in runs:
                    got = load_csv(out, pol + pol)
                    row = dict(target=key, freq_ghz=freq / 1e9, pol=pol + pol, method=name,
                               triangles=nt, seconds=round(secs, 1),
                               median=med(got, r), lobes=med(got, r, lobe),
                               s0_30=med(got, r, lambda p: p <= 30),
                               s30_150=med(got, r, lambda p: 30 < p < 150),
                               s150_180=med(got, r, lambda p: p >= 150),
                               meas=med(got, m) if m else float("nan"))
                    rows.append(row)
                    print(f"    {name:10s} median |diff| {row['median']:5.2f} dB, lobes "
                          f"{row['lobes']:5.2f}, phi 0-30 {row['s0_30']:5.2f}, 30-150 "
                          f"{row['s30_150']:5.2f}, 150-180 {row['s150_180']:5.2f}; vs "
                          f"measurement {row['meas']:5.2f}  ({secs:.1f} s, {nt} triangles)")
    with open(os.path.join(args.work, "summary.csv"), "w", newline="") as f:
        if rows:
            w = csv.DictWriter(f, fieldnames=list(rows[0]))
            w.writeheader()
            w.writerows(rows)
    # Which of rim-as-wedges and today's default is closer, per target (median over the cut).
    print("\nrim as wedges (--edge-turn-deg 5) against today's default, median |diff| vs "
          "reference:")
    for key in (k for k in args.targets.split(",") if k in TARGETS):
        pairs = []
        for r in rows:
            if r["target"] == key and r["method"] == "default":
                rim = [x for x in rows if x["target"] == key and x["method"] == "rim-wedges"
                       and x["freq_ghz"] == r["freq_ghz"] and x["pol"] == r["pol"]]
                if rim:
                    pairs.append((r["freq_ghz"], r["pol"], r["median"], rim[0]["median"]))
        if pairs:
            better = sum(1 for p in pairs if p[3] < p[2])
            print(f"  {key}: rim better in {better} of {len(pairs)} cases; "
                  + ", ".join(f"{f:g} {p} {d:.2f}->{q:.2f}" for f, p, d, q in pairs))
    if args.markdown:
        print(markdown(rows))
    print(f"\ntotal {time.monotonic() - started_all:.0f} s; rows in "
          f"{os.path.join(args.work, 'summary.csv')}")


if __name__ == "__main__":
    sys.exit(main())
