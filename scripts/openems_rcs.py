#!/usr/bin/python3
"""Full-wave monostatic RCS references computed with openEMS (FDTD; Debian 12: openems,
python3-openems 0.0.35), for tests/data/openems_plate/ (README.md there says how the checked-in
table was made; tests/integration/check_openems_plate.py compares radar-emu rcs with it).

Two set-ups share one FDTD routine (run_case):
  sphere  PEC sphere, radius 50 mm, ka = 1..5 from one Gaussian-pulse run, against the Mie series
          computed here (mie_pec_backscatter: numpy/scipy spherical Bessel functions, independent
          of radar-emu's radar/reference/mie.*): the check of the set-up (excitation normalisation,
          NF2FF, units).
  plate   PEC zero-thickness square plate, 100 mm a side (3.0, 3.33 and 4.0 wavelengths at 9, 10
          and 12 GHz), in the x-y plane (z = 0), edges along x and y, centred on the origin.
          Radar directions theta = 0..85 deg from the normal +z, phi = 0 (the x-z plane is the
          plane of incidence, a principal plane), one FDTD run per angle.

Excitation: a total-field/scattered-field plane wave (openEMS excitation type 10) filling a box
around the object, travelling along -r_hat(theta, phi), r_hat the radar direction; Gaussian pulse
(openEMS SetGaussExcite). Scattered far field: the NF2FF transform of the frequency-domain
E and H recorded on a closed box in the scattered-field region, evaluated back toward the radar at
radius 1 m. sigma = 4 pi r^2 |E_s . p|^2 / |E_0 . p|^2 with E_0(f) the spectrum of the excitation
signal that openEMS writes (file 'et', same DFT convention as the field dumps), p the receive
polarisation: H = phi_hat, V = theta_hat (radar-emu's convention, radar/em/rcs.hpp).

Both polarisations from one run (plate): the incident E is phi_hat + theta_hat. The plate and the
mesh are symmetric under the mirror y -> -y, which holds the radar direction (phi = 0); under it
theta_hat is even and phi_hat = y_hat odd, so an H-incident wave scatters only H back and a V one
only V (no cross-polarisation in a principal plane): the phi_hat and theta_hat parts of the
backscattered field give sigma_HH and sigma_VV. `plate --separate-pol` runs the two apart.

HH here: E = y_hat, parallel to the plate and perpendicular to the plane of incidence (TE, or
E-perpendicular). VV: E = theta_hat, in the plane of incidence (TM, or E-parallel; its E has a
component normal to the plate, which grows toward grazing).

Usage:
  scripts/openems_rcs.py sphere OUT.csv [--threads N] [--dx-mm 2.5] [--pml-gap 4] [--end 1e-5]
  scripts/openems_rcs.py plate OUT.csv [--theta-deg 0:85:35] [--threads N] [--dx-mm 1.25]
                         [--separate-pol]
  scripts/openems_rcs.py plate OUT.csv --theta-deg A --no-object   (the set-up without the
                                                     plate: the TF/SF leakage floor, as an RCS)
Each run works in a temporary folder (removed after) and prints its time; nice it yourself
(nice -n 5). Requires /usr/bin/python3 with python3-openems, python3-h5py, python3-scipy."""
import argparse
import math
import os
import shutil
import sys
import tempfile
import time

import numpy as np
from scipy import special
from CSXCAD import ContinuousStructure
from openEMS import openEMS
from openEMS.physical_constants import C0
from openEMS.ports import UI_data

MM = 1e-3  # the CSX drawing unit
START_DIR = os.getcwd()


def r_hat(theta, phi):
    return np.array([math.sin(theta) * math.cos(phi), math.sin(theta) * math.sin(phi),
                     math.cos(theta)])


def theta_hat(theta, phi):
    return np.array([math.cos(theta) * math.cos(phi), math.cos(theta) * math.sin(phi),
                     -math.sin(theta)])


def phi_hat(theta, phi):
    return np.array([-math.sin(phi), math.cos(phi), 0.0])


def mie_pec_backscatter(ka):
    """Monostatic RCS of a PEC sphere over pi a^2 (Mie; G. T. Ruck et al., Radar Cross Section
    Handbook, Plenum 1970, vol. 1, sec. 3.2.1.1, eq. 3.2-4; C. F. Bohren and D. R. Huffman,
    Absorption and Scattering of Light by Small Particles, Wiley 1983, sec. 4.4):
    sigma / (pi a^2) = |sum_n (-1)^n (2n + 1) (a_n - b_n)|^2 / x^2, x = ka, with the PEC
    coefficients b_n = j_n(x) / h_n(x) and a_n = [x j_n(x)]' / [x h_n(x)]', h_n = j_n + j y_n."""
    x = float(ka)
    n = np.arange(1, int(x + 4.05 * x ** (1 / 3) + 10))
    jn, yn = special.spherical_jn(n, x), special.spherical_yn(n, x)
    djn, dyn = special.spherical_jn(n, x, True), special.spherical_yn(n, x, True)
    hn, dhn = jn + 1j * yn, djn + 1j * dyn
    b = jn / hn
    a = (jn + x * djn) / (hn + x * dhn)
    s = np.sum((-1.0) ** n * (2 * n + 1) * (a - b))
    return abs(s) ** 2 / x ** 2


def uniform_lines(half_mm, dx_mm):
    """Lines -half..half with spacing dx (half a multiple of dx), symmetric about 0."""
    n = int(round(half_mm / dx_mm))
    return np.linspace(-n * dx_mm, n * dx_mm, 2 * n + 1)


def run_case(add_object, half_mm, dx_mm, tfsf_mm, nf2ff_mm, radar_theta, radar_phi, e_inc,
             f0, fc, freqs, threads, end_criteria=1e-5):
    """One FDTD run: uniform mesh of spacing dx over the box |x_i| <= half_mm[i] (PML-8 outside
    that), plane wave of polarisation e_inc arriving from the radar direction, TF/SF box
    |x_i| <= tfsf_mm[i], NF2FF box |x_i| <= nf2ff_mm[i]. Returns (E_theta, E_phi) of the scattered
    far field toward the radar at r = 1 m, and E_0(f), at freqs; and the run time."""
    sim = tempfile.mkdtemp(prefix="openems_rcs_")
    try:
        fdtd = openEMS(EndCriteria=end_criteria, NrTS=60000)
        fdtd.SetGaussExcite(f0, fc)
        # PML inside the meshed box: 8 extra cells each side so the physical region is half_mm.
        fdtd.SetBoundaryCond(["PML_8"] * 6)
        csx = ContinuousStructure()
        fdtd.SetCSX(csx)
        grid = csx.GetGrid()
        grid.SetDeltaUnit(MM)
        for i, ax in enumerate("xyz"):
            grid.SetLines(ax, uniform_lines(half_mm[i] + 8 * dx_mm, dx_mm))
        add_object(csx)
        k_dir = -r_hat(radar_theta, radar_phi)
        exc = csx.AddExcitation("plane_wave", exc_type=10, exc_val=list(e_inc))
        exc.SetPropagationDir(list(k_dir))
        exc.SetFrequency(f0)  # openEMS matches the plane wave's phase velocity to the grid here
        exc.AddBox([-t for t in tfsf_mm], list(tfsf_mm))
        nf = fdtd.CreateNF2FFBox("nf2ff", [-t for t in nf2ff_mm], list(nf2ff_mm),
                                 frequency=list(freqs))
        t0 = time.time()
        fdtd.Run(sim, cleanup=True, verbose=0, numThreads=threads)
        elapsed = time.time() - t0
        e0 = np.array(UI_data("et", sim, list(freqs)).ui_f_val[0])
        res = nf.CalcNF2FF(sim, list(freqs), [math.degrees(radar_theta)],
                           [math.degrees(radar_phi)], radius=1.0)
        e_t = np.array([res.E_theta[i][0, 0] for i in range(len(freqs))])
        e_p = np.array([res.E_phi[i][0, 0] for i in range(len(freqs))])
        return e_t, e_p, e0, elapsed
    finally:
        os.chdir(START_DIR)  # openEMS Run() changes into the simulation folder
        shutil.rmtree(sim, ignore_errors=True)


def sigma(e_scat, e0, p_amp):
    """4 pi r^2 |E_s|^2 / |E_0 p_amp|^2 at r = 1 m."""
    return 4 * math.pi * np.abs(e_scat) ** 2 / np.abs(e0 * p_amp) ** 2


def dbsm(x):
    return 10 * np.log10(np.maximum(x, 1e-30))


# --- sphere ---------------------------------------------------------------------------------
SPHERE_A_MM, SPHERE_DX_MM = 50.0, 2.5


def cmd_sphere(args):
    a = SPHERE_A_MM * MM
    kas = np.round(np.arange(1.0, 5.0001, 0.2), 3)
    freqs = kas * C0 / (2 * math.pi * a)
    f0, fc = 0.5 * (freqs[0] + freqs[-1]), 0.5 * (freqs[-1] - freqs[0]) + 0.5e9
    dx = args.dx_mm or SPHERE_DX_MM
    tfsf = SPHERE_A_MM + 4 * dx
    nfb = tfsf + 3 * dx
    half = nfb + args.pml_gap * dx

    def add(csx):
        if not args.no_object:
            csx.AddMetal("sphere").AddSphere(priority=10, center=[0, 0, 0], radius=SPHERE_A_MM)

    th, ph = math.pi / 2, 0.0
    e_t, e_p, e0, el = run_case(add, [half] * 3, dx, [tfsf] * 3, [nfb] * 3, th, ph,
                                phi_hat(th, ph), f0, fc, freqs, args.threads, args.end)
    s = sigma(e_p, e0, 1.0)
    ref = np.array([mie_pec_backscatter(k) * math.pi * a * a for k in kas])
    diff = dbsm(s) - dbsm(ref)
    with open(args.out, "w") as f:
        f.write("ka,freq_hz,rcs_dbsm,mie_dbsm,diff_db\n")
        for k, fr, x, r, d in zip(kas, freqs, dbsm(s), dbsm(ref), diff):
            f.write(f"{k:.2f},{fr:.6e},{x:.3f},{r:.3f},{d:+.3f}\n")
    lam_min = C0 / freqs[-1] / MM
    print(f"sphere a = {SPHERE_A_MM} mm, dx = {dx} mm (lambda/{lam_min / dx:.0f} at ka 5), "
          f"{el:.0f} s: |openEMS - Mie| over ka 1..5: median {np.median(np.abs(diff)):.2f} dB, "
          f"max {np.max(np.abs(diff)):.2f} dB (cross-pol {dbsm(sigma(e_t, e0, 1.0)).max():.1f} "
          f"dBsm)")


# --- plate ----------------------------------------------------------------------------------
PLATE_SIDE_MM = 100.0
PLATE_DX_MM = 1.25  # lambda/24 at 10 GHz, lambda/20 at 12 GHz (the table; 100/66 mm gave the
#                    first one, within 0.3-0.45 dB median of it: tests/data/openems_plate)
PLATE_FREQS = (9e9, 10e9, 12e9)


def plate_geometry(with_plate, dx):
    if abs(PLATE_SIDE_MM / 2 / dx - round(PLATE_SIDE_MM / 2 / dx)) > 1e-9:
        sys.exit(f"--dx-mm {dx}: the plate's half side {PLATE_SIDE_MM / 2} mm must be a multiple")
    h = PLATE_SIDE_MM / 2
    tfsf = [h + 4 * dx, h + 4 * dx, 4 * dx]
    nfb = [t + 3 * dx for t in tfsf]
    half = [n + 4 * dx for n in nfb]

    def add(csx):
        if with_plate:
            # Zero thickness: a box flat in z on the mesh plane z = 0, edges on mesh lines.
            csx.AddMetal("plate").AddBox(priority=10, start=[-h, -h, 0], stop=[h, h, 0])

    return add, half, tfsf, nfb


def parse_sweep(text):
    p = [float(v) for v in text.split(":")]
    if len(p) == 1:
        return [p[0]]
    return list(np.linspace(p[0], p[1], int(p[2])))


def cmd_plate(args):
    dx = args.dx_mm or PLATE_DX_MM
    add, half, tfsf, nfb = plate_geometry(not args.no_object, dx)
    freqs = np.array(PLATE_FREQS)
    f0, fc = 10.5e9, 4.5e9  # 6..15 GHz at -20 dB
    rows, total = [], 0.0
    for theta_deg in parse_sweep(args.theta_deg):
        th, ph = math.radians(theta_deg), 0.0
        h_hat, v_hat = phi_hat(th, ph), theta_hat(th, ph)
        if args.separate_pol:
            runs = [("HH", h_hat, 1), ("VV", v_hat, 0)]
        else:
            runs = [("both", h_hat + v_hat, None)]
        for name, e_inc, which in runs:
            e_t, e_p, e0, el = run_case(add, half, dx, tfsf, nfb, th, ph, e_inc,
                                        f0, fc, freqs, args.threads, args.end)
            total += el
            s_hh, s_vv = sigma(e_p, e0, 1.0), sigma(e_t, e0, 1.0)
            for i, fr in enumerate(freqs):
                if which in (None, 1):
                    rows.append((fr, theta_deg, "HH", dbsm(s_hh[i])))
                if which in (None, 0):
                    rows.append((fr, theta_deg, "VV", dbsm(s_vv[i])))
            print(f"theta {theta_deg:5.1f} deg ({name}, {el:.0f} s): "
                  + ", ".join(f"{fr / 1e9:g} GHz HH {dbsm(s_hh[i]):7.2f} VV {dbsm(s_vv[i]):7.2f}"
                              for i, fr in enumerate(freqs)), flush=True)
    rows.sort(key=lambda r: (r[0], r[2], r[1]))
    with open(args.out, "w") as f:
        f.write("freq_hz,theta_deg,phi_deg,pol,rcs_dbsm\n")
        for fr, theta_deg, pol, v in rows:
            f.write(f"{fr:.6e},{theta_deg:g},0,{pol},{v:.3f}\n")
    a = (PLATE_SIDE_MM * MM) ** 2
    print(f"total FDTD time {total:.0f} s; closed form 4 pi A^2 / lambda^2 at normal: "
          + ", ".join(f"{fr / 1e9:g} GHz {dbsm(4 * math.pi * a * a * (fr / C0) ** 2):.2f} dBsm"
                      for fr in freqs))


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("what", choices=["sphere", "plate"])
    ap.add_argument("out")
    ap.add_argument("--threads", type=int, default=1)
    ap.add_argument("--theta-deg", default="0:85:35", help="plate: START:STOP:N or A")
    ap.add_argument("--separate-pol", action="store_true")
    ap.add_argument("--dx-mm", type=float, default=0.0, help="mesh step (default: the table's)")
    ap.add_argument("--pml-gap", type=int, default=4, help="cells from the NF2FF box to the PML")
    ap.add_argument("--end", type=float, default=1e-5, help="openEMS EndCriteria (energy)")
    ap.add_argument("--no-object", action="store_true", help="empty set-up: TF/SF leakage floor")
    args = ap.parse_args()
    if args.what == "sphere":
        cmd_sphere(args)
    else:
        cmd_plate(args)


if __name__ == "__main__":
    sys.exit(main())
