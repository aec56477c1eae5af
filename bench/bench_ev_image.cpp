// `radar-emu image` (issue 17): the seed's 94 GHz enhanced-vision image of
// examples/ev_radar_94ghz.toml (30 x 10 deg, 200 x 66 pixels of 0.15 deg), 360 m short of the
// threshold. BM_EvImage/N: the whole product at N looks (scene build, trace, image, optical
// preview at 4 x 4 pixels a radar pixel: what the command computes, without its file writes);
// BM_EvImageForm/N: forming the image alone from one trace's returns.
// Run: build/bench/bench_ev_image --benchmark_repetitions=3 --benchmark_report_aggregates_only=true

#include <benchmark/benchmark.h>

#include <vector>

#include "loop/closed_loop.hpp"
#include "loop/ownship.hpp"
#include "loop/scenario.hpp"
#include "radar/products/ev_image.hpp"
#include "scene/scene.hpp"
#include "tools/image.hpp"

namespace loop = radar_emu::loop;
namespace tools = radar_emu::tools;
namespace radar = radar_emu::radar;

namespace {

constexpr double kTimeS = 52.0;

const loop::Scenario& scenario() {
  static const loop::Scenario s =
      loop::load_scenario(RADAR_EMU_EXAMPLES_DIR "/ev_radar_94ghz.toml");
  return s;
}

void BM_EvImage(benchmark::State& state) {
  const int looks = static_cast<int>(state.range(0));
  std::size_t returns = 0;
  for (auto _ : state) {
    const tools::EvImageProduct p = tools::compute_ev_image(scenario(), kTimeS, looks, 20261124, 4);
    returns = p.contributions;
    benchmark::DoNotOptimize(p.image.intensity_m2.data());
  }
  state.counters["returns"] = static_cast<double>(returns);
}
BENCHMARK(BM_EvImage)->Arg(1)->Arg(10)->Unit(benchmark::kMillisecond)->UseRealTime();

void BM_EvImageForm(benchmark::State& state) {
  const loop::Scenario& s = scenario();
  radar_emu::scene::Scene scene(loop::scene_description(s));
  scene.set_time(kTimeS);
  radar::SbrConfig cfg = s.sbr;
  cfg.reuse_static_paths = false;  // one image's frame traced whole, every iteration
  radar::SbrTracer tracer(scene, cfg);
  radar::RadarPose pose;
  pose.position_m = s.ownship_start_enu_m + s.ownship_velocity_enu_mps * kTimeS;
  pose.world_from_antenna =
      loop::enu_from_body(s.ownship_heading_rad, s.ownship_pitch_rad, s.ownship_roll_rad) *
      loop::body_from_antenna(s.antenna_depression_rad);
  std::vector<radar::Contribution> c(tracer.max_contributions());
  radar::TraceStats stats;
  c.resize(tracer.trace(pose, c, stats));
  radar::EvImageConfig g;
  g.azimuth_min_rad = s.sbr.azimuth_min_rad;
  g.azimuth_max_rad = s.sbr.azimuth_max_rad;
  g.elevation_min_rad = s.sbr.elevation_min_rad;
  g.elevation_max_rad = s.sbr.elevation_max_rad;
  g.pixel_rad = s.beam_spacing_rad;
  g.looks = static_cast<int>(state.range(0));
  for (auto _ : state) {
    const radar::EvImage im = radar::form_ev_image(c, pose, g);
    benchmark::DoNotOptimize(im.intensity_m2.data());
  }
  state.counters["returns"] = static_cast<double>(c.size());
}
BENCHMARK(BM_EvImageForm)->Arg(1)->Arg(10)->Unit(benchmark::kMillisecond)->UseRealTime();

}  // namespace

BENCHMARK_MAIN();
