#pragma once
// The built scene: an Embree 3 BVH over the static geometry plus one instance per moving object,
// behind a ray-query API in our own types.

#include <cstdint>
#include <memory>
#include <span>

#include "scene/types.hpp"

namespace radar_emu::scene {

class Scene {
 public:
  /// Builds the acceleration structures (setup; throws std::runtime_error with context on
  /// invalid input: empty scene, out-of-range indices, non-finite vertices, bad material index).
  explicit Scene(SceneDescription description);
  ~Scene();
  Scene(Scene&&) noexcept;
  Scene& operator=(Scene&&) noexcept;
  Scene(const Scene&) = delete;
  Scene& operator=(const Scene&) = delete;

  /// Closest hit along `ray` within [t_near, t_far]. Real-time safe, thread-safe (const).
  [[nodiscard]] bool intersect(const Ray& ray, Hit& hit) const noexcept;
  /// True if anything blocks `ray` within [t_near, t_far]. Real-time safe, thread-safe.
  [[nodiscard]] bool occluded(const Ray& ray) const noexcept;

  /// Moves every moving object to time `t_s` (instance transforms only; static geometry is not
  /// rebuilt). Real-time safe; not thread-safe against concurrent queries.
  void set_time(double t_s) noexcept;
  [[nodiscard]] double time_s() const noexcept;

  [[nodiscard]] std::span<const Material> materials() const noexcept;
  [[nodiscard]] std::span<const ObjectState> objects() const noexcept;
  [[nodiscard]] const GeoAnchor& anchor() const noexcept;
  /// The description the scene was built from (bodies in body frames).
  [[nodiscard]] const SceneDescription& description() const noexcept;
  [[nodiscard]] std::size_t triangle_count() const noexcept;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace radar_emu::scene
