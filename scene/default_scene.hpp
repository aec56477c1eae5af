#pragma once
// The embedded default scene of `radar-emu run`: a runway on flat ground with metallic objects.

#include "scene/types.hpp"

namespace radar_emu::scene {

/// Geometry of the default scene, for scenario defaults and tests (ENU metres, runway along +y
/// (north), threshold at the origin).
struct DefaultSceneLayout {
  static constexpr double kRunwayLength_m = 3000.0;
  static constexpr double kRunwayWidth_m = 45.0;
  static constexpr double kGroundHalfWidth_m = 3000.0;  ///< ground extends +-3 km east-west
  static constexpr double kGroundSouth_m = -6000.0;     ///< ground from 6 km short of threshold
  static constexpr double kGroundNorth_m = 4000.0;
};

/// Builds the default scene: ground ("grass"), runway ("asphalt"), a parked aircraft-sized
/// object, a parked vehicle, a light mast (all "metal") and a vehicle moving along a taxiway.
/// Anchor: a fixed WGS84 point (documented in docs/architecture.md).
[[nodiscard]] SceneDescription default_scene();

}  // namespace radar_emu::scene
