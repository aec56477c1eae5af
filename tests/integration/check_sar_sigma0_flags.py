#!/usr/bin/python3
"""Issue 28 end to end: `radar-emu sar` says where its clutter read sigma0 values the catalogue
flags (outside a model's validity, extrapolated or assumed), and says nothing where it did not.

The case is examples/sar_trihedrals.toml (35 GHz, 63 deg incidence at the image centre) over a
flat ground of one material with clutter on and no targets. The expected flags come from
`radar-emu sigma0` (the catalogue's own CLI, not the SAR path) over 50-76 deg incidence, wider
than the image's: water (the NRL curve) is flagged nowhere there, grass (assumed at 35 GHz)
everywhere. Checked: sar.json `sigma0_validity`, the stderr warning, and through gdalinfo (GDAL's
own reader) image.tif's SIGMA0_VALIDITY metadata and bit 16 of its mask band (band 2).
Usage: check_sar_sigma0_flags.py RADAR_EMU SOURCE_DIR WORK_DIR"""
import csv
import json
import os
import subprocess
import sys

from cli_check import check, finish, runner

exe, src, work = sys.argv[1], sys.argv[2], sys.argv[3]
os.makedirs(work, exist_ok=True)
run = runner(exe)
with open(os.path.join(src, "examples", "sar_trihedrals.toml")) as f:
    text = f.read()
text = text[: text.index("[[scene.target]]")]  # the flat ground alone


def catalogue_flags(material):
    out = os.path.join(work, f"sigma0_{material}.csv")
    run("sigma0", "--material", material, "--freq-hz", "35e9", "--pol", "VV", "--theta-deg",
        "50:76:27", "--out", out)
    with open(out) as f:
        rows = list(csv.DictReader(f))
    flags = 0
    for r in rows:
        flags |= int(r["flags"])
    return flags, [int(r["flags"]) for r in rows]


def gdalinfo(path):
    r = subprocess.run(["gdalinfo", "-json", "-mm", path], capture_output=True, text=True)
    check(r.returncode == 0, f"gdalinfo {path}: {r.stderr}")
    return json.loads(r.stdout) if r.returncode == 0 else {}


for material in ("water", "grass"):
    flags, per_angle = catalogue_flags(material)
    case = os.path.join(work, f"sar_{material}.toml")
    with open(case, "w") as f:
        f.write(text.replace('ground_material = "none"',
                             f'ground_material = "{material}"\nclutter = true\nclutter_cell_m = 10.0'))
    out = os.path.join(work, material)
    r = run("sar", case, "--out", out, "-q")
    with open(os.path.join(out, "sar.json")) as f:
        v = json.load(f)["sigma0_validity"]
    info = gdalinfo(os.path.join(out, "image.tif"))
    md = info.get("metadata", {}).get("", {})
    bands = info.get("bands", [])
    mask = bands[1] if len(bands) > 1 else {}
    warned = "sigma0 outside model validity" in r.stderr
    print(f"{material}: catalogue flags {flags} over 50-76 deg; sar.json flagged {v['flagged']} "
          f"flags {v['flags']}, {v['flagged_pixels']} of {v['terrain_pixels']} pixels; "
          f"SIGMA0_VALIDITY {md.get('SIGMA0_VALIDITY')!r}; mask band {mask.get('computedMin')}.."
          f"{mask.get('computedMax')}")
    check(v["terrain_pixels"] > 0, f"{material}: terrain pixels in sar.json")
    if material == "water":
        check(flags == 0, f"water at 35 GHz, 50-76 deg: the catalogue flags {per_angle}")
        check(not v["flagged"] and v["flags"] == 0 and v["flagged_pixels"] == 0 and
              v["materials"] == [] and v["flagged_patch_fraction"] == 0.0,
              f"water: sar.json says nothing is flagged ({v})")
        check(not warned, f"water: no warning on stderr ({r.stderr!r})")
        check(md.get("SIGMA0_VALIDITY") == "valid", "water: image.tif SIGMA0_VALIDITY = valid")
        check(mask.get("computedMax", 99) < 16, "water: no pixel has mask bit 16")
    else:
        check(flags != 0 and all(a == flags for a in per_angle),
              f"grass at 35 GHz, 50-76 deg: the catalogue flags every angle alike {per_angle}")
        check(v["flagged"] and v["flags"] == flags, f"grass: sar.json flags {v['flags']}, "
              f"catalogue {flags}")
        check(v["flagged_pixels"] == v["terrain_pixels"] and v["flagged_patch_fraction"] == 1.0,
              "grass: every terrain pixel and patch flagged")
        check(len(v["materials"]) == 1 and v["materials"][0].startswith("grass at 35 GHz, "),
              f"grass: one line naming the material and band {v['materials']}")
        check(warned and "grass at 35 GHz" in r.stderr, f"grass: the warning on stderr "
              f"({r.stderr!r})")
        check(md.get("SIGMA0_VALIDITY", "").startswith("outside model validity"),
              f"grass: image.tif SIGMA0_VALIDITY {md.get('SIGMA0_VALIDITY')!r}")
        check(md.get("SIGMA0_FLAGGED_1", "").startswith("grass at 35 GHz"),
              "grass: image.tif SIGMA0_FLAGGED_1")
        check(mask.get("computedMin", 0) >= 16, "grass: every pixel has mask bit 16")
finish()
