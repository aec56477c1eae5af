#!/usr/bin/env bash
# Timed import of the issue's database shape (docs/performance.md, "scene import"): a 5 x 7 km
# central area at 5 m inside a 20 x 20 km surround at 30 m, from two synthetic GeoTIFF DEMs
# (UTM 31N around 43.45 N, 1.30 E; written here with GDAL's Python bindings, Debian
# python3-gdal), then the time to load the result, against the generated terrain's.
#
# Usage: scripts/bench-geodata-import.sh [BUILD_DIR]   (default: build)
set -euo pipefail
here="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
build="${1:-$here/build}"
exe="$build/app/radar-emu"
tmp="$(mktemp -d)"
trap 'rm -rf "$tmp"' EXIT

/usr/bin/python3 - "$tmp" <<'PY'
import sys, numpy as np
from osgeo import gdal, osr
gdal.UseExceptions()
out = sys.argv[1]
srs = osr.SpatialReference(); srs.ImportFromEPSG(32631)
t = osr.CoordinateTransformation(osr.SpatialReference(), srs) if False else None
# Anchor 43.45 N, 1.30 E in UTM 31N.
wgs = osr.SpatialReference(); wgs.ImportFromEPSG(4326)
wgs.SetAxisMappingStrategy(osr.OAMS_TRADITIONAL_GIS_ORDER)
srs.SetAxisMappingStrategy(osr.OAMS_TRADITIONAL_GIS_ORDER)
e0, n0, _ = osr.CoordinateTransformation(wgs, srs).TransformPoint(1.30, 43.45)
def dem(name, half_e, half_n, step):
    w, h = int(2 * half_e / step), int(2 * half_n / step)
    x = e0 - half_e + step * (np.arange(w) + 0.5)
    y = n0 + half_n - step * (np.arange(h) + 0.5)
    X, Y = np.meshgrid(x - e0, y - n0)
    z = 200 + 15 * np.sin(X / 2500.0) * np.cos(Y / 3100.0) + 4 * np.sin((X + Y) / 400.0)
    ds = gdal.GetDriverByName("GTiff").Create(f"{out}/{name}", w, h, 1, gdal.GDT_Float32,
                                                ["TILED=YES", "COMPRESS=DEFLATE"])
    ds.SetGeoTransform([e0 - half_e, step, 0, n0 + half_n, 0, -step])
    ds.SetSpatialRef(srs)
    ds.GetRasterBand(1).WriteArray(z.astype(np.float32))
    ds = None
    print(f"{name}: {w} x {h} pixels at {step} m")
dem("central_5m.tif", 2700, 3700, 5.0)
dem("surround_30m.tif", 10600, 10600, 30.0)
PY

echo "== import (5 x 7 km at 5 m, 20 x 20 km at 30 m)"
/usr/bin/time -v "$exe" scene import --dem "$tmp/central_5m.tif" --surround-dem "$tmp/surround_30m.tif" \
  --anchor 43.45,1.30 --central 5000,7000 --cell-m 5 --surround-m 20000 --surround-cell-m 30 \
  --out "$tmp/imported.glb" 2>"$tmp/time.txt" | tail -4
grep -E "Elapsed|Maximum resident" "$tmp/time.txt"
echo "== load (scene info reads the glTF; Scene builds the BVHs in run/image)"
/usr/bin/time -v "$exe" scene info "$tmp/imported.glb" 2>"$tmp/t2.txt" | grep -E "polygons|objects" | head -3
grep -E "Elapsed|Maximum resident" "$tmp/t2.txt"
"$exe" scene gen terrain --out "$tmp/generated.glb" -q
/usr/bin/time -v "$exe" scene info "$tmp/generated.glb" 2>"$tmp/t3.txt" | grep -E "polygons|objects" | head -3
grep -E "Elapsed|Maximum resident" "$tmp/t3.txt"
