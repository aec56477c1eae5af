#pragma once
// Canonical radar targets (physics.md's closed forms), as meshes in their body frame, metres.
// Conventions (the RCS frame of design.md: the radar sits in direction (theta, phi) from +z):
//   plate            a (x) by b (y) in the plane z = 0, centred; one sheet, both sides reflect.
//                    Broadside: theta = 0.
//   dihedral         right dihedral, fold along y (length a) through the origin, two faces of
//                    width b at +-45 deg from +z; broadside (double bounce): theta = 0.
//   trihedral-square three a x a plates in the planes x = 0, y = 0, z = 0 of the positive octant;
//   trihedral-tri    three right isosceles triangles (legs a) in the same planes. Symmetry axis
//                    (1,1,1): theta = 54.7356 deg, phi = 45 deg.
//   sphere           radius a, centred; latitude-longitude facets.
//   cylinder         radius a, length b along z, centred, closed with end caps.
//   box              a (x) by b (y) by c (z), centred.
//   vehicle          a tank-like armoured vehicle, overall length a (x, gun included), width b
//                    (y), height c (z), e.g. 7 x 3.5 x 2.5 m; origin on the ground at the centre
//                    of its footprint (x in [-a/2, a/2]), x forward (the gun), z up: sloped hull,
//                    side skirts, road wheels, a faceted turret with its gun, a cupola and stowage
//                    boxes. Flat plates and right angles (strong single and multi-bounce returns)
//                    and curved parts; every part is a closed, outward-wound mesh. The benchmark
//                    target of the RCS engine: about 25,000 facets at the default facet size (0: a
//                    / 58).
// facet_m bounds the edge length of the facets (quads split in two have diagonals up to
// sqrt(2) facet_m; 0: the coarsest mesh that is exact for flat targets, 32 segments around for
// curved ones).

#include <optional>
#include <span>
#include <string>
#include <string_view>

#include "scene/types.hpp"

namespace radar_emu::scene {

enum class TargetKind {
  kPlate,
  kDihedral,
  kTrihedralSquare,
  kTrihedralTriangular,
  kSphere,
  kCylinder,
  kBox,
  kVehicle
};

struct TargetSpec {
  TargetKind kind = TargetKind::kPlate;
  double a_m = 1.0;
  double b_m = 1.0;
  double c_m = 1.0;
  double facet_m = 0.0;
};

/// Names as on the command line: plate, dihedral, trihedral-square, trihedral-tri, sphere,
/// cylinder, box, vehicle.
[[nodiscard]] std::optional<TargetKind> target_kind_from_name(std::string_view name) noexcept;
[[nodiscard]] std::string_view target_name(TargetKind kind) noexcept;
[[nodiscard]] std::string target_names();  ///< "plate|dihedral|..." for messages

/// The target as a one-object scene (material "metal"). Throws std::invalid_argument naming the
/// dimension when one is not a positive finite number (or facet_m is negative).
[[nodiscard]] SceneDescription make_target(const TargetSpec& spec);

}  // namespace radar_emu::scene
