#!/usr/bin/env bash
# Installs the Debian 12 packages radar-emu needs to build and test. Idempotent: packages
# already installed are not touched, and apt-get runs only when something is missing.
set -euo pipefail

PACKAGES=(
  # toolchain
  build-essential cmake ninja-build pkg-config git
  # libraries (design.md: Debian packages only)
  libembree-dev libglm-dev libtinygltf-dev nlohmann-json3-dev libstb-dev libtbb-dev
  libusb-1.0-0-dev libsocketcan-dev libmodbus-dev libfftw3-dev libtomlplusplus-dev libcli11-dev
  # `run --cube` (loop/outputs/cube_writer.cpp: HDF5's C API) and its test (h5py)
  libhdf5-dev python3-h5py
  libgtest-dev libgmock-dev libbenchmark-dev
  # dense LU of `rcs --method mom` (radar/em/mom.hpp): LAPACK as OpenBLAS builds it
  libopenblas-dev
  # GeoTIFF output of `radar-emu sar` (optional at build time) and gdalinfo, which its test reads
  libgdal-dev gdal-bin
  # `scene import` (scene/geodata/): PROJ and its EGM96 geoid grid egm96_15.gtx
  libproj-dev proj-data
  # scripts/bench-geodata-import.sh writes its DEMs with GDAL's Python bindings
  python3-gdal
  # coverage-guided fuzzing (tests/fuzz, scripts/fuzz.sh): clang 14 and its libFuzzer runtime
  clang libclang-rt-14-dev
  # independent peers used by the tests (buses.md)
  python3 python3-can python3-canmatrix python3-pymodbus python3-serial-asyncio mbpoll socat
  # the Python module radar_emu (python/, optional at build time) and its tests
  python3-dev pybind11-dev python3-numpy python3-pytest
  # every figure of the tools (plot/render.py, docs/plotting.md): matplotlib draws them, run
  # by the interpreter CMake finds (RADAR_EMU_PLOT_PYTHON; $RADAR_EMU_PYTHON at run time)
  python3-matplotlib
  # MPI scale-out of rcs / profile (tools/mpi_work.hpp, docs/cluster.md; optional at build
  # time, CMake RADAR_EMU_MPI) and its mpirun test
  openmpi-bin libopenmpi-dev
  # the live view's test (run --serve): headless Chromium screenshots the page
  chromium
)
# Not installed here, needed only to regenerate the full-wave table tests/data/openems_plate
# (scripts/openems_rcs.py; the tests read the checked-in table):
#   openems python3-openems python3-scipy

missing=()
for p in "${PACKAGES[@]}"; do
  if ! dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed"; then
    missing+=("$p")
  fi
done

if [ ${#missing[@]} -eq 0 ]; then
  echo "install-deps: all ${#PACKAGES[@]} packages present"
  exit 0
fi

echo "install-deps: installing ${missing[*]}"
SUDO=""
if [ "$(id -u)" -ne 0 ]; then SUDO="sudo"; fi
export DEBIAN_FRONTEND=noninteractive
$SUDO apt-get update -q
$SUDO apt-get install -y -q --no-install-recommends "${missing[@]}"
