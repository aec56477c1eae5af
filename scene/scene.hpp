#pragma once
// The built scene: an Embree 3 BVH over the static geometry (plus one per level of detail of the
// terrain tiles) and one body-frame BVH per moving object, behind a ray-query API in our own
// types. Queries traverse in float and refine every hit in double precision; moving objects
// (constant velocity or waypoint trajectories) are placed by double-precision transforms, so
// set_time() rebuilds nothing; set_view() picks each tile's level of detail and culls tiles outside
// the radar's view by flags that an Embree filter reads, so it rebuilds nothing either.

#include <array>
#include <cstdint>
#include <memory>
#include <span>

#include "scene/types.hpp"

namespace radar_emu::scene {

/// What the radar can see in one frame (Scene::set_view): a pyramid from the antenna bounded by
/// the field of view's azimuth and elevation limits, cut at the maximum range, plus the radar's
/// resolution, which picks the level of detail of terrain tiles.
struct ViewVolume {
  glm::dvec3 position_m{0.0};  ///< antenna phase centre, world [m]
  /// Rotation world from antenna; antenna frame x boresight, y right, z down (radar::RadarPose).
  glm::dmat3 world_from_antenna{1.0};
  /// Field of view, antenna frame [rad]: azimuth atan2(y, x), positive right; elevation
  /// atan2(-z, hypot(x, y)), positive up (radar::azel_from_direction). -pi/2 < min < max < pi/2.
  double azimuth_min_rad = -0.1745;
  double azimuth_max_rad = 0.1745;
  double elevation_min_rad = -0.0873;
  double elevation_max_rad = 0.0873;
  double max_range_m = 6000.0;  ///< one-way range limit [m], > 0
  double range_cell_m = 1.0;    ///< the radar's range resolution cell [m], > 0
  /// Angular cross-range cell (beamwidth) or the tracer's terrain ray spacing [rad], >= 0: with
  /// it, a tile at range R may use facets up to max(range_cell_m, R angular_cell_rad); 0: up to
  /// range_cell_m at every range (see Scene::set_view).
  double angular_cell_rad = 0.0;
  /// true: LOD tiles entirely outside the volume have no active level (queries ignore them);
  /// false: they keep the level the rule gives for their range.
  bool cull_outside = true;
};

/// What the last set_view() selected (all zero counts before the first call, apart from the
/// totals).
struct ViewStats {
  std::uint32_t lod_groups = 0;          ///< terrain tiles (LOD groups) in the scene
  std::uint32_t lod_groups_in_view = 0;  ///< tiles whose box meets the view volume
  std::uint32_t lod_groups_culled = 0;   ///< tiles with no active level (outside, cull_outside)
  /// Active tiles by selected level (index 3 counts levels >= 3).
  std::array<std::uint32_t, 4> lod_groups_at_level{};
  std::uint32_t objects_in_view = 0;    ///< active objects whose world box meets the volume
  std::uint64_t triangles_total = 0;    ///< every triangle in the scene, every LOD level
  std::uint64_t triangles_active = 0;   ///< triangles that queries can hit
  std::uint64_t triangles_in_view = 0;  ///< active triangles of objects whose box meets the volume
  std::uint64_t views_set = 0;          ///< set_view() calls accepted
  std::uint64_t invalid_views = 0;      ///< set_view() calls rejected (volume invalid: defaults)
};

/// Scene::occluded split by a moving object: the rest of the scene, or that object alone.
enum class MoverSplit : std::uint8_t { kRest, kOwn };
/// No moving object (Scene::occluded's split).
inline constexpr std::uint32_t kNoMover = 0xFFFFFFFFu;

class Scene {
 public:
  /// Builds the acceleration structures (setup; throws std::runtime_error with context on
  /// invalid input: empty scene, out-of-range indices, non-finite vertices or transforms, bad
  /// material index, meshes with only degenerate triangles; or with Embree's message when the
  /// build fails). Coordinates should stay within about +-20 km of the anchor (float BVH).
  explicit Scene(SceneDescription description);
  ~Scene();
  Scene(Scene&&) noexcept;
  Scene& operator=(Scene&&) noexcept;
  Scene(const Scene&) = delete;
  Scene& operator=(const Scene&) = delete;

  /// Closest hit along `ray` within [t_near, t_far]. Traversal is in float; t, position and
  /// normal are then recomputed in double from the hit triangle's world-space vertices.
  /// Returns false for no hit and for invalid rays (non-finite, t_far < t_near).
  /// Real-time safe (no allocation, no lock), thread-safe (const).
  [[nodiscard]] bool intersect(const Ray& ray, Hit& hit) const noexcept;
  /// True if anything blocks `ray` within [t_near, t_far]. Real-time safe, thread-safe.
  [[nodiscard]] bool occluded(const Ray& ray) const noexcept;

  /// Batched queries for coherent rays (neighbouring origins, similar directions: the samples
  /// of a facet toward a plane wave, a row of parallel ray tubes): the answers of the single
  /// queries above, ray by ray, with the static BVH traversed as Embree ray streams marked
  /// coherent (rtcIntersect1M / rtcOccluded1M, which trace them in SIMD packets; several times
  /// the single-ray throughput on such rays). The occlusion query asks the levels of detail and
  /// the moving objects' BVHs as streams too (per BVH, the rays that no earlier one blocked and
  /// that can reach it; a mover's in its body frame). Order the rays so that neighbours in the
  /// span are neighbours in space. found[i] = intersect(rays[i], hits[i]); blocked[i] =
  /// occluded(rays[i]); only the first min(sizes) rays are answered. Real-time safe (no
  /// allocation: a fixed stack buffer), thread-safe.
  void intersect(std::span<const Ray> rays, std::span<Hit> hits,
                 std::span<std::uint8_t> found) const noexcept;
  void occluded(std::span<const Ray> rays, std::span<std::uint8_t> blocked) const noexcept;
  /// occluded() split by one moving object a ray: blocked[i] is rays[i]'s answer from the whole
  /// scene but the moving object mover[i] (MoverSplit::kRest), or from mover[i] alone (kOwn; its
  /// BVH in its body frame, after the same box test); kNoMover: the whole scene (kRest) or
  /// nothing (kOwn). The two answers' OR is occluded(rays[i]) (the same stages, each asked as
  /// in the unsplit query). For a mover's own facets: what its body shadows on itself depends
  /// on its aspect only, the rest on its place in the scene as well.
  void occluded(std::span<const Ray> rays, std::span<const std::uint32_t> mover, MoverSplit split,
                std::span<std::uint8_t> blocked) const noexcept;
  /// The same for parallel rays over [0, infinity) from `origins` along the unit `direction`
  /// (toward a plane wave's source): blocked[i] = occluded({origins[i], direction, 0, inf}).
  void occluded_along(const glm::dvec3& direction, std::span<const glm::dvec3> origins,
                      std::span<std::uint8_t> blocked) const noexcept;

  /// Moves every moving object to time `t_s`: constant-velocity objects (LinearMotion) and
  /// trajectories (scene/trajectory.hpp; O(log pieces) each). Only transforms, velocities and
  /// world boxes change: no BVH is rebuilt, no Embree call. Non-finite `t_s` is ignored.
  /// Real-time safe (no allocation, O(number of moving objects)); not thread-safe against
  /// concurrent queries.
  void set_time(double t_s) noexcept;
  [[nodiscard]] double time_s() const noexcept;

  /// Per-frame view: selects what queries can hit, for the frame's radar position and beam.
  /// (a) A terrain tile (LOD group) is in view when its world box (over all its levels) meets
  ///     the volume: it is not entirely outside any of the four bounding planes of the field of
  ///     view (azimuth planes exact; elevation cones replaced by planes that contain them over
  ///     the azimuth span) and its nearest point is within max_range_m. Conservative: a tile that
  ///     any ray inside the field of view and range can reach is in view.
  /// (b) LOD rule: a tile whose box's nearest point is at range R uses its coarsest level whose
  ///     lod_facet_m <= max(range_cell_m, R * angular_cell_rad) (facets no longer than the radar's
  ///     resolution cell, or than the terrain sampling, at that range), or its finest level when
  ///     none qualifies. Nearest point: the rule errs toward finer.
  /// (c) Queries then ignore every LOD mesh but the selected level of each tile, and, with
  ///     cull_outside, every level of tiles out of view (an Embree filter reads a per-object flag
  ///     this call writes: no rebuild, no commit). Objects outside LOD groups (targets, moving
  ///     objects, buildings) stay active.
  /// An invalid volume (non-finite, a limit outside (-pi/2, pi/2), min >= max, range or cell
  /// <= 0) resets to the default view and is counted in ViewStats::invalid_views.
  /// Real-time safe (no allocation; O(objects)); not thread-safe against concurrent queries.
  void set_view(const ViewVolume& view) noexcept;
  /// Back to the default view (also before the first set_view()): every object outside LOD
  /// groups active, and the finest level (level 0) of every tile. Real-time safe.
  void clear_view() noexcept;
  [[nodiscard]] const ViewStats& view_stats() const noexcept;
  /// Selected level of tile `lod_group`: -1 when it is culled or there is no such group.
  [[nodiscard]] int active_lod_level(std::int32_t lod_group) const noexcept;

  [[nodiscard]] std::span<const Material> materials() const noexcept;
  [[nodiscard]] std::span<const ObjectState> objects() const noexcept;
  [[nodiscard]] const GeoAnchor& anchor() const noexcept;
  /// SceneDescription::incomplete of the database it was built from ("": whole).
  [[nodiscard]] const std::string& incomplete() const noexcept;
  /// The description the scene was built from (bodies in body frames).
  [[nodiscard]] const SceneDescription& description() const noexcept;
  [[nodiscard]] std::size_t triangle_count() const noexcept;
  /// World from body of object `object_id` at the current time (static objects: their
  /// placement; LinearMotion: start + v t, body +x along the horizontal velocity; trajectories:
  /// TrajectoryPath::at). Identity for an unknown id. Real-time safe.
  [[nodiscard]] glm::dmat4 world_from_body(std::uint32_t object_id) const noexcept;

  /// Diagnostics: how often the static geometry's BVHs have been built (1 after construction,
  /// 0 when every object moves) and how many Embree scene commits there have been in total (one
  /// per BVH at construction: static objects, one per LOD level present, one per moving
  /// object). set_time() and set_view() change neither: they rebuild nothing.
  [[nodiscard]] std::uint64_t static_build_count() const noexcept;
  [[nodiscard]] std::uint64_t embree_commit_count() const noexcept;
  /// Embree errors reported since construction (0 in a healthy scene; a query that hits an
  /// Embree error returns "no hit").
  [[nodiscard]] std::uint32_t embree_error_count() const noexcept;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

/// How every Embree BVH of a Scene is built, as Embree's RTCSceneFlags and RTCBuildQuality
/// values (the header does not include Embree's): robust mode, whose watertight traversal never
/// lets a ray through the edge two triangles share, and high build quality. bench_frame's raw
/// replay (BM_TraceRaw) builds its BVH the same way, so that it times the queries the tracer
/// asks as the tracer's scene answers them.
struct EmbreeBuild {
  int scene_flags = 0;
  int build_quality = 0;
};
[[nodiscard]] EmbreeBuild embree_build() noexcept;

/// Whether `ray` crosses the axis-aligned box [lo, hi] somewhere in [t_near_m, t_far_m] (slab
/// test in double; the box is padded by a relative 1e-6 so that float traversal inside it
/// cannot be culled wrongly). Cheap: used to cull queries that cannot reach an object.
[[nodiscard]] bool ray_crosses_box(const Ray& ray, const glm::dvec3& lo,
                                   const glm::dvec3& hi) noexcept;
/// The padded box ray_crosses_box tests, prepared once (e.g. per frame for a box that many rays
/// test): padded_box(lo, hi) pads as ray_crosses_box does, and ray_crosses_box(ray, box) then
/// gives its answer without recomputing the padding. Real-time safe.
struct PaddedBox {
  glm::dvec3 lo_m{0.0}, hi_m{0.0};
};
[[nodiscard]] PaddedBox padded_box(const glm::dvec3& lo, const glm::dvec3& hi) noexcept;
[[nodiscard]] bool ray_crosses_box(const Ray& ray, const PaddedBox& box) noexcept;

}  // namespace radar_emu::scene
