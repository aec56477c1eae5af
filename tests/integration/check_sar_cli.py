#!/usr/bin/python3
"""radar-emu sar end to end through the real binary on examples/sar_trihedrals.toml (three
isolated square trihedrals in free space, the SBR tracer's echoes), unweighted and with a Hamming
taper; checked here against closed forms recomputed in Python and against gdalinfo (GDAL's own
reader, an independent tool):
  - point-target impulse response (the definitions of isce3's point_target_info: -3 dB width,
    PSLR, ISLR with the main lobe between the first nulls and 10 main-lobe half-widths of
    sidelobes each side): range resolution within 5 % of 0.886 c / (2B) (Hamming 1.30), azimuth
    within 5 % of 0.886 lambda / (2 Theta) with Theta = lambda / (2 R0 theta_s) the processed
    integration angle, PSLR within 0.5 dB of -13.26 dB (Hamming -42.7 dB; Harris 1978), ISLR
    within 1 dB of the same windows applied to the continuous sinc (Hamming: 0.54 sinc(x) +
    0.23 (sinc(x-1) + sinc(x+1))) integrated here by the midpoint rule; the peak within 0.25
    resolution cell of the trihedral's corner; integrated energy (unweighted) within 0.5 dB of
    the square trihedral's closed form sigma = 12 pi a^4 / lambda^2 on its axis (the canonical
    targets of docs/validation.md);
  - gdalinfo reads image.tif as a CFloat32 GeoTIFF in a transverse Mercator at the scene anchor,
    its geotransform puts each trihedral's world position at the pixel the processing expected,
    and raw.tif as CFloat32 pulses x samples with ground control points;
  - a trihedral receding at 1 m/s images -R v_r / V along track off its place (Raney 1971),
    within 1 m (about a resolution cell);
  - image.png and irf.png are figures with their axis and colour-bar labels in units
    (figure_checks.py).
Usage: check_sar_cli.py RADAR_EMU SOURCE_DIR WORK_DIR"""
import json
import math
import os
import subprocess
import sys

from cli_check import check, finish, runner
from figure_checks import check_figure

exe, src, work = sys.argv[1], sys.argv[2], sys.argv[3]
os.makedirs(work, exist_ok=True)
run = runner(exe)
C = 299792458.0
example = os.path.join(src, "examples", "sar_trihedrals.toml")
with open(example) as f:
    text = f.read()


def key(name):
    for line in text.splitlines():
        if line.split("=")[0].strip() == name:
            return float(line.split("=")[1].split("#")[0])
    sys.exit(f"{name} not in {example}")


B, fc, H = key("bandwidth_hz"), key("carrier_hz"), key("altitude_m")
inc, syn, a = math.radians(key("incidence_deg")), math.radians(key("synthetic_beamwidth_deg")), 0.3
lam = C / fc
R0 = H / math.cos(inc)
theta = lam / (2 * R0 * syn)
rcs_db = 10 * math.log10(12 * math.pi * a ** 4 / lam ** 2)


def sinc(x):
    return 1.0 if x == 0 else math.sin(math.pi * x) / (math.pi * x)


def islr_theory(hamming):
    x0, dx = (2.0 if hamming else 1.0), 1e-3
    main = side = 0.0
    x = dx / 2
    while x < 11 * x0:
        h = 0.54 * sinc(x) + 0.23 * (sinc(x - 1) + sinc(x + 1)) if hamming else sinc(x)
        if x < x0:
            main += h * h
        else:
            side += h * h
        x += dx
    return 10 * math.log10(side / main)


def gdalinfo(path):
    r = subprocess.run(["gdalinfo", "-json", path], capture_output=True, text=True)
    check(r.returncode == 0, f"gdalinfo {path}: {r.stderr}")
    return json.loads(r.stdout) if r.returncode == 0 else {}


for taper in ("none", "hamming"):
    hamming = taper == "hamming"
    case = os.path.join(work, f"sar_{taper}.toml")
    with open(case, "w") as f:
        f.write(text.replace('taper = "none"', f'taper = "{taper}"'))
    out = os.path.join(work, taper)
    run("sar", case, "--out", out, "-q")
    with open(os.path.join(out, "sar.json")) as f:
        j = json.load(f)
    k = 1.30 if hamming else 0.886
    res_r, res_a = k * C / (2 * B), k * lam / (2 * theta)
    pslr = -42.7 if hamming else -13.26
    islr = islr_theory(hamming)
    targets = [t for t in j["point_targets"] if "range_resolution_m" in t]
    check(len(targets) == 3, f"{taper}: three static trihedrals measured")
    # The mover: imaged -R v_r / V along track off its place (Raney 1971), R and v_r at the time
    # the platform passes it, from the case's geometry (track on the +y side, flying +x).
    mover = [t for t in j["point_targets"] if t["name"] == "mover"]
    check(len(mover) == 1 and "measured_azimuth_shift_m" in mover[0], f"{taper}: the mover")
    if mover and "measured_azimuth_shift_m" in mover[0]:
        m = mover[0]
        V = j["platform"]["speed_mps"]
        x0, y_track = j["platform"]["start_position_m"][0], j["platform"]["start_position_m"][1]
        tb = (m["position_m"][0] - x0) / V
        yb = m["position_m"][1] - 1.0 * tb  # velocity (0, -1, 0) m/s
        R = math.hypot(y_track - yb, H)
        v_r = (y_track - yb) / R  # the unit line of sight from the radar, dotted with (0, -1, 0)
        shift = -R * v_r / V
        print(f"{taper} mover: shift {m['measured_azimuth_shift_m']:.2f} m (theory {shift:.2f})")
        check(abs(m["measured_azimuth_shift_m"] - shift) < 1.0, f"{taper}: mover's azimuth shift")
        # Its zero-Doppler place is one beamwidth off broadside: two-way Gaussian gain
        # -8 ln2 (a / theta)^2 nepers = -24.08 (a / theta)^2 dB, in the beam (above -60 dB).
        a = abs(shift) / R / math.radians(j["antenna"]["azimuth_beamwidth_deg"])
        check(m["zero_doppler_in_beam"] and abs(m["zero_doppler_two_way_gain_db"] +
                                                24.0824 * a * a) < 0.05,
              f"{taper}: the mover's zero-Doppler gain {m['zero_doppler_two_way_gain_db']}")
        check(abs(m["measured_ground_range_offset_m"]) < 2.5, f"{taper}: mover's range")
    for t in targets:
        w = f"{taper} {t['name']}"
        print(f"{w}: res {t['range_resolution_m']:.3f}/{t['azimuth_resolution_m']:.3f} m "
              f"(theory {res_r:.3f}/{res_a:.3f}), PSLR {t['range_pslr_db']:.2f}/"
              f"{t['azimuth_pslr_db']:.2f} dB, ISLR {t['range_islr_db']:.2f}/"
              f"{t['azimuth_islr_db']:.2f} dB (theory {islr:.2f}), offset "
              f"{t['range_offset_m']:.3f}/{t['azimuth_offset_m']:.3f} m, energy "
              f"{t['integrated_energy_dbsm']:.2f} dBsm (theory {rcs_db:.2f})")
        check(abs(t["range_resolution_m"] / res_r - 1) < 0.05, f"{w}: range resolution")
        check(abs(t["azimuth_resolution_m"] / res_a - 1) < 0.05, f"{w}: azimuth resolution")
        for axis in ("range", "azimuth"):
            check(abs(t[f"{axis}_pslr_db"] - pslr) < 0.5, f"{w}: {axis} PSLR")
            check(abs(t[f"{axis}_islr_db"] - islr) < 1.0, f"{w}: {axis} ISLR")
        check(abs(t["range_offset_m"]) < 0.25 * res_r, f"{w}: range position")
        check(abs(t["azimuth_offset_m"]) < 0.25 * res_a, f"{w}: azimuth position")
        if not hamming:
            check(abs(t["integrated_energy_dbsm"] - rcs_db) < 0.5, f"{w}: energy against RCS")

    info = gdalinfo(os.path.join(out, "image.tif"))
    rows, cols = j["processing"]["image_rows"], j["processing"]["image_cols"]
    check(info.get("size") == [cols, rows], f"{taper}: image.tif size {info.get('size')}")
    check(info.get("bands", [{}])[0].get("type") == "CFloat32", f"{taper}: image.tif CFloat32")
    wkt = info.get("coordinateSystem", {}).get("wkt", "")
    check("Transverse Mercator" in wkt and "43.6" in wkt, f"{taper}: image.tif CRS {wkt[:80]}")
    gt = info.get("geoTransform", [0] * 6)
    for t in targets:
        x, y = t["position_m"][0], t["position_m"][1]  # static: their place at every pulse
        # Invert X = gt0 + c gt1 + r gt2, Y = gt3 + c gt4 + r gt5 (pixel corners), then centres.
        det = gt[1] * gt[5] - gt[2] * gt[4]
        c = ((x - gt[0]) * gt[5] - (y - gt[3]) * gt[2]) / det - 0.5
        r = ((y - gt[3]) * gt[1] - (x - gt[0]) * gt[4]) / det - 0.5
        er, ec = t["expected_pixel"]
        check(abs(r - er) < 1e-6 and abs(c - ec) < 1e-6,
              f"{taper} {t['name']}: geotransform puts it at ({r:.3f}, {c:.3f}), "
              f"processing at ({er:.3f}, {ec:.3f})")
    raw = gdalinfo(os.path.join(out, "raw.tif"))
    check(raw.get("size", [0, 0])[1] == j["platform"]["pulses"], f"{taper}: raw.tif has a line "
          "per pulse")
    check(raw.get("bands", [{}])[0].get("type") == "CFloat32", f"{taper}: raw.tif CFloat32")
    check(len(raw.get("gcps", {}).get("gcpList", [])) >= 4, f"{taper}: raw.tif GCPs")
    # The figures (figure_checks.py): the grey image in metres with its colour bar [dB], the
    # impulse response's cuts.
    for f in check_figure(os.path.join(out, "image.png"), colour_bars=1,
                          texts=["ground range from the near edge [m]", "pixel power [dB]"]):
        check(False, f"{taper}: {f}")
    for f in check_figure(os.path.join(out, "irf.png"), size=(1000, 640), colour_bars=0,
                          texts=["power [dB]"]):
        check(False, f"{taper}: {f}")
finish()
