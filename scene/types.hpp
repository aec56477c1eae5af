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
  double lod_facet_m = 0.0;
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
  glm::dvec3 velocity_mps{0.0};  ///< world velocity [m/s]
  glm::dvec3 bounds_min_m{0.0};  ///< world axis-aligned bounds at the current time [m]
  glm::dvec3 bounds_max_m{0.0};
  std::size_t triangle_count = 0;
};

}  // namespace radar_emu::scene
