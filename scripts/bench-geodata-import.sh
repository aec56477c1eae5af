#!/usr/bin/env bash
# Timed import of the issue's database shape (docs/performance.md, "scene import"): a 5 x 7 km
# central area at 5 m inside a 20 x 20 km surround at 30 m, from two synthetic GeoTIFF DEMs
# (UTM 31N around 43.45 N, 1.30 E; written here with GDAL's Python bindings, Debian
# python3-gdal), then the time to load the result (glTF and BVHs, bench/bench_scene), against
# the generated terrain's, with a second import of the generated terrain's size.
#
# Usage: scripts/bench-geodata-import.sh [BUILD_DIR]   (default: build)
#        BENCH_SCENE=OTHER/bench_scene scripts/bench-geodata-import.sh   (another build's loader)
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
echo "== import of the generated terrain's size (5 x 7 km at 20 m, 20 x 20 km at 120 m)"
"$exe" scene import --dem "$tmp/central_5m.tif" --surround-dem "$tmp/surround_30m.tif" \
  --anchor 43.45,1.30 --central 5000,7000 --cell-m 20 --surround-m 20000 --surround-cell-m 120 \
  --out "$tmp/imported_20m.glb" -q 2>/dev/null | tail -1
echo "== load: load_gltf + every BVH (what run, image and sar do), in one bench_scene run each:"
echo "   the generated terrain (BM_LoadAndBuildAllLevelsGlb) against an imported one (BM_LoadAndBuildGlbFile)"
# BENCH_SCENE: one bench_scene or several (space-separated, e.g. a build before a change and
# one after): each file is timed by each binary in turn, twice (A B A B), so that a shared
# machine's load falls on all alike.
benches="${BENCH_SCENE:-$build/bench/bench_scene}"
for glb in imported_20m.glb imported.glb; do
  for round in 1 2; do
    for bench in $benches; do
      echo "-- $glb, round $round, $bench"
      RADAR_EMU_BENCH_GLB="$tmp/$glb" "$bench" --benchmark_filter='LoadAndBuild(AllLevels|GlbFile)' \
        2>/dev/null | grep -E '^BM_' | awk '{print $1, $2, $3, $NF}'
    done
  done
done
