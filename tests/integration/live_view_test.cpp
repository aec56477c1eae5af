// loop/outputs/live_view.hpp: the frame thread's publish() does not allocate, superseded updates
// are counted, the JSON message carries the frame as given (closed forms for the derived ownship
// values), and --serve addresses are parsed or refused in one line.

#include "loop/outputs/live_view.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <nlohmann/json.hpp>
#include <numbers>
#include <stdexcept>
#include <string>
#include <vector>

#include "loop/closed_loop.hpp"
#include "loop/scenario.hpp"
#include "tests/alloc_counter.hpp"

namespace loop = radar_emu::loop;

namespace {

loop::Scenario scenario() {
  return loop::parse_scenario(loop::default_scenario_toml(), "<default scenario>");
}

loop::LiveViewConfig config(const loop::Scenario& s) {
  loop::LiveViewConfig c;
  c.serve = "127.0.0.1:0";
  c.scenario = &s;
  c.object_names = {"hangar", "tug \"7\""};
  c.max_detections = 8;
  c.max_truth = 4;
  // The server takes a snapshot once at start, then not for an hour: nothing is taken while
  // the test publishes.
  c.update_interval_ms = 3'600'000;
  return c;
}

TEST(LiveView, PublishDoesNotAllocateAndCountsSupersededUpdates) {
  const loop::Scenario s = scenario();
  loop::LiveView view(config(s));
  loop::FrameRecord rec;
  rec.ownship_valid = true;
  std::vector<radar_emu::io::icd::Detection> det(20);  // more than max_detections: clipped
  std::vector<loop::ObjectTruth> truth(3);
  std::array<std::int64_t, radar_emu::timing::kStageCount> stage_ns{};
  std::vector<loop::TargetOutcome> targets(6);  // more than max_truth: clipped
  const loop::OutcomeSoFar outcome{targets, 10, 3};
  radar_emu::test::start_counting_allocations();
  for (std::uint64_t i = 0; i < 10; ++i) {
    rec.frame_index = i;
    view.publish(rec, glm::dvec3(1.0, 2.0, 3.0), stage_ns, det, truth, outcome);
  }
  EXPECT_EQ(radar_emu::test::stop_counting_allocations(), 0u);
  const loop::LiveViewCounters c = view.counters();
  EXPECT_EQ(c.updates_published, 10u);
  EXPECT_EQ(c.updates_dropped, 9u);  // each publish after the first replaced an untaken one
  EXPECT_EQ(c.updates_taken, 0u);
}

TEST(LiveView, MessageCarriesTheFrame) {
  const loop::Scenario s = scenario();
  loop::LiveView view(config(s));
  loop::LiveView::Snapshot snap;
  snap.frame_index = 42;
  snap.time_s = 2.1;
  snap.ownship_valid = true;
  snap.ownship_enu_m = {10.0, -3900.0, 230.0};
  snap.velocity_enu_mps = {-30.0, 0.0, -3.0};  // due west: track 270 deg
  snap.stage_ns.fill(-1);
  snap.stage_ns[static_cast<std::size_t>(radar_emu::timing::Stage::kTrace)] = 12'345'678;
  snap.published = 43;
  snap.dropped = 7;
  snap.detections.resize(2);
  snap.detections[0].azimuth_deg = -3.25;
  snap.detections[0].range_m = 4321.5;
  snap.detections[1].azimuth_deg = 5.5;
  snap.detections[1].range_m = 1000.25;
  snap.detection_count = 2;
  snap.truth.resize(1);
  snap.truth[0].object_id = 1;
  snap.truth[0].azimuth_rad = std::numbers::pi / 180.0 * 2.0;
  snap.truth[0].range_m = 1500.0;
  snap.truth_count = 1;
  // The outcome so far: object 1 in the beam 4 frames, detected in 3 with range errors 1, 2, 3 m
  // (mean 2, sample std 1); object 0 never in the beam (left out of the message).
  snap.targets.resize(2);
  snap.targets[0].object_id = 0;
  snap.targets[1].object_id = 1;
  snap.targets[1].frames_in_beam = 4;
  snap.targets[1].frames_detected = 3;
  for (double e : {1.0, 2.0, 3.0})
    snap.targets[1].range_m.add(e, 0.1);
  snap.target_count = 2;
  snap.frames_scored = 4;
  snap.false_alarms = 2;
  std::string text;
  view.format(snap, true, text);
  const nlohmann::json m = nlohmann::json::parse(text);
  EXPECT_EQ(m["frame"], 42);
  EXPECT_EQ(m["ended"], true);
  EXPECT_EQ(m["scenario"], s.name);
  EXPECT_DOUBLE_EQ(m["layout"]["azimuth_min_deg"].get<double>(),
                   s.sbr.azimuth_min_rad * 180.0 / std::numbers::pi);
  EXPECT_DOUBLE_EQ(m["layout"]["range_max_m"].get<double>(), s.sensor.max_range_m);
  EXPECT_DOUBLE_EQ(m["budget_ms"].get<double>(), 1e3 / s.rate_hz);
  EXPECT_DOUBLE_EQ(m["stages_ms"]["trace"].get<double>(), 12.3457);
  EXPECT_TRUE(m["stages_ms"]["sensor"].is_null());
  EXPECT_DOUBLE_EQ(m["ownship"]["ground_speed_mps"].get<double>(), 30.0);
  EXPECT_DOUBLE_EQ(m["ownship"]["track_deg"].get<double>(), 270.0);
  EXPECT_DOUBLE_EQ(m["ownship"]["climb_mps"].get<double>(), -3.0);
  EXPECT_DOUBLE_EQ(m["ownship"]["north_m"].get<double>(), -3900.0);
  ASSERT_EQ(m["detections"].size(), 2u);
  EXPECT_DOUBLE_EQ(m["detections"][0]["azimuth_deg"].get<double>(), -3.25);
  EXPECT_DOUBLE_EQ(m["detections"][1]["range_m"].get<double>(), 1000.25);
  ASSERT_EQ(m["truth"].size(), 1u);
  EXPECT_EQ(m["truth"][0]["object"], "tug \"7\"");  // escaped in the JSON, intact after
  EXPECT_DOUBLE_EQ(m["truth"][0]["azimuth_deg"].get<double>(), 2.0);
  EXPECT_EQ(m["view"]["dropped"], 7);
  EXPECT_DOUBLE_EQ(m["outcome"]["false_alarms_per_frame"].get<double>(), 0.5);
  ASSERT_EQ(m["outcome"]["targets"].size(), 1u);
  const nlohmann::json& t = m["outcome"]["targets"][0];
  EXPECT_EQ(t["object"], "tug \"7\"");
  EXPECT_EQ(t["frames_in_beam"], 4);
  EXPECT_EQ(t["frames_detected"], 3);
  EXPECT_DOUBLE_EQ(t["pd"].get<double>(), 0.75);
  EXPECT_DOUBLE_EQ(t["range_error_m"][0].get<double>(), 2.0);
  EXPECT_DOUBLE_EQ(t["range_error_m"][1].get<double>(), 1.0);
}

TEST(LiveView, ServeAddresses) {
  EXPECT_EQ(loop::parse_serve_address("127.0.0.1:8080").port, 8080);
  EXPECT_EQ(loop::parse_serve_address(":0").host, "127.0.0.1");
  EXPECT_EQ(loop::parse_serve_address("9000").host, "127.0.0.1");
  EXPECT_EQ(loop::parse_serve_address("[::1]:9000").host, "::1");
  for (const char* bad : {"", "host:", "host:65536", "host:-1", "host:80x"}) {
    try {
      (void)loop::parse_serve_address(bad);
      ADD_FAILURE() << bad;
    } catch (const std::invalid_argument& e) {
      EXPECT_EQ(std::string(e.what()),
                std::string("--serve '") + bad +
                    "': expected HOST:PORT, :PORT or PORT with a port 0-65535");
    }
  }
}

TEST(LiveView, PortInUseNamesTheOption) {
  const loop::Scenario s = scenario();
  loop::LiveView first(config(s));
  loop::LiveViewConfig c = config(s);
  c.serve = first.address();
  try {
    loop::LiveView second(c);
    FAIL() << "bound a port in use";
  } catch (const std::runtime_error& e) {
    EXPECT_EQ(std::string(e.what()),
              "--serve " + first.address() + ": cannot listen: Address already in use");
  }
}

}  // namespace
