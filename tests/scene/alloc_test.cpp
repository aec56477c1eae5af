// The frame path (intersect, occluded, set_time) must not allocate (style.md item 10): count
// every operator new while it runs. (Embree's aligned allocations would not be counted, but the
// frame path makes no Embree call that builds anything: only rtcIntersect1/rtcOccluded1.)

#include <gtest/gtest.h>

#include <atomic>
#include <cstdlib>
#include <new>

#include "scene/default_scene.hpp"
#include "scene/scene.hpp"

namespace {
std::atomic<long> g_news{0};
}  // namespace

void* operator new(std::size_t n) {
  g_news.fetch_add(1, std::memory_order_relaxed);
  if (void* p = std::malloc(n == 0 ? 1 : n))
    return p;
  throw std::bad_alloc();
}
void* operator new[](std::size_t n) {
  return operator new(n);
}
void operator delete(void* p) noexcept {
  std::free(p);
}
void operator delete[](void* p) noexcept {
  std::free(p);
}
void operator delete(void* p, std::size_t) noexcept {
  std::free(p);
}
void operator delete[](void* p, std::size_t) noexcept {
  std::free(p);
}

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
  const long before = g_news.load();
  int hits = 0;
  for (int i = 0; i < 1000; ++i) {
    s.set_time(0.01 * i);
    hits += s.intersect(r, hit) ? 1 : 0;
    hits += s.occluded(r) ? 1 : 0;
    r.origin_m.x = -120.0 + 0.001 * i;
  }
  const long after = g_news.load();
  EXPECT_EQ(after - before, 0) << "operator new called in the frame path";
  EXPECT_EQ(hits, 2000);
  EXPECT_EQ(s.static_build_count(), 1u);
  // The counter works: building a scene allocates.
  const long b2 = g_news.load();
  const sc::SceneDescription d = sc::default_scene();
  EXPECT_GT(g_news.load() - b2, 0);
}
