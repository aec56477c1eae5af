// The live view's cost to the frame loop (docs/live_view.md, docs/performance.md):
// BM_LiveViewPublish, one publish() of a full frame (64 detections, 64 objects in the beam), with
// the server idle (arg 0) or taking and formatting a snapshot every millisecond (arg 1: the
// exchange contends with the server thread's); BM_FrameWithView, whole frames of the default
// scenario on the simulated clock without (arg 0) and with (arg 1) `--serve`, side by side.

#include <benchmark/benchmark.h>

#include <vector>

#include "loop/closed_loop.hpp"
#include "loop/outputs/live_view.hpp"
#include "loop/scenario.hpp"

namespace loop = radar_emu::loop;

namespace {

void BM_LiveViewPublish(benchmark::State& state) {
  const loop::Scenario s = loop::parse_scenario(loop::default_scenario_toml(), "<default>");
  loop::LiveViewConfig c;
  c.serve = "127.0.0.1:0";
  c.scenario = &s;
  c.max_detections = 64;
  c.max_truth = 64;
  c.update_interval_ms = state.range(0) == 0 ? 3'600'000 : 1;
  loop::LiveView view(c);
  loop::FrameRecord rec;
  rec.ownship_valid = true;
  std::vector<radar_emu::io::icd::Detection> det(64);
  std::vector<loop::ObjectTruth> truth(64);
  for (std::size_t i = 0; i < det.size(); ++i) {
    det[i].azimuth_deg = -8.0 + 0.25 * static_cast<double>(i);
    det[i].range_m = 100.0 * static_cast<double>(i);
  }
  std::array<std::int64_t, radar_emu::timing::kStageCount> stage_ns{};
  std::uint64_t frame = 0;
  for (auto _ : state) {
    rec.frame_index = frame++;
    view.publish(rec, glm::dvec3(0.0, 70.0, -3.7), stage_ns, det, truth);
  }
  const loop::LiveViewCounters k = view.counters();
  state.counters["taken"] = static_cast<double>(k.updates_taken);
  state.counters["dropped"] = static_cast<double>(k.updates_dropped);
}
BENCHMARK(BM_LiveViewPublish)->Arg(0)->Arg(1)->Unit(benchmark::kNanosecond)->UseRealTime();

void BM_FrameWithView(benchmark::State& state) {
  loop::Scenario s = loop::parse_scenario(loop::default_scenario_toml(), "<default>");
  s.frames = 1'000'000;
  loop::RunOptions o;
  o.record_frames_max = 0;
  o.timing_frames_max = 1;
  if (state.range(0) != 0)
    o.serve = "127.0.0.1:0";
  loop::ClosedLoop loop(s, o);
  loop.begin();
  loop::FrameOutput out;
  for (auto _ : state) {
    if (!loop.step(out))
      state.SkipWithError("the scenario ended");
  }
  if (const auto k = loop.live_view_counters()) {
    state.counters["taken"] = static_cast<double>(k->updates_taken);
    state.counters["dropped"] = static_cast<double>(k->updates_dropped);
  }
}
BENCHMARK(BM_FrameWithView)
    ->Arg(0)
    ->Arg(1)
    ->Arg(0)
    ->Arg(1)
    ->Iterations(200)
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();

}  // namespace

BENCHMARK_MAIN();
