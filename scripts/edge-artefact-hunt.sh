#!/usr/bin/env bash
# The full edge artefact hunt (issue 30): plate, dihedral, both trihedrals, cylinder, sphere,
# cone and the vehicle swept at 0.1 deg within 5 deg of their face normals and edge-on
# directions (0.5 deg elsewhere), both polarisations, edges on and off, against each target's
# physical maximum and the geometry's bound on neighbouring-angle jumps; then the tessellated
# cylinders and spheres (ka 10-40, meshes to lambda / 16) against their closed forms. Prints
# each target's worst case and the overall worst. The coarse version of the same test runs in
# ctest (radar_tests, EdgeArtefacts.*). Takes several minutes on two cores.
# Usage: scripts/edge-artefact-hunt.sh [BUILD_DIR]   (default: build)
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
build="${1:-$root/build}"
RADAR_EMU_EDGE_HUNT=full exec "$build/tests/radar/radar_tests" --gtest_filter='EdgeArtefacts.*'
