#!/usr/bin/env bash
# Regenerates the figures in docs/img that the tools draw (docs/plotting.md: matplotlib, PNG with
# an SVG beside it; only the PNGs are kept in docs/img), with the commands the docs quote.
# Usage: scripts/make-doc-figures.sh [BUILD_DIR] [--slow] [--images]
#   --slow: also the 25 000-facet vehicle (RCS over a turn, range profile, ISAR; ~15 min on 2 cores).
#   --images: also the EV and SAR images, the SAR impulse responses and the full tradeoff run
#     (its summary and frame charts: their x axis is a measured cost, docs/performance.md);
#     ~10 min on 2 cores.
# Not regenerated: the scene previews and the live view's screenshot (not charts).
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
build="$root/build"
slow=0
images=0
for a in "$@"; do
  case "$a" in
    --slow) slow=1 ;;
    --images) images=1 ;;
    *) build="$a" ;;
  esac
done
build="$(cd "$build" 2>/dev/null && pwd || echo "$build")"  # absolute: the script changes folder
exe="$build/app/radar-emu"
[ -x "$exe" ] || { echo "make-doc-figures: $exe not found (build first: scripts/build.sh)" >&2; exit 1; }
img="$root/docs/img"
work="$(mktemp -d)"
trap 'rm -rf "$work"' EXIT
cd "$work"
set -x
"$exe" atten --freq-hz 1e9:200e9:400 --rain-mmh 10 --fog-gm3 0.05 --out atten.csv \
  --plot "$img/atten_1_200ghz.png" -q
"$exe" ambiguity --out amb -q
cp amb/ambiguity.png "$img/ambiguity_default_lfm.png"
"$exe" sigma0 --material asphalt --freq-hz 94e9 --theta-deg 0:88:89 --out s.csv \
  --plot "$img/sigma0_asphalt_94ghz.png" -q 2>/dev/null
bist=(--eps-r "5,0.09" --rms-height-m 0.0005 --corr-length-m 0.005 --freq-hz 94e9 --model iem
      --theta-s-deg 0:88:89 --phi-s-deg 0)
"$exe" sigma0 "${bist[@]}" --theta-deg 40 --out b.csv \
  --plot "$img/sigma0_bistatic_asphalt_94ghz.png" -q 2>/dev/null
"$exe" sigma0 "${bist[@]}" --theta-deg 10:70:31 --pol VV,HH --out bm.csv \
  --plot "$img/sigma0_bistatic_map_94ghz.png" -q 2>/dev/null
"$exe" scene target trihedral-tri --a-m 0.3 --out tri.stl > /dev/null
"$exe" rcs --mesh tri.stl --freq-hz 10e9 --theta-deg 0:90:361 --phi-deg 45 --pol HH,VV,HV \
  --out tri.csv --plot "$img/trihedral_rcs.png" -q 2>/dev/null
"$exe" rcs --mesh tri.stl --freq-sweep-hz 8e9:12e9:21 --theta-deg 0:90:91 --phi-deg 45 \
  --pol HH,VV --out trimap.csv --plot "$img/trihedral_rcs_map.png" -q 2>/dev/null
"$exe" profile --mesh tri.stl --freq-sweep-hz 9e9:11e9:200 --theta-deg 54.7356 \
  --phi-deg 40:50:64 --out profile.csv --plot profile.png --isar-plot "$img/trihedral_isar.png" \
  -q 2>/dev/null
"$exe" tradeoff --cases sphere,grazing,iem --out trade -q
cp trade/tradeoff_sphere.png trade/tradeoff_grazing.png trade/tradeoff_iem.png "$img/"
"$exe" sigma0 --catalogue-chart "$img/sigma0_catalogue.png" \
  --chart-materials grass,asphalt,forest,crops,water \
  --points "$root/tests/data/sigma0_catalogue_points.csv" -q
# The openEMS and Austin plate overlays (docs/validation.md): their check scripts draw them from
# the tables.
/usr/bin/python3 "$root/tests/integration/check_openems_plate.py" "$exe" "$work/openems" \
  --charts "$img" > /dev/null
/usr/bin/python3 "$root/tests/integration/check_austin_rcs.py" "$exe" "$work/austin" \
  --charts "$img" > /dev/null
if [ "$slow" = 1 ]; then
  "$exe" scene target vehicle --a-m 7 --b-m 3.5 --c-m 2.5 --out veh.glb > /dev/null
  "$exe" rcs --mesh veh.glb --freq-hz 35e9 --theta-deg 80 --phi-deg 0:360:361 \
    --rays-per-wavelength 0.5 --pol VV --no-edges --out veh.csv \
    --plot "$img/vehicle_rcs_35ghz.png" -q
  "$exe" profile --mesh veh.glb --freq-sweep-hz 34e9:36e9:200 --theta-deg 80 \
    --phi-deg 28.5:31.5:128 --rays-per-wavelength 1 --no-edges --out vp.csv \
    --plot "$img/vehicle_profile.png" --isar-plot "$img/vehicle_isar.png" -q
fi
if [ "$images" = 1 ]; then
  # The example cases read their relative paths from the repository's root.
  cd "$root"
  "$exe" image examples/ev_radar_94ghz.toml --time-s 52 --looks 10 --out "$work/ev" --plot -q
  cp "$work/ev/image.png" "$img/ev_image.png"
  "$exe" image examples/geodata/olinda_approach.toml --time-s 8 --plot --out "$work/olinda_ev" -q
  cp "$work/olinda_ev/image.png" "$img/olinda_ev_image.png"
  "$exe" sar examples/sar_seed.toml --out "$work/sar_seed" -q
  cp "$work/sar_seed/image.png" "$img/sar_seed.png"
  "$exe" sar examples/sar_terrain.toml --out "$work/sar_terrain" -q
  cp "$work/sar_terrain/image.png" "$img/sar_terrain.png"
  "$exe" sar examples/geodata/olinda_sar.toml --out "$work/olinda_sar" -q
  cp "$work/olinda_sar/image.png" "$img/olinda_sar.png"
  "$exe" sar examples/sar_trihedrals.toml --out "$work/sar_tri" -q
  cp "$work/sar_tri/irf.png" "$img/sar_irf_unweighted.png"
  sed 's/taper = "none"/taper = "hamming"/' examples/sar_trihedrals.toml > "$work/sar_hamming.toml"
  "$exe" sar "$work/sar_hamming.toml" --out "$work/sar_ham" -q
  cp "$work/sar_ham/irf.png" "$img/sar_irf_hamming.png"
  "$exe" tradeoff --out "$work/trade_full" -q
  cp "$work/trade_full/tradeoff.png" "$work/trade_full/tradeoff_frame.png" "$img/"
fi
# The docs show the PNGs; the SVGs the tools write beside them are not kept here.
rm -f "$img"/*.svg
