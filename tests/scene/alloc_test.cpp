// The frame path (intersect, occluded, set_time) must not allocate (style.md item 10): count
// every operator new while it runs. (Embree's aligned allocations would not be counted, but the
// frame path makes no Embree call that builds anything: only rtcIntersect1/rtcOccluded1 and the
// batched queries' rtcIntersect1M/rtcOccluded1M.)

#include <gtest/gtest.h>

#include <array>
#include <cstdint>

#include "scene/default_scene.hpp"
#include "scene/scene.hpp"
#include "tests/alloc_counter.hpp"

namespace sc = radar_emu::scene;

TEST(SceneFramePath, QueriesAndSetTimeDoNotAllocate) {
  sc::Scene s(sc::default_scene());
  sc::Ray r;
  r.origin_m = {-120.0, 0.0, 1.0};
  r.direction = {0.0, 1.0, 0.0};
  sc::Hit hit;
  // Warm up (first calls may initialise lazily inside Embree).
  (void)s.intersect(r, hit);
  (void)s.occluded(r);
  s.set_time(0.01);
  radar_emu::test::start_counting_allocations();
  int hits = 0;
  for (int i = 0; i < 1000; ++i) {
    s.set_time(0.01 * i);
    hits += s.intersect(r, hit) ? 1 : 0;
    hits += s.occluded(r) ? 1 : 0;
    r.origin_m.x = -120.0 + 0.001 * i;
  }
  // The batched queries too (caller-provided spans, a fixed stack buffer), over more rays than
  // one Embree stream call takes.
  std::array<sc::Ray, 150> rays;
  std::array<sc::Hit, 150> batch_hits;
  std::array<glm::dvec3, 150> origins;
  std::array<std::uint8_t, 150> found{}, blocked{}, blocked_along{};
  for (std::size_t i = 0; i < rays.size(); ++i) {
    rays[i] = r;
    rays[i].origin_m.x = -120.0 + 0.001 * static_cast<double>(i);
    origins[i] = rays[i].origin_m;
  }
  s.intersect(rays, batch_hits, found);
  s.occluded(rays, blocked);
  s.occluded_along(r.direction, origins, blocked_along);
  EXPECT_EQ(radar_emu::test::stop_counting_allocations(), 0u)
      << "operator new called in the frame path";
  EXPECT_EQ(hits, 2000);
  for (std::size_t i = 0; i < rays.size(); ++i) {
    EXPECT_EQ(found[i], 1);
    EXPECT_EQ(blocked[i], 1);
    EXPECT_EQ(blocked_along[i], 1);
  }
  EXPECT_EQ(s.static_build_count(), 1u);
  // The counter works: building a scene allocates.
  radar_emu::test::start_counting_allocations();
  const sc::SceneDescription d = sc::default_scene();
  EXPECT_GT(radar_emu::test::stop_counting_allocations(), 0u);
}
