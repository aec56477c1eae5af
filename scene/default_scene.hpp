#pragma once
// The embedded default scene of `radar-emu run`: a runway on flat ground with metallic objects.
//
// Anchor (origin of the ENU world frame): the runway threshold, a fixed WGS84 point of a made-up
// airport in southern France, latitude 43.6 deg N, longitude 1.4 deg E, 150 m above the WGS84
// ellipsoid (DefaultSceneLayout::kAnchor*). Also documented in docs/architecture.md.
//
// Layout (ENU metres, runway along +y = north, threshold at the origin):
//   ground          "grass"    z = 0, x in [-3000, 3000], y in [-6000, 4000] (2 triangles)
//   runway          "asphalt"  z = 0.05 (above the grass so that it wins the hit),
//                              x in [-22.5, 22.5], y in [0, 3000]
//   parked_aircraft "metal"    at (110, 700, 0): fuselage a 12-sided prism, radius 2 m, 32 m
//                              long, axis east-west 3.5 m above ground; wings 30 m (north-south)
//                              x 4 m chord x 0.4 m at the fuselage centre; tail fin 0.4 x 4 x 6 m
//                              at the east end, standing on the fuselage
//   parked_vehicle  "metal"    at (-70, 400, 0): box 5 m (E-W) x 2.2 m (N-S) x 2.2 m high
//   light_mast      "metal"    at (60, 250, 0): column 1 x 1 x 12 m, lamp head 4 m (E-W) x 1 x 1 m
//                              on top (13 m overall)
//   moving_vehicle  "metal"    box 6 m long (body x) x 2.5 m wide x 2.5 m high, body origin at
//                              its bottom centre; starts at (-120, 200, 0), 15 m/s north on a
//                              taxiway parallel to the runway (so its body x points north)
// Every object is one ObjectDesc; its body parts are closed meshes wound counter-clockwise seen
// from outside. The aircraft (on its fuselage top, 6 m west of centre), the parked vehicle, the
// light mast and the moving vehicle (on their roofs) also carry a 0.5 m square trihedral corner
// reflector of single-sheet plates (an open mesh), aimed south along the approach 3 deg up: flat
// faces only flash within hundredths of a degree of normal incidence at 94 GHz. Static objects
// keep their placement in ObjectDesc::world_from_body.

#include <glm/glm.hpp>

#include "scene/types.hpp"

namespace radar_emu::scene {

/// Geometry of the default scene, for scenario defaults and tests (ENU metres, runway along +y
/// (north), threshold at the origin).
struct DefaultSceneLayout {
  static constexpr double kAnchorLatitude_deg = 43.6;  ///< WGS84 anchor = runway threshold
  static constexpr double kAnchorLongitude_deg = 1.4;
  static constexpr double kAnchorHeight_m = 150.0;  ///< above the ellipsoid

  static constexpr double kRunwayLength_m = 3000.0;
  static constexpr double kRunwayWidth_m = 45.0;
  static constexpr double kRunwayHeight_m = 0.05;       ///< above the grass
  static constexpr double kGroundHalfWidth_m = 3000.0;  ///< ground extends +-3 km east-west
  static constexpr double kGroundSouth_m = -6000.0;     ///< ground from 6 km short of threshold
  static constexpr double kGroundNorth_m = 4000.0;

  /// Body origins (on the ground, object centre) of the static metallic objects.
  static constexpr glm::dvec3 kParkedAircraft_m{110.0, 700.0, 0.0};
  static constexpr glm::dvec3 kParkedVehicle_m{-70.0, 400.0, 0.0};
  static constexpr glm::dvec3 kLightMast_m{60.0, 250.0, 0.0};
  /// The moving vehicle's body origin at t = 0 and its velocity.
  static constexpr glm::dvec3 kMovingVehicleStart_m{-120.0, 200.0, 0.0};
  static constexpr glm::dvec3 kMovingVehicleVelocity_mps{0.0, 15.0, 0.0};
};

/// Builds the default scene: ground ("grass"), runway ("asphalt"), a parked aircraft-sized
/// object, a parked vehicle, a light mast (all "metal") and a vehicle moving along a taxiway
/// (layout above). Setup only (allocates).
[[nodiscard]] SceneDescription default_scene();

}  // namespace radar_emu::scene
