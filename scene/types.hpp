#pragma once
// Value types of the scene: geometry, materials, objects and ray queries. No Embree here:
// Embree is an implementation detail of scene/ (style.md item 2).
//
// Frames: the world frame is East-North-Up (ENU) in metres, anchored at SceneDescription::anchor.
// An object's body frame is x forward, y left, z up (glTF uses y up: the loader converts).

#include <cstdint>
#include <glm/glm.hpp>
#include <optional>
#include <string>
#include <vector>

namespace radar_emu::scene {

/// A surface material. Scene only knows names and optical colour; radar/ maps names to radar
/// properties (conductor, clutter class) at setup.
struct Material {
  std::string name;                        ///< e.g. "metal", "asphalt", "grass", "concrete"
  glm::vec3 base_color{0.5f, 0.5f, 0.5f};  ///< optical colour, linear RGB 0..1 (previews)
};

/// Triangle mesh in its object's body frame. float vertices are fine for geometry (style.md 5).
struct Mesh {
  std::vector<glm::vec3> positions_m;            ///< vertex positions [m]
  std::vector<glm::uvec3> triangles;             ///< vertex indices, counter-clockwise = outside
  std::vector<std::uint16_t> triangle_material;  ///< material index per triangle
};

/// Constant-velocity straight-line motion, heading along the velocity.
struct LinearMotion {
  glm::dvec3 start_position_m{0.0};  ///< world position of the body origin at t = 0 [m]
  glm::dvec3 velocity_mps{0.0};      ///< world velocity [m/s]
};

/// Waypoint trajectory: straight legs between waypoints joined by circular turns tangent to both
/// legs (a fillet of radius turn_radius_m at each inner waypoint, in the plane of the two legs),
/// traversed at constant speed. Body x points along the velocity (3-D: climbing legs pitch the
/// body), body y stays horizontal (left) unless `bank` rolls it into the turns. Waypoints are
/// world (ENU) positions of the body origin [m]; scene/trajectory.hpp evaluates it.
struct Trajectory {
  std::vector<glm::dvec3> waypoints_m;  ///< >= 2 world positions [m]; consecutive ones distinct
  double speed_mps = 0.0;               ///< speed along the path [m/s], > 0
  /// Radius of the turns [m]; 0 (with turn_rate_rad_s 0): sharp corners, heading jumps there.
  double turn_radius_m = 0.0;
  /// Alternative to turn_radius_m (which must then be 0): a constant turn rate [rad/s], so the
  /// radius is speed_mps / turn_rate_rad_s.
  double turn_rate_rad_s = 0.0;
  /// Closed path: a leg from the last waypoint back to the first, a turn at every waypoint, and
  /// the path repeats. t = 0 is where the leg from waypoint 0 to waypoint 1 starts (after the turn
  /// at waypoint 0). Open paths start at waypoint 0 at t = 0 and rest at their ends outside
  /// [0, duration] (velocity 0).
  bool loop = false;
  /// Roll into turns like a coordinated turn: tan(bank) = v^2 / (g r) (body z tilted toward the
  /// turn centre; the roll steps at the arc's ends).
  bool bank = false;
};

struct ObjectDesc {
  std::string name;
  Mesh mesh;
  /// Placement of static objects (ignored when `motion` is set): world from body.
  glm::dmat4 world_from_body{1.0};
  /// Moving objects are instanced: moving them never rebuilds the static geometry.
  std::optional<LinearMotion> motion;
  /// Database area the object belongs to ("central", "surround", "airport", ...; "" if none).
  /// Carried in glTF node extras; `radar-emu scene info` counts polygons per area.
  std::string area{};
  /// Level of detail: objects sharing a group (>= 0) are alternative meshes of one terrain tile,
  /// level 0 the finest; at most one level of a group is active per frame (scene culling picks it
  /// by range so that facets stay below the range cell). -1: not part of a group (always active).
  std::int32_t lod_group = -1;
  std::uint8_t lod_level = 0;
  /// Longest facet edge of this mesh [m] (what LOD selection compares with the range cell).
  /// 0: Scene computes it from the mesh.
  double lod_facet_m = 0.0;
  /// Moving on a waypoint trajectory (exclusive with `motion`; `world_from_body` is ignored).
  /// Like `motion`, moving it never rebuilds anything.
  std::optional<Trajectory> trajectory = std::nullopt;
};

/// WGS84 point at the origin of the world ENU frame.
struct GeoAnchor {
  double latitude_rad = 0.0;
  double longitude_rad = 0.0;
  double height_m = 0.0;  ///< above the WGS84 ellipsoid
};

/// A whole scene before acceleration structures are built.
struct SceneDescription {
  std::vector<Material> materials;
  std::vector<ObjectDesc> objects;
  GeoAnchor anchor{};
  /// Empty, or why the database is not whole ("import stopped by SIGINT: ..."): written to and
  /// read from glTF (scene extras radar_emu.incomplete); loading such a scene warns.
  std::string incomplete;
};

/// A ray in the world frame. Double precision in the API; scene/ converts for the tracer and
/// refines hits in double precision.
struct Ray {
  glm::dvec3 origin_m{0.0};
  glm::dvec3 direction{0.0, 0.0, 1.0};  ///< unit vector
  double t_near_m = 0.0;
  double t_far_m = 1e30;
};

/// The first surface a ray meets.
struct Hit {
  double t_m = 0.0;                  ///< distance from the ray origin [m] (double-precision refit)
  glm::dvec3 position_m{0.0};        ///< world position [m]
  glm::dvec3 normal{0.0, 0.0, 1.0};  ///< unit geometric normal, world frame, as wound (not flipped)
  std::uint32_t object_id = 0;       ///< index into Scene::objects()
  std::uint32_t primitive_id = 0;    ///< triangle index in that object's mesh
  std::uint16_t material_id = 0;     ///< index into Scene::materials()
};

/// State of one object at the scene's current time.
struct ObjectState {
  std::string name;
  bool moving = false;
  /// Queries can hit it: false for LOD meshes that are not the level selected for their tile
  /// and for tiles culled by Scene::set_view().
  bool active = true;
  glm::dvec3 velocity_mps{0.0};  ///< world velocity at the current time [m/s]
  glm::dvec3 bounds_min_m{0.0};  ///< world axis-aligned bounds at the current time [m]
  glm::dvec3 bounds_max_m{0.0};
  std::size_t triangle_count = 0;
};

}  // namespace radar_emu::scene
