#!/usr/bin/python3
"""radar-emu scene gen / info / preview end to end through the real binary:
  - `scene gen terrain --seed 7` twice gives byte-identical files, another seed another file;
  - the .glb read here with struct + json (GLB container, glTF 2.0 spec section 4.4) agrees with
    `scene info --json`: objects, triangles per LOD level and per material summed from the index
    accessors and node extras;
  - the counts are the seed paper's: 190,000-210,000 polygons in the central area at full detail
    (LOD level 0 + the other central objects), 6,000-8,000 in the surround; level 0 is 140 tiles
    of 24 x 24 cells, levels 1 and 2 a quarter and a sixteenth of it;
  - every feature class is there with its material, and every material name is one of the radar
    catalogue's (as `radar-emu sigma0 --help` lists them);
  - `scene preview` writes an RGB PNG of the requested size (header and IDAT read with
    struct + zlib) that shows more than sky.
Usage: check_scene_cli.py RADAR_EMU WORK_DIR"""
import json
import os
import re
import struct
import sys

from cli_check import check, finish, runner
import zlib

exe, work = sys.argv[1], sys.argv[2]
os.makedirs(work, exist_ok=True)
run = runner(exe)


def read_glb(path):
    """The JSON chunk and the binary chunk of a GLB file (glTF 2.0 spec, section 4.4)."""
    data = open(path, "rb").read()
    magic, version, length = struct.unpack_from("<III", data, 0)
    check(magic == 0x46546C67 and version == 2 and length == len(data), f"{path}: GLB header")
    json_len, json_type = struct.unpack_from("<II", data, 12)
    check(json_type == 0x4E4F534A, f"{path}: first chunk is JSON")
    doc = json.loads(data[20:20 + json_len])
    off = 20 + json_len
    bin_len, bin_type = struct.unpack_from("<II", data, off)
    check(bin_type == 0x004E4942, f"{path}: second chunk is BIN")
    return doc, data[off + 8:off + 8 + bin_len]


# --- generation: deterministic -----------------------------------------------------------------
t1, t2, t3 = (os.path.join(work, n) for n in ("t.glb", "t_again.glb", "t8.glb"))
out = run("scene", "gen", "terrain", "--seed", "7", "--out", t1).stdout
print(out.strip())
check(re.search(r"generated in [0-9.]+ s", out) is not None, "gen prints the time taken")
run("scene", "gen", "terrain", "--seed", "7", "--out", t2, "-q")
run("scene", "gen", "terrain", "--seed", "8", "--out", t3, "-q")
b1, b2, b3 = (open(p, "rb").read() for p in (t1, t2, t3))
check(b1 == b2, "same seed, same bytes")
check(b1 != b3, "another seed, another file")

# --- scene info against the file itself ---------------------------------------------------------
info = json.loads(run("scene", "info", t1, "--json").stdout)
doc, _ = read_glb(t1)
per_level, per_material, per_area = {}, {}, {}
kinds = {}
for node in doc["nodes"]:
    if "mesh" not in node:
        continue
    extras = node.get("extras", {}).get("radar_emu", {})
    group = extras.get("lod_group", -1)
    level = "none" if group < 0 else str(extras.get("lod_level", 0))
    area = extras.get("area", "none")
    kind = re.sub(r"(_[^_]*\d[^_]*)+$", "", node["name"])
    kinds[kind] = kinds.get(kind, 0) + 1
    for prim in doc["meshes"][node["mesh"]]["primitives"]:
        n = doc["accessors"][prim["indices"]]["count"] // 3
        per_level[level] = per_level.get(level, 0) + n
        if level in ("none", "0"):
            mat = doc["materials"][prim["material"]]
            name = mat.get("extras", {}).get("radar_emu", {}).get("radar_material", mat["name"])
            per_material[name] = per_material.get(name, 0) + n
            per_area[area] = per_area.get(area, 0) + n
check(info["objects"] == sum(kinds.values()), "objects")
check(info["polygons_by_lod_level"] == per_level,
      f"per LOD level: info {info['polygons_by_lod_level']} vs file {per_level}")
check(info["polygons_total"] == sum(per_level.values()), "polygons_total: every level")
check({k: v for k, v in info["polygons_by_material"].items() if v} == per_material,
      "per material (full detail)")
check(info["polygons_by_area"] == per_area, f"per area: {info['polygons_by_area']} vs {per_area}")
check(info["objects_by_kind"] == kinds, f"objects by kind {info['objects_by_kind']} vs {kinds}")

# --- the paper's figures --------------------------------------------------------------------------
central, surround = info["polygons_by_area"]["central"], info["polygons_by_area"]["surround"]
print(f"central {central}, surround {surround}, all levels {info['polygons_total']}")
check(190_000 <= central <= 210_000, f"central area {central} polygons (paper: 200,000)")
check(6_000 <= surround <= 8_000, f"surround {surround} polygons (paper: 7,000)")
lv = info["polygons_by_lod_level"]
check(lv["0"] == 140 * 24 * 24 * 2, "level 0: 140 tiles of 24 x 24 cells")
check(lv["1"] * 4 == lv["0"] and lv["2"] * 16 == lv["0"], "levels 1, 2: 1/4 and 1/16 of level 0")
check(info["lod_groups"] == 140, "140 tiles")
lo, hi = info["extent_m"]["min"], info["extent_m"]["max"]
check(abs(lo[0] + 10_000) < 20 and abs(hi[0] - 10_000) < 20, "extent: 20 km east-west")
check(abs(lo[1] + 10_000) < 20 and abs(hi[1] - 10_000) < 20, "extent: 20 km south-north")
check(10 < hi[2] - lo[2] < 120, f"relief {hi[2] - lo[2]:.1f} m: undulating")
lat, lon, _ = info["anchor_deg_m"]
check(abs(lat - 43.45) < 1e-6 and abs(lon - 1.30) < 1e-6, "anchor near Toulouse")

# --- every feature class with its material ----------------------------------------------------------
k = info["objects_by_kind"]
for kind, least in (("terrain", 420), ("road", 3), ("river", 1), ("lake", 1), ("bridge", 1),
                    ("building", 20), ("pylon", 8), ("tree", 500), ("surround_terrain", 1),
                    ("surround_lake", 1), ("surround_river", 1)):
    check(k.get(kind, 0) >= least, f"{kind}: {k.get(kind, 0)} objects, at least {least}")
check(k.get("wire", 0) == 3 * (k.get("pylon", 0) - 1), "three wires a span")
m = info["polygons_by_material"]
for name in ("crops", "grass", "forest", "soil_dry", "soil_wet", "urban", "water", "asphalt",
             "concrete", "metal"):
    check(m.get(name, 0) > 0, f"material {name} used")
help_text = run("sigma0", "--help").stdout
catalogue = re.search(r"Catalogue material: ([a-z_, ]+)", help_text).group(1).split(", ")
for name in m:
    check(name in catalogue, f"material {name} is in the radar catalogue {catalogue}")

text = run("scene", "info", t1).stdout
check("full detail" in text and "central" in text, "the table says what it counts")

# --- preview ---------------------------------------------------------------------------------------
png = os.path.join(work, "view.png")
run("scene", "preview", t1, "--out", png, "--camera", "-1500,-4500,900", "--look-at", "0,-1000,0",
    "--fov-deg", "50", "--width", "320", "--height", "200", "-q")
data = open(png, "rb").read()
check(data[:8] == b"\x89PNG\r\n\x1a\n", "PNG signature")
w, h, depth, colour = struct.unpack(">IIBB", data[16:26])
check((w, h, depth, colour) == (320, 200, 8, 2), f"PNG {w} x {h}, depth {depth}, colour {colour}")
idat, pos = b"", 8
while pos < len(data):
    n, kind = struct.unpack(">I4s", data[pos:pos + 8])
    if kind == b"IDAT":
        idat += data[pos + 8:pos + 8 + n]
    pos += 12 + n
raw = zlib.decompress(idat)
check(len(raw) == h * (1 + 3 * w), "IDAT holds 200 rows of 320 RGB pixels")
# Unfilter the rows (PNG spec section 9) and count distinct colours: ground, water, sky...
rows, prev = [], bytearray(3 * w)
for y in range(h):
    f, line = raw[y * (1 + 3 * w)], bytearray(raw[y * (1 + 3 * w) + 1:(y + 1) * (1 + 3 * w)])
    for i in range(len(line)):
        a = line[i - 3] if i >= 3 else 0
        b = prev[i]
        c = prev[i - 3] if i >= 3 else 0
        if f == 1:
            line[i] = (line[i] + a) & 255
        elif f == 2:
            line[i] = (line[i] + b) & 255
        elif f == 3:
            line[i] = (line[i] + (a + b) // 2) & 255
        elif f == 4:
            p = a + b - c
            pa, pb, pc = abs(p - a), abs(p - b), abs(p - c)
            line[i] = (line[i] + (a if pa <= pb and pa <= pc else b if pb <= pc else c)) & 255
    rows.append(bytes(line))
    prev = line
colours = {r[i:i + 3] for r in rows for i in range(0, len(r), 3)}
check(len(colours) > 50, f"the preview shows a scene ({len(colours)} colours)")

finish()
print("scene cli: ok")
