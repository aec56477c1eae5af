#pragma once
// The built scene: an Embree 3 BVH over the static geometry plus one body-frame BVH per moving
// object, behind a ray-query API in our own types. Queries traverse in float and refine every hit
// in double precision; moving objects are placed by double-precision transforms, so set_time()
// rebuilds nothing.

#include <cstdint>
#include <memory>
#include <span>

#include "scene/types.hpp"

namespace radar_emu::scene {

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

  /// Moves every moving object to time `t_s` (their transforms and world boxes only; no BVH is
  /// rebuilt, no Embree call). Non-finite `t_s` is ignored. Real-time safe (no allocation, O(number
  /// of moving objects)); not thread-safe against concurrent queries.
  void set_time(double t_s) noexcept;
  [[nodiscard]] double time_s() const noexcept;

  [[nodiscard]] std::span<const Material> materials() const noexcept;
  [[nodiscard]] std::span<const ObjectState> objects() const noexcept;
  [[nodiscard]] const GeoAnchor& anchor() const noexcept;
  /// The description the scene was built from (bodies in body frames).
  [[nodiscard]] const SceneDescription& description() const noexcept;
  [[nodiscard]] std::size_t triangle_count() const noexcept;
  /// World from body of object `object_id` at the current time (static objects: their
  /// placement; moving objects: start + v t, body +x along the horizontal velocity). Identity
  /// for an unknown id. Real-time safe.
  [[nodiscard]] glm::dmat4 world_from_body(std::uint32_t object_id) const noexcept;

  /// Diagnostics: how often the static geometry's BVH has been built (1 after construction,
  /// 0 when every object moves) and how many Embree scene commits there have been in total (one
  /// per BVH at construction). set_time() changes neither: it rebuilds nothing.
  [[nodiscard]] std::uint64_t static_build_count() const noexcept;
  [[nodiscard]] std::uint64_t embree_commit_count() const noexcept;
  /// Embree errors reported since construction (0 in a healthy scene; a query that hits an
  /// Embree error returns "no hit").
  [[nodiscard]] std::uint32_t embree_error_count() const noexcept;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace radar_emu::scene
