#pragma once
// Targets added to a scene description: a built-in target (scene/targets.hpp) or a mesh file
// (glTF, OBJ, STL), placed fixed, on a straight line or on a waypoint trajectory, optionally
// dropped onto the scene's ground. What a scenario's [[target]] tables become
// (docs/scene_format.md). Setup only (allocates, throws).
//
// Angles here are compass angles in radians: clockwise from north seen from above (north 0,
// east pi/2), as the ownship's true heading (loop/ownship.hpp); the scene's ENU yaw
// (counter-clockwise from east) is pi/2 minus it.

#include <filesystem>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "scene/targets.hpp"
#include "scene/types.hpp"

namespace radar_emu::scene {

/// An axis of a mesh file's own frame, with its sign.
enum class MeshAxis { kPlusX, kMinusX, kPlusY, kMinusY, kPlusZ, kMinusZ };
/// "+x", "-x", "+y", "-y", "+z", "-z".
[[nodiscard]] std::optional<MeshAxis> mesh_axis_from_name(std::string_view name) noexcept;

/// One target to add. Exactly one of `builtin` and `mesh_file`; the motion is fixed
/// (speed_mps == 0, no waypoints), a straight line (speed_mps > 0, no waypoints) or a waypoint
/// trajectory (>= 2 waypoints, speed_mps > 0).
struct TargetPlacement {
  std::string name;     ///< ObjectDesc::name; unique in the scene
  std::string context;  ///< prefix of every error message, e.g. "x.toml: [[target]] #2"

  std::optional<TargetSpec> builtin;
  std::filesystem::path mesh_file;  ///< .glb, .gltf, .obj or .stl
  double mesh_scale = 1.0;          ///< metres per file unit, > 0
  /// The file's axes (as written in the file; glTF before its y-up conversion) that become the
  /// body's x (forward) and z (up). Defaults: glTF +x forward, +y up; OBJ and STL +x, +z.
  std::optional<MeshAxis> mesh_front_axis;
  std::optional<MeshAxis> mesh_up_axis;
  /// Radar material of every triangle; empty: "metal" for a built-in target, the file's own
  /// materials for a mesh file (OBJ usemtl names, glTF material names, "metal" for STL).
  std::string material;
  double facet_m = 0.0;  ///< built-in targets: TargetSpec::facet_m

  /// Body origin in the scene's ENU frame [m] (fixed and straight-line targets). With
  /// on_ground, z is the height of the mesh's lowest point above the ground below (x, y).
  glm::dvec3 position_m{0.0};
  /// Drop onto the ground: the mesh's lowest point sits z metres above the highest static
  /// surface below (x, y) (ground_height_m()); waypoints likewise, each on its own ground.
  bool on_ground = false;
  double heading_rad = 0.0;  ///< compass direction of the body's x axis (the nose)
  double speed_mps = 0.0;    ///< 0: fixed
  /// Straight line: compass direction of travel. The nose keeps heading_rad (so a target can
  /// reverse or crab); set both equal for a target that faces its velocity.
  double course_rad = 0.0;
  /// Waypoint trajectory (body x along the velocity; heading_rad and course_rad unused).
  std::vector<glm::dvec3> waypoints_m;
  double turn_radius_m = 0.0;
  bool closed = false;  ///< Trajectory::loop
  bool bank = false;    ///< Trajectory::bank
};

/// Height [m] of the highest static surface of `scene` (ENU z) on the vertical through
/// (east_m, north_m), or nullopt when nothing is there. Static surfaces: objects without motion
/// or trajectory; of a level-of-detail group only level 0 (the finest). Roofs, bridge decks,
/// tree crowns and forest canopy count. Exact on the facets (double precision, brute force
/// over the objects whose box contains the point).
class GroundProbe {
 public:
  explicit GroundProbe(const SceneDescription& scene);
  [[nodiscard]] std::optional<double> height_m(double east_m, double north_m) const;

 private:
  struct Object {
    glm::dvec2 min_m, max_m;
    std::vector<glm::dvec3> vertices_m;  // world
    const std::vector<glm::uvec3>* triangles = nullptr;
  };
  std::vector<Object> objects_;
};

/// Adds the targets to `scene`, in order, as ObjectDesc with area "target", merging their
/// materials into scene.materials by name. Ground heights come from the scene as it was
/// before the first target (targets do not stand on each other). Throws std::runtime_error
/// "CONTEXT: reason" for a name already in the scene, an unreadable or moving mesh file, bad
/// dimensions, a trajectory TrajectoryPath rejects, or no ground below an on_ground target.
void add_targets(SceneDescription& scene, std::span<const TargetPlacement> targets);

}  // namespace radar_emu::scene
