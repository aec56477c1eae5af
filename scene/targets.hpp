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
// The vehicles and aircraft below are closed, outward-wound parts lofted through polygonal
// sections (every part its own closed surface; parts may interpenetrate, as real assemblies do),
// all "metal", origin on the ground below the centre of the overall length, x forward, y left,
// z up; their bounds are exactly x [-a/2, a/2], y [-b/2, b/2], z [0, c] for proportions near the
// examples (wheels and skids touch z = 0 with a vertex). Part proportions: scene/targets.cpp.
//   truck            overall length a, width b, height c, e.g. 8 x 2.5 x 3.4 m: cab with a sloped
//                    upper front, cargo box, chassis, 6 wheels (16-gons); 436 triangles.
//   jeep             overall length a, width b (wheels), height c, e.g. 4 x 1.8 x 1.9 m: hull with
//                    a sloped nose, cabin with a raked windscreen, 4 wheels; 292 triangles.
//   helicopter       fuselage length a (nose to fin), main rotor diameter b, height c (skids to
//                    hub top), e.g. 12.7 x 14.6 x 4.4 m (UH-1): elliptic fuselage, tail boom,
//                    fin, tail rotor disc, stabiliser, mast, hub, a two-bladed main rotor parked
//                    across the fuselage (so the width is b), skids on struts; 512 triangles.
//   transport_aircraft overall length a, wing span b, height c (ground to fin tip), e.g. A320
//                    37.6 x 35.8 x 11.8 m or C-130 29.8 x 40.4 x 11.7 m: 32-gon fuselage with
//                    nose and upswept tail cones, swept tapered wing with dihedral, tailplane,
//                    fin (hexagonal aerofoils), two engine nacelles on pylons, nose and main
//                    gear wheels; 896 triangles.
//   (Triangle counts at facet_m = 0.) For these four, facet_m = 0 gives the coarsest mesh (flat
//   faces unsplit; round parts 12 to 32 sides); facet_m > 0 splits faces and adds sides so that no
//   edge exceeds facet_m (split quads: sqrt(2) facet_m); flat faces, hence the volume of the
//   non-round parts, are unchanged.
// facet_m bounds the edge length of the facets (quads split in two have diagonals up to
// sqrt(2) facet_m; 0: the coarsest mesh that is exact for flat targets, 32 segments around for
// curved ones).

#include <array>
#include <filesystem>
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
  kVehicle,
  kTruck,
  kJeep,
  kHelicopter,
  kTransportAircraft
};

/// Dimensions of a target [m]; what a, b and c mean depends on the kind (list above). For the
/// vehicles and aircraft: a = overall length (x), b = overall width (y: track, wing span or
/// rotor diameter), c = overall height (z).
struct TargetSpec {
  TargetKind kind = TargetKind::kPlate;
  double a_m = 1.0;      ///< first dimension [m]
  double b_m = 1.0;      ///< second dimension [m]
  double c_m = 1.0;      ///< third dimension [m]
  double facet_m = 0.0;  ///< longest facet edge [m] (see above); 0: the kind's default
};

/// The dimensions a kind reads and its default size: the one table behind `radar-emu scene
/// target KIND` (--a-m, --b-m, --c-m left out) and a scenario's `[[target]] builtin = KIND`
/// (size_m left out). The vehicles and aircraft default to the example sizes above (a truck is
/// 8 x 2.5 x 3.4 m); the canonical shapes have none (their size is the whole of their radar
/// cross section): both refuse to guess it. Both print the size they used (target_size_text).
struct TargetKindSize {
  int dims = 3;                                    ///< 1 (a), 2 (a, b) or 3 (a, b, c)
  std::string_view meaning;                        ///< "[length, width, height]", "[radius]", ...
  std::optional<std::array<double, 3>> default_m;  ///< a, b, c [m]; none: to be given
};
[[nodiscard]] TargetKindSize target_kind_size(TargetKind kind) noexcept;
/// "truck 8 x 2.5 x 3.4 m [length, width, height]": the kind, the dimensions it reads [m] and
/// what they are, for the line both `scene target` and a scenario's setup print.
[[nodiscard]] std::string target_size_text(const TargetSpec& spec);

/// Names as on the command line: plate, dihedral, trihedral-square, trihedral-tri, sphere,
/// cylinder, box, vehicle, truck, jeep, helicopter, transport_aircraft.
[[nodiscard]] std::optional<TargetKind> target_kind_from_name(std::string_view name) noexcept;
[[nodiscard]] std::string_view target_name(TargetKind kind) noexcept;
[[nodiscard]] std::string target_names();  ///< "plate|dihedral|..." for messages

/// The target as a one-object scene (material "metal"). Throws std::invalid_argument naming the
/// dimension when one is not a positive finite number (or facet_m is negative).
[[nodiscard]] SceneDescription make_target(const TargetSpec& spec);

/// Makes the target and writes it: glTF for a .glb / .gltf path (any case), otherwise the mesh
/// file its extension names (write_mesh_file: .obj, .stl ...). Returns the triangles written.
/// `scene target` and the Python module's make_target write through this one function.
std::size_t write_target_file(const TargetSpec& spec, const std::filesystem::path& path);

/// Triangles make_target(spec) would make, without making them: exact for plate, dihedral,
/// trihedrals, sphere, cylinder and box; for the vehicles and aircraft a fit (coarse count plus a
/// per-kind constant times the bounding box's surface over facet_m^2) within a factor of 2 of the
/// count for facet_m from 0.05 m to 0.5 m at the example sizes above
/// (tests/scene/targets_test.cpp). A double: absurd facet sizes give counts past any integer type.
[[nodiscard]] double target_triangle_estimate(const TargetSpec& spec);

/// Peak resident memory per triangle while a target is made and written [bytes]: measured with
/// GNU time (%M) on a 1.58 M-triangle sphere, 203 B/triangle for .glb and 67 B/triangle for .stl;
/// the larger, rounded up, so that an estimate from it does not under-state.
inline constexpr double kTargetBytesPerTriangle = 210.0;

}  // namespace radar_emu::scene
