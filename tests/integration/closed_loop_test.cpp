// The closed loop on the software bus, end to end, checked against geometry this test computes
// on its own: ownship on its scripted straight line, objects where the scene description puts
// them, cells from the radar's parameters (c / 2B, lambda PRF / 4, azimuth cell width).

#include "loop/closed_loop.hpp"

#include <gtest/gtest.h>
#include <stb/stb_image.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <csignal>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <nlohmann/json.hpp>
#include <numbers>
#include <sstream>
#include <string>
#include <vector>

#include "common/units.hpp"
#include "io/candump.hpp"
#include "io/detection_icd.hpp"
#include "loop/outputs/run_plots.hpp"
#include "loop/scenario.hpp"
#include "radar/propagation/itu.hpp"
#include "scene/airport_gen.hpp"
#include "tests/alloc_counter.hpp"

namespace loop = radar_emu::loop;
namespace fs = std::filesystem;

namespace {

constexpr double kC_mps = 299792458.0;
namespace common = radar_emu::common;

fs::path temp_dir(const std::string& name) {
  // One directory per process: CTest runs each test of a suite as its own process, in parallel,
  // and the outputs are written while the run goes (a shared directory would be clobbered).
  const fs::path p =
      fs::temp_directory_path() / ("radar_emu_it_" + name + "_" + std::to_string(getpid()));
  fs::remove_all(p);
  fs::create_directories(p);
  return p;
}

std::string slurp(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  std::ostringstream os;
  os << in.rdbuf();
  return os.str();
}

// What the test knows about one object at one time, in the world ENU frame.
struct TruthObject {
  std::string name;
  std::vector<glm::dvec3> vertices_m;
  glm::dvec3 velocity_mps{0.0};
};

std::vector<TruthObject> objects_at(const radar_emu::scene::SceneDescription& d, double t_s) {
  std::vector<TruthObject> out;
  for (const auto& o : d.objects) {
    // Objects that stand up: everything but the flat ground and pavements (metal or not: the
    // airport's concrete hangars and terminal are strong reflectors at 94 GHz too).
    float z_lo = 1e30f, z_hi = -1e30f;
    for (const auto& p : o.mesh.positions_m) {
      z_lo = std::min(z_lo, p.z);
      z_hi = std::max(z_hi, p.z);
    }
    if (z_hi - z_lo < 1.0f)
      continue;
    TruthObject t;
    t.name = o.name;
    if (o.motion) {
      // Moving objects: body origin at start + v t, body x along the horizontal velocity.
      const glm::dvec3 v = o.motion->velocity_mps;
      const double yaw = std::atan2(v.y, v.x);
      const glm::dvec3 p = o.motion->start_position_m + v * t_s;
      for (const auto& bf : o.mesh.positions_m) {
        const glm::dvec3 b(bf);
        t.vertices_m.push_back(p + glm::dvec3(std::cos(yaw) * b.x - std::sin(yaw) * b.y,
                                              std::sin(yaw) * b.x + std::cos(yaw) * b.y, b.z));
      }
      t.velocity_mps = v;
    } else {
      for (const auto& b : o.mesh.positions_m) {
        t.vertices_m.push_back(glm::dvec3(o.world_from_body * glm::dvec4(glm::dvec3(b), 1.0)));
      }
    }
    out.push_back(std::move(t));
  }
  return out;
}

// Antenna axes for a wings-level aircraft (roll 0): heading h from north clockwise, boresight
// elevated by pitch - depression.
struct Antenna {
  glm::dvec3 boresight, right, up;
};
Antenna antenna_axes(double heading_rad, double elevation_rad) {
  Antenna a;
  a.boresight = {std::sin(heading_rad) * std::cos(elevation_rad),
                 std::cos(heading_rad) * std::cos(elevation_rad), std::sin(elevation_rad)};
  a.right = {std::cos(heading_rad), -std::sin(heading_rad), 0.0};
  a.up = glm::cross(a.right, a.boresight);
  return a;
}

struct Window {
  double range_min_m = 1e30, range_max_m = -1e30;
  double az_min_rad = 1e30, az_max_rad = -1e30;
  double el_min_rad = 1e30, el_max_rad = -1e30;
  double vr_min_mps = 1e30, vr_max_mps = -1e30;
};

Window window_of(const TruthObject& o, const glm::dvec3& radar, const glm::dvec3& v_radar,
                 const Antenna& a) {
  Window w;
  for (const glm::dvec3& p : o.vertices_m) {
    const glm::dvec3 d = p - radar;
    const double r = glm::length(d);
    const glm::dvec3 u = d / r;
    w.range_min_m = std::min(w.range_min_m, r);
    w.range_max_m = std::max(w.range_max_m, r);
    const double az = std::atan2(glm::dot(u, a.right), glm::dot(u, a.boresight));
    const double el = std::asin(std::clamp(glm::dot(u, a.up), -1.0, 1.0));
    w.az_min_rad = std::min(w.az_min_rad, az);
    w.az_max_rad = std::max(w.az_max_rad, az);
    w.el_min_rad = std::min(w.el_min_rad, el);
    w.el_max_rad = std::max(w.el_max_rad, el);
    const double vr = glm::dot(o.velocity_mps - v_radar, u);  // range rate, + receding
    w.vr_min_mps = std::min(w.vr_min_mps, vr);
    w.vr_max_mps = std::max(w.vr_max_mps, vr);
  }
  // The nearest point of a face can be nearer than every vertex: widen by the object's size
  // projected across the line of sight (bounded by its half extent).
  return w;
}

struct Cells {
  double range_cell_m, az_min_rad, az_cell_rad, v_ua_mps, doppler_cell_mps;
  int n_doppler;
  long range_cell(double r) const { return static_cast<long>(std::floor(r / range_cell_m)); }
  long az_cell(double az) const {
    return static_cast<long>(std::floor((az - az_min_rad) / az_cell_rad));
  }
  // Fold into [-v_ua, v_ua) (a sampled Doppler spectrum is periodic in 2 v_ua).
  double fold(double v) const {
    return v - 2.0 * v_ua_mps * std::floor((v + v_ua_mps) / (2.0 * v_ua_mps));
  }
  // FFT bins centred on multiples of the cell width, zero velocity at index N/2.
  long doppler_cell(double v) const {
    const long bin = std::lround(fold(v) / doppler_cell_mps);
    return ((bin + n_doppler / 2) % n_doppler + n_doppler) % n_doppler;
  }
  long doppler_distance(long a, long b) const {
    const long d = std::labs(a - b) % n_doppler;
    return std::min(d, n_doppler - d);
  }
};

Cells cells_of(const loop::Scenario& s) {
  Cells c{};
  const auto& w = s.sensor.processing.waveform;
  c.range_cell_m = kC_mps / (2.0 * w.bandwidth_hz);
  c.az_min_rad = s.sbr.azimuth_min_rad;
  c.az_cell_rad = s.beam_spacing_rad;
  const double lambda = kC_mps / w.carrier_hz;
  c.v_ua_mps = lambda * s.prf_hz / 4.0;
  c.n_doppler = w.pulses;
  c.doppler_cell_mps = 2.0 * c.v_ua_mps / w.pulses;
  return c;
}

// The scripted ownship's true position at scenario time t, and its antenna axes (the default
// flies wings level, so the antenna is the body pitched by pitch - depression).
glm::dvec3 ownship_at(const loop::Scenario& s, double t_s) {
  return s.ownship_start_enu_m + s.ownship_velocity_enu_mps * t_s;
}
Antenna scenario_antenna(const loop::Scenario& s) {
  return antenna_axes(s.ownship_heading_rad, s.ownship_pitch_rad - s.antenna_depression_rad);
}

loop::Scenario default_scenario() {
  return loop::parse_scenario(loop::default_scenario_toml(), "<default scenario>");
}

// The default scenario flies over the generated airport (scene/airport_gen.hpp).
radar_emu::scene::SceneDescription scenario_scene(const loop::Scenario& s) {
  EXPECT_EQ(s.scene_builtin, "airport");
  radar_emu::scene::AirportSpec spec;
  spec.seed = s.scene_seed;
  spec.corner_reflectors = s.scene_corner_reflectors;
  return radar_emu::scene::generate_airport(spec);
}

}  // namespace

class ClosedLoopDefault : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    scenario_ = new loop::Scenario(default_scenario());
    // The default scenario as a test range would fly it: the four closed-loop objects carry
    // their trihedrals ([scene] corner_reflectors), so that "detected in every frame with it in
    // the beam" is a statement about geometry. Without them they are detected from their own
    // ground coupling in 84-96 % of frames (docs/architecture.md).
    scenario_->scene_corner_reflectors = true;
    ASSERT_GE(scenario_->frames, 200u);
    loop::RunOptions options;
    // Count heap allocations between frame 5 and the end: the frame path must not allocate.
    options.progress = radar_emu::test::count_allocations_from_frame(5);
    // The stage timeline too: its buffer is preallocated, so it adds no allocation.
    trace_file_ = temp_dir("default_trace") / "trace.json";
    options.trace_events_file = trace_file_;
    // The outputs stream during the run: the writer thread must not allocate either.
    out_ = temp_dir("default");
    options.out_dir = out_;
    loop_ = new loop::ClosedLoop(*scenario_, options);
    result_ = new loop::RunResult(loop_->run());
    allocations_ = radar_emu::test::stop_counting_allocations();  // the count frozen at the end
    // The renderer also writes where each figure's data area landed (plot/render.py).
    ::setenv("RADAR_EMU_PLOT_AXES", "1", 1);
    loop_->write_outputs(*result_);
    ::unsetenv("RADAR_EMU_PLOT_AXES");
    loop_->write_trace_events();
  }
  static void TearDownTestSuite() {
    delete result_;
    delete loop_;
    delete scenario_;
    fs::remove_all(out_);
    fs::remove_all(trace_file_.parent_path());
  }
  static loop::Scenario* scenario_;
  static loop::ClosedLoop* loop_;
  static loop::RunResult* result_;
  static std::uint64_t allocations_;
  static fs::path out_;
  static fs::path trace_file_;
};
loop::Scenario* ClosedLoopDefault::scenario_ = nullptr;
loop::ClosedLoop* ClosedLoopDefault::loop_ = nullptr;
loop::RunResult* ClosedLoopDefault::result_ = nullptr;
std::uint64_t ClosedLoopDefault::allocations_ = 0;
fs::path ClosedLoopDefault::out_;
fs::path ClosedLoopDefault::trace_file_;

TEST_F(ClosedLoopDefault, EveryFrameRunsWithAValidStateAndReachesTheAvionics) {
  const auto& r = *result_;
  EXPECT_EQ(r.frames, scenario_->frames);
  // The navigation data start at t = 0, so every frame has a fresh state.
  EXPECT_EQ(r.frames_valid, r.frames);
  EXPECT_EQ(r.decoder.rejected(), 0u);
  EXPECT_EQ(r.decoder.message_code_gaps, 0u);
  EXPECT_EQ(r.sink_lists, r.frames);
  EXPECT_EQ(r.sink_malformed, 0u);
  EXPECT_EQ(r.bus_rx_overflows, 0u);
  EXPECT_EQ(r.record_overflows, 0u);
  EXPECT_EQ(r.trace.dropped_contributions, 0u);
  EXPECT_GT(r.detections_total, 0u);
}

TEST_F(ClosedLoopDefault, DetectionsMatchIndependentGeometry) {
  const loop::Scenario& s = *scenario_;
  const Cells cells = cells_of(s);
  // The airport's objects are where its description puts them. The four objects carrying
  // corner reflectors must be detected in every frame that has them in the beam; a detection of
  // any object standing on the ground (aircraft, vehicles, masts, hangars, terminal) is no false
  // alarm.
  const auto desc = scenario_scene(s);
  const std::vector<std::string> with_reflector{"parked_aircraft", "parked_vehicle", "light_mast",
                                                "moving_vehicle"};
  const Antenna ant = scenario_antenna(s);
  std::size_t frames_checked = 0, unmatched = 0;
  std::vector<std::size_t> detected_frames_per_object;
  std::vector<std::string> names;
  for (const loop::FrameRecord& rec : result_->records) {
    const double t = rec.time_s;
    const glm::dvec3 radar = ownship_at(s, t);
    const std::vector<TruthObject> objects = objects_at(desc, t);
    if (names.empty()) {
      for (const auto& o : objects)
        names.push_back(o.name);
      detected_frames_per_object.assign(objects.size(), 0);
      std::size_t found = 0;
      for (const auto& n : names)
        found +=
            static_cast<std::size_t>(std::count(with_reflector.begin(), with_reflector.end(), n));
      ASSERT_EQ(found, 4u) << "the airport keeps the four closed-loop objects";
    }
    std::vector<Window> windows;
    std::vector<bool> in_beam;
    for (const auto& o : objects) {
      const Window w = window_of(o, radar, s.ownship_velocity_enu_mps, ant);
      windows.push_back(w);
      in_beam.push_back(
          w.az_min_rad > s.sbr.azimuth_min_rad && w.az_max_rad < s.sbr.azimuth_max_rad &&
          w.el_min_rad > s.sbr.elevation_min_rad && w.el_max_rad < s.sbr.elevation_max_rad &&
          w.range_max_m < s.sensor.max_range_m);
    }
    std::vector<bool> detected(objects.size(), false);
    for (std::uint32_t i = 0; i < rec.detection_count; ++i) {
      const auto& d = result_->detections[rec.first_detection + i];
      const long rc = cells.range_cell(d.range_m);
      const long ac = cells.az_cell(common::radians(d.azimuth_deg));
      const long dc = cells.doppler_cell(d.radial_velocity_mps);
      bool matched = false;
      for (std::size_t k = 0; k < objects.size(); ++k) {
        const Window& w = windows[k];
        const bool range_ok =
            rc >= cells.range_cell(w.range_min_m) - 1 && rc <= cells.range_cell(w.range_max_m) + 1;
        const bool az_ok =
            ac >= cells.az_cell(w.az_min_rad) - 1 && ac <= cells.az_cell(w.az_max_rad) + 1;
        const bool doppler_ok = cells.doppler_distance(dc, cells.doppler_cell(w.vr_min_mps)) <= 1 ||
                                cells.doppler_distance(dc, cells.doppler_cell(w.vr_max_mps)) <= 1;
        if (range_ok && az_ok && doppler_ok) {
          matched = true;
          detected[k] = true;
        }
      }
      if (!matched && ++unmatched <= 10) {
        std::cout << "  frame " << rec.header.frame_counter << ": unmatched detection at "
                  << d.range_m << " m, az " << d.azimuth_deg << " deg, vr " << d.radial_velocity_mps
                  << " m/s, SNR " << d.snr_db << " dB\n";
      }
      EXPECT_LE(std::abs(common::radians(d.azimuth_deg)), s.sbr.azimuth_max_rad + 1e-9);
    }
    for (std::size_t k = 0; k < objects.size(); ++k) {
      if (!in_beam[k])
        continue;
      if (detected[k])
        ++detected_frames_per_object[k];
      if (std::find(with_reflector.begin(), with_reflector.end(), objects[k].name) ==
          with_reflector.end()) {
        continue;  // no reflector: reported below, not required
      }
      EXPECT_TRUE(detected[k]) << "frame " << rec.header.frame_counter << " t=" << t
                               << " s: " << objects[k].name << " inside the beam at range "
                               << windows[k].range_min_m << ".." << windows[k].range_max_m
                               << " m, az " << windows[k].az_min_rad / common::kRadPerDeg << ".."
                               << windows[k].az_max_rad / common::kRadPerDeg << " deg, vr "
                               << windows[k].vr_min_mps << " m/s was not detected";
    }
    ++frames_checked;
  }
  EXPECT_EQ(frames_checked, s.frames);
  // Detections that match no object are false alarms (receiver noise, clutter speckle). Their
  // number must agree with detection theory: a noise cell crosses when its power exceeds
  // max(alpha, 1 + min SNR) times the mean of N training cells, probability
  // (1 + T / N)^-N (Richards 2014, eq. 6.134); allow twice the expectation plus Poisson slack.
  const auto& cf = s.sensor.cfar;
  const double n_train =
      2.0 * cf.range_training * (2 * cf.velocity_training + 2 * cf.velocity_guard + 1) +
      2.0 * cf.velocity_training * (2 * cf.range_guard + 1);
  const double alpha = n_train * (std::pow(cf.pfa, -1.0 / n_train) - 1.0);
  const double t = std::max(alpha, 1.0 + std::pow(10.0, s.sensor.min_snr_db / 10.0));
  const double pfa_eff = std::pow(1.0 + t / n_train, -n_train);
  const auto& w = s.sensor.processing.waveform;
  const double image_cells = static_cast<double>(frames_checked) * w.range_bins * w.pulses *
                             static_cast<double>(s.sensor.antenna.beam_azimuth_rad.size());
  const double expected = image_cells * pfa_eff;
  std::cout << "  unmatched detections: " << unmatched << " in " << frames_checked
            << " frames; false alarms expected " << expected << " (" << image_cells
            << " cells, Pfa " << pfa_eff << ")\n";
  EXPECT_LE(static_cast<double>(unmatched), 2.0 * expected + 3.0 * std::sqrt(expected) + 5.0);
  for (std::size_t k = 0; k < names.size(); ++k) {
    std::cout << "  " << names[k] << ": detected in " << detected_frames_per_object[k] << "/"
              << frames_checked << " frames\n";
  }
}

// The summary says what was seen (issue 29): one row per object that was in the beam, its
// frames in the beam counted here from the recorded truth, the four objects carrying corner
// reflectors detected in every such frame (as DetectionsMatchIndependentGeometry requires), the
// false alarms over every detection; and where the governor degraded frames, "N of M frames
// degraded (levels a-b, est. X dB)" with N, a and b counted here from the per-frame levels.
TEST_F(ClosedLoopDefault, SummaryGivesTheOutcomePerTargetAndTheDegradedFrames) {
  const loop::RunResult& r = *result_;
  const loop::RunReport rep = loop_->report(r);
  char* buf = nullptr;
  std::size_t len = 0;
  std::FILE* mem = open_memstream(&buf, &len);
  ASSERT_NE(mem, nullptr);
  loop::print_summary(rep, mem);
  std::fclose(mem);
  const std::string text(buf, len);
  std::free(buf);
  std::cout << text;

  ASSERT_EQ(r.records.size(), r.frames) << "every frame recorded";
  std::map<std::uint32_t, std::uint64_t> in_beam;
  for (const loop::FrameRecord& rec : r.records) {
    for (std::uint32_t k = 0; k < rec.truth_count; ++k)
      ++in_beam[r.truth[rec.first_truth + k].object_id];
  }
  ASSERT_FALSE(in_beam.empty());
  const std::vector<std::string> with_reflector{"parked_aircraft", "parked_vehicle", "light_mast",
                                                "moving_vehicle"};
  std::size_t reflectors_seen = 0;
  for (const loop::TargetOutcome& t : r.outcome.targets) {
    const std::string& name = rep.object_names.at(t.object_id);
    EXPECT_EQ(t.frames_in_beam, in_beam[t.object_id]) << name;
    EXPECT_LE(t.frames_detected, t.frames_in_beam) << name;
    if (t.frames_in_beam == 0)
      continue;
    std::istringstream rows(text);
    std::string line;
    bool found = false;
    while (std::getline(rows, line)) {
      std::istringstream cols(line);
      std::string first;
      std::uint64_t beam = 0, detected = 0;
      double pd = -1.0;
      if (line.rfind("    ", 0) == 0 && (cols >> first >> beam >> detected >> pd) &&
          first == name) {
        found = true;
        EXPECT_EQ(beam, in_beam[t.object_id]) << line;
        EXPECT_EQ(detected, t.frames_detected) << line;
        // Printed with two decimals: off by at most half a unit (and the binary rounding of it).
        EXPECT_NEAR(pd, static_cast<double>(detected) / static_cast<double>(beam), 0.005 + 1e-9)
            << line;
      }
    }
    EXPECT_TRUE(found) << "no summary row for " << name;
    if (std::find(with_reflector.begin(), with_reflector.end(), name) != with_reflector.end()) {
      ++reflectors_seen;
      EXPECT_EQ(t.frames_detected, t.frames_in_beam) << name << " carries a corner reflector";
      // Its associated detection lies within its gate: the range error within a cell plus its
      // size (a few metres), whatever its mean.
      EXPECT_LT(std::abs(t.range_m.mean), 25.0) << name;
    }
  }
  EXPECT_EQ(reflectors_seen, 4u);
  EXPECT_NE(text.find(" of " + std::to_string(r.detections_total) + " detections associated"),
            std::string::npos);
  EXPECT_EQ(r.outcome.detections, r.detections_total);

  std::uint64_t degraded = 0;
  int lowest = 99, highest = 0;
  for (const std::int8_t l : r.governor.per_frame_level) {
    if (l > 0) {
      ++degraded;
      lowest = std::min<int>(lowest, l);
      highest = std::max<int>(highest, l);
    }
  }
  if (degraded == 0) {
    EXPECT_EQ(text.find("frames degraded"), std::string::npos);
    return;
  }
  char want[160];
  std::snprintf(want, sizeof want,
                "  governor    %llu of %llu frames degraded (levels %d-%d, est. %.1f dB)\n",
                static_cast<unsigned long long>(degraded),
                static_cast<unsigned long long>(r.frames), lowest, highest,
                loop::FidelityGovernor::kLevelSnrError_db[static_cast<std::size_t>(highest)]);
  EXPECT_NE(text.find(want), std::string::npos) << "expected: " << want;
  EXPECT_NE(text.find("not on this scenario"), std::string::npos);
}

TEST_F(ClosedLoopDefault, MovingVehicleRadialVelocityFromItsKnownVelocity) {
  // Tighter than the cell check: the reported radial velocity (a Doppler cell centre) is within
  // one Doppler cell of the value computed from the vehicle's and the ownship's known velocities.
  const loop::Scenario& s = *scenario_;
  const Cells cells = cells_of(s);
  const auto desc = scenario_scene(s);
  const Antenna ant = scenario_antenna(s);
  std::size_t frames_with_vehicle = 0;
  for (const loop::FrameRecord& rec : result_->records) {
    const glm::dvec3 radar = ownship_at(s, rec.time_s);
    for (const auto& o : objects_at(desc, rec.time_s)) {
      if (o.name != "moving_vehicle")
        continue;
      const Window w = window_of(o, radar, s.ownship_velocity_enu_mps, ant);
      const double vr_expected = cells.fold(0.5 * (w.vr_min_mps + w.vr_max_mps));
      bool found = false;
      for (std::uint32_t i = 0; i < rec.detection_count; ++i) {
        const auto& d = result_->detections[rec.first_detection + i];
        const long rc = cells.range_cell(d.range_m);
        if (rc < cells.range_cell(w.range_min_m) - 1 || rc > cells.range_cell(w.range_max_m) + 1) {
          continue;
        }
        if (std::abs(d.radial_velocity_mps - vr_expected) <= cells.doppler_cell_mps)
          found = true;
      }
      EXPECT_TRUE(found) << "t=" << rec.time_s << " expected vr " << vr_expected;
      ++frames_with_vehicle;
    }
  }
  EXPECT_EQ(frames_with_vehicle, s.frames);
}

TEST_F(ClosedLoopDefault, FramePathDoesNotAllocate) {
  EXPECT_EQ(allocations_, 0u) << "heap allocations between frame 5 and the last frame";
}

TEST_F(ClosedLoopDefault, ReportHoldsStageTimingsAndCounters) {
  std::ifstream in(out_ / "report.json");
  ASSERT_TRUE(in) << "report.json missing";
  const nlohmann::json rep = nlohmann::json::parse(in);
  for (const char* stage : {"input", "scene_update", "trace", "sensor", "output", "frame"}) {
    ASSERT_TRUE(rep["stage_timing"].contains(stage)) << stage;
    EXPECT_EQ(rep["stage_timing"][stage]["count"].get<std::uint64_t>(), scenario_->frames);
    for (const char* k : {"p50_ms", "p99_ms", "max_ms"}) {
      EXPECT_TRUE(rep["stage_timing"][stage][k].is_number()) << stage << "." << k;
    }
  }
  EXPECT_EQ(rep["frames"].get<std::uint64_t>(), scenario_->frames);
  EXPECT_TRUE(rep["input"]["rejected_by_reason"].contains("short_frame"));
  for (const char* f : {"detections.json", "bus_in.log", "bus_out.log"}) {
    EXPECT_TRUE(fs::exists(out_ / f)) << f;
  }
}

TEST_F(ClosedLoopDefault, BusOutputDecodesToTheDetectionsWithinIcdQuantisation) {
  // Read our own candump log back and reassemble lists with the ICD decoder: what went on the
  // bus is what detections.json says, within half a quantisation step.
  const auto lines = radar_emu::io::read_candump_file(out_ / "bus_out.log");
  radar_emu::io::icd::ListDecoder dec;
  std::size_t list_index = 0;
  for (const auto& line : lines) {
    if (dec.feed(line.frame) != radar_emu::io::icd::FeedStatus::kComplete)
      continue;
    ASSERT_LT(list_index, result_->records.size());
    const loop::FrameRecord& rec = result_->records[list_index++];
    const auto& got = dec.list();
    ASSERT_EQ(got.count, rec.detection_count);
    EXPECT_EQ(got.header.frame_counter, rec.header.frame_counter);
    for (std::size_t i = 0; i < got.count; ++i) {
      const auto& want = result_->detections[rec.first_detection + i];
      namespace icd = radar_emu::io::icd;
      EXPECT_NEAR(got.detections[i].range_m, want.range_m, icd::kRangeScale_m / 2 + 1e-9);
      EXPECT_NEAR(got.detections[i].azimuth_deg, want.azimuth_deg, icd::kAngleScale_deg / 2 + 1e-9);
      EXPECT_NEAR(got.detections[i].elevation_deg, want.elevation_deg,
                  icd::kAngleScale_deg / 2 + 1e-9);
      EXPECT_NEAR(got.detections[i].radial_velocity_mps, want.radial_velocity_mps,
                  icd::kRadialVelocityScale_mps / 2 + 1e-9);
    }
  }
  EXPECT_EQ(list_index, result_->records.size());
}

TEST_F(ClosedLoopDefault, PictureShowsEachDetectionWhereItIs) {
  // Decode detections.png with stb_image (independent of matplotlib) and look at the pixel of
  // the first and last frames' detections, placed through the data area the renderer reports
  // (detections.axes.json: its pixel box and axis limits), and at an empty corner.
  int w = 0, h = 0, channels = 0;
  unsigned char* px = stbi_load((out_ / "detections.png").c_str(), &w, &h, &channels, 3);
  ASSERT_NE(px, nullptr) << "detections.png missing or not a PNG";
  EXPECT_EQ(w, loop::BScope::kWidth);
  EXPECT_EQ(h, loop::BScope::kHeight);
  EXPECT_TRUE(fs::exists(out_ / "detections.svg"));
  std::ifstream axes_in(out_ / "detections.axes.json");
  ASSERT_TRUE(axes_in) << "detections.axes.json";
  const nlohmann::json ax = nlohmann::json::parse(axes_in).at("panels").at(0);
  const double x0 = ax.at("x0"), x1 = ax.at("x1"), y0 = ax.at("y0"), y1 = ax.at("y1");
  const double az0 = ax.at("xlim")[0], az1 = ax.at("xlim")[1];
  const double r0 = ax.at("ylim")[0], r1 = ax.at("ylim")[1];
  EXPECT_NEAR(az0, scenario_->sbr.azimuth_min_rad * 180.0 / std::numbers::pi, 1e-9);
  EXPECT_NEAR(r1, scenario_->sensor.max_range_m * 1e-3, 1e-9);
  auto rgb = [&](double azimuth_deg, double range_m) {
    const int x = static_cast<int>(x0 + (azimuth_deg - az0) / (az1 - az0) * (x1 - x0));
    const int y = static_cast<int>(y1 - (range_m * 1e-3 - r0) / (r1 - r0) * (y1 - y0));
    const unsigned char* p = px + (static_cast<std::size_t>(y) * static_cast<std::size_t>(w) +
                                   static_cast<std::size_t>(x)) *
                                      3;
    return std::array<int, 3>{p[0], p[1], p[2]};
  };
  const std::array<int, 3> background{255, 255, 255};
  EXPECT_EQ(rgb(az0 + 0.02 * (az1 - az0), 0.98 * r1 * 1e3), background) << "empty corner";
  for (const loop::FrameRecord* rec : {&result_->records.front(), &result_->records.back()}) {
    ASSERT_GT(rec->detection_count, 0u);
    const auto& d = result_->detections[rec->first_detection];
    EXPECT_NE(rgb(d.azimuth_deg, d.range_m), background) << "no dot at range " << d.range_m;
  }
  // Colour encodes time (plasma: blue-violet at the first frame, yellow at the last).
  const auto& first = result_->detections[result_->records.front().first_detection];
  const auto& last = result_->detections[result_->records.back().first_detection];
  const auto cf = rgb(first.azimuth_deg, first.range_m);
  const auto cl = rgb(last.azimuth_deg, last.range_m);
  EXPECT_GT(cf[2], cf[0]);
  EXPECT_GT(cl[0], cl[2]);
  stbi_image_free(px);
}

TEST_F(ClosedLoopDefault, TraceEventsHoldEveryStageOfEveryFrameInsideTheFrame) {
  // Chrome trace-event JSON read back with nlohmann: one complete ("X") event per stage per
  // frame, durations >= 0, the stages inside their frame and summing to no more than it.
  std::ifstream in(trace_file_);
  ASSERT_TRUE(in) << trace_file_;
  const nlohmann::json doc = nlohmann::json::parse(in);
  const auto& events = doc.at("traceEvents");
  const std::vector<std::string> stages{"input", "scene_update", "trace", "sensor", "output"};
  struct PerFrame {
    std::map<std::string, int> count;
    double sum_us = 0.0, frame_ts = -1.0, frame_dur = -1.0, first_ts = 1e300, last_end = -1e300;
  };
  std::map<std::uint64_t, PerFrame> frames;
  for (const auto& e : events) {
    ASSERT_EQ(e.at("ph"), "X");
    ASSERT_TRUE(e.contains("pid") && e.contains("tid"));
    const std::string name = e.at("name");
    const double ts = e.at("ts"), dur = e.at("dur");
    EXPECT_GE(ts, 0.0);
    EXPECT_GE(dur, 0.0) << name;
    PerFrame& f = frames[e.at("args").at("frame").get<std::uint64_t>()];
    ++f.count[name];
    if (name == "frame") {
      f.frame_ts = ts;
      f.frame_dur = dur;
    } else {
      f.sum_us += dur;
      f.first_ts = std::min(f.first_ts, ts);
      f.last_end = std::max(f.last_end, ts + dur);
    }
  }
  ASSERT_EQ(frames.size(), scenario_->frames);
  EXPECT_EQ(events.size(), scenario_->frames * (stages.size() + 1));
  for (const auto& [index, f] : frames) {
    for (const std::string& st : stages)
      EXPECT_EQ(f.count.count(st) ? f.count.at(st) : 0, 1) << "frame " << index << " " << st;
    ASSERT_EQ(f.count.at("frame"), 1);
    EXPECT_LE(f.sum_us, f.frame_dur + 1e-6) << "frame " << index;
    EXPECT_GE(f.first_ts, f.frame_ts - 1e-6) << "frame " << index;
    EXPECT_LE(f.last_end, f.frame_ts + f.frame_dur + 1e-6) << "frame " << index;
  }
  EXPECT_EQ(result_->trace_events_dropped, 0u);
}

TEST_F(ClosedLoopDefault, TimingPictureHasItsSize) {
  int w = 0, h = 0, channels = 0;
  unsigned char* px = stbi_load((out_ / "timing.png").c_str(), &w, &h, &channels, 3);
  ASSERT_NE(px, nullptr) << "timing.png missing or not a PNG";
  EXPECT_EQ(w, loop::kTimingPngWidth);
  EXPECT_EQ(h, loop::kTimingPngHeight);
  stbi_image_free(px);
}

TEST_F(ClosedLoopDefault, TruthOfTheMovingVehicleIsItsClosedFormGeometry) {
  // truth.json against geometry computed here: the vehicle's box centre from its description
  // (start + v t, body x along v), seen from the frame's antenna position on the scenario's
  // attitude (the antenna axes of antenna_axes()), range rate (v_vehicle - v_ownship) . u.
  const loop::Scenario& s = *scenario_;
  std::ifstream in(out_ / "truth.json");
  ASSERT_TRUE(in);
  const nlohmann::json truth = nlohmann::json::parse(in);
  ASSERT_EQ(truth.at("frames").size(), result_->records.size());
  const auto desc = scenario_scene(s);
  const Antenna ant = scenario_antenna(s);
  std::size_t checked = 0;
  for (std::size_t k = 0; k < result_->records.size(); ++k) {
    const loop::FrameRecord& rec = result_->records[k];
    const nlohmann::json& frame = truth.at("frames")[k];
    for (const TruthObject& o : objects_at(desc, rec.time_s)) {
      if (o.name != "moving_vehicle")
        continue;
      glm::dvec3 lo(1e300), hi(-1e300);
      for (const glm::dvec3& v : o.vertices_m) {
        lo = glm::min(lo, v);
        hi = glm::max(hi, v);
      }
      const glm::dvec3 d = 0.5 * (lo + hi) - rec.ownship_enu_m;
      const double range = glm::length(d);
      const glm::dvec3 u = d / range;
      const double az = std::atan2(glm::dot(u, ant.right), glm::dot(u, ant.boresight));
      const double el = std::asin(glm::dot(u, ant.up));
      const double vr = glm::dot(o.velocity_mps - s.ownship_velocity_enu_mps, u);
      const bool inside = az > s.sbr.azimuth_min_rad + 1e-3 && az < s.sbr.azimuth_max_rad - 1e-3 &&
                          el > s.sbr.elevation_min_rad + 1e-3 &&
                          el < s.sbr.elevation_max_rad - 1e-3 && range < s.sbr.max_range_m;
      const nlohmann::json* found = nullptr;
      for (const auto& t : frame.at("objects")) {
        if (t.at("object") == "moving_vehicle")
          found = &t;
      }
      if (!inside)
        continue;
      ASSERT_NE(found, nullptr) << "t=" << rec.time_s << ": vehicle in the beam but not in truth";
      // Tolerances: the antenna attitude and velocity come over CANaerospace as floats.
      EXPECT_NEAR(found->at("range_m").get<double>(), range, 1e-3);
      EXPECT_NEAR(found->at("azimuth_deg").get<double>(), az / common::kRadPerDeg, 1e-4);
      EXPECT_NEAR(found->at("elevation_deg").get<double>(), el / common::kRadPerDeg, 1e-4);
      EXPECT_NEAR(found->at("radial_velocity_mps").get<double>(), vr, 1e-3);
      ++checked;
    }
  }
  EXPECT_GE(checked, s.frames / 2);
  // Only targets (objects with a conducting material) are listed; the ground is not.
  for (const auto& o : truth.at("objects"))
    EXPECT_NE(o.at("object"), "ground");
}

TEST_F(ClosedLoopDefault, DetectionsNameTheirObject) {
  std::ifstream in(out_ / "detections.json");
  const nlohmann::json dets = nlohmann::json::parse(in);
  std::size_t n = 0;
  for (const auto& f : dets.at("frames")) {
    for (const auto& d : f.at("detections")) {
      ASSERT_TRUE(d.contains("object_id") && d.contains("object"));
      if (d.at("object_id").is_null()) {
        EXPECT_EQ(d.at("object"), "clutter");
      } else {
        const auto id = d.at("object_id").get<std::uint32_t>();
        const auto desc = scenario_scene(*scenario_);
        ASSERT_LT(id, desc.objects.size());
        EXPECT_EQ(d.at("object"), desc.objects[id].name);
      }
      ++n;
    }
  }
  EXPECT_EQ(n, result_->detections.size());
}

TEST(Truth, PointSeenFromAMovingRadarByHand) {
  // Radar at 400 m height flying north at 70 m/s, antenna boresight north and level (antenna
  // frame x north, y east = right, z down); a vehicle 300 m east, 4000 m north on the ground
  // driving south at 10 m/s.
  radar_emu::radar::RadarPose pose;
  pose.position_m = {0.0, 0.0, 400.0};
  pose.velocity_mps = {0.0, 70.0, 0.0};
  pose.world_from_antenna =
      glm::dmat3(glm::dvec3(0, 1, 0), glm::dvec3(1, 0, 0), glm::dvec3(0, 0, -1));
  const loop::ObjectTruth t = loop::point_truth(pose, {300.0, 4000.0, 0.0}, {0.0, -10.0, 0.0});
  const double r = std::sqrt(300.0 * 300.0 + 4000.0 * 4000.0 + 400.0 * 400.0);  // 4031.13 m
  EXPECT_NEAR(t.range_m, r, 1e-9);
  EXPECT_NEAR(t.azimuth_rad, std::atan(300.0 / 4000.0), 1e-12);  // right of boresight: +
  EXPECT_NEAR(t.elevation_rad, -std::asin(400.0 / r), 1e-12);    // below: -
  // Closing at (70 + 10) m/s along north, projected on the line of sight: -80 * 4000 / r.
  EXPECT_NEAR(t.radial_velocity_mps, -80.0 * 4000.0 / r, 1e-9);
  // Receding: the same vehicle driving north at 90 m/s opens the range at 20 * 4000 / r.
  EXPECT_NEAR(loop::point_truth(pose, {300.0, 4000.0, 0.0}, {0.0, 90.0, 0.0}).radial_velocity_mps,
              20.0 * 4000.0 / r, 1e-9);
}

TEST(ClosedLoopWeather, FogLowersEachDetectionsSnrByTheTwoWayLoss) {
  // Thermal noise off: a detection's SNR is then its cell's power in noise units, deterministic.
  // The same approach in free space and in thick fog: each detection found in both has lost
  // 2 gamma R dB, gamma the ITU-R P.676 + P.840 one-way specific attenuation at 94 GHz.
  loop::Scenario clear = default_scenario();
  clear.frames = 20;
  clear.sensor.thermal_noise = false;
  loop::Scenario fog = clear;
  fog.weather.enabled = true;
  fog.weather.condition = "fog";
  fog.weather.fog_water_gm3 = 0.5;
  fog.weather.humidity_gm3 = 9.4;
  fog.weather.temperature_k = 283.15;
  const radar_emu::radar::Atmosphere air{1013.25, 283.15, 9.4};
  const double gamma_db_per_m =
      1e-3 * (radar_emu::radar::gaseous_specific_attenuation(94e9, air).total_db_per_km() +
              radar_emu::radar::cloud_fog_specific_attenuation_db_per_km(94e9, 0.5, 283.15));
  loop::ClosedLoop loop_clear(clear, {});
  const loop::RunResult a = loop_clear.run();
  loop::RunOptions options;
  options.progress = radar_emu::test::count_allocations_from_frame(5);
  loop::ClosedLoop loop_fog(fog, options);
  const loop::RunResult b = loop_fog.run();
  EXPECT_EQ(radar_emu::test::stop_counting_allocations(), 0u) << "the fog frame path allocated";
  std::vector<double> errors_db;
  for (std::size_t k = 0; k < a.records.size(); ++k) {
    for (std::uint32_t i = 0; i < a.records[k].detection_count; ++i) {
      const auto& da = a.sensor_detections[a.records[k].first_detection + i];
      for (std::uint32_t j = 0; j < b.records[k].detection_count; ++j) {
        const auto& db = b.sensor_detections[b.records[k].first_detection + j];
        if (std::abs(da.range_m - db.range_m) > 0.5 ||
            std::abs(da.azimuth_rad - db.azimuth_rad) > 1e-3 ||
            std::abs(da.radial_velocity_mps - db.radial_velocity_mps) > 0.1) {
          continue;
        }
        const double drop_db = 10.0 * std::log10(da.snr / db.snr);
        const double expected_db = 2.0 * gamma_db_per_m * da.range_m;
        errors_db.push_back(std::abs(drop_db - expected_db));
      }
    }
  }
  // A cell that one scatterer dominates loses exactly 2 gamma R. A cell where scatterers tens
  // of metres apart in range interfere (the parked transports, clutter next to a target) does
  // not: each return loses its own 2 gamma r, so their sum changes phase balance (near a null,
  // by dB; about a quarter of this run's cells). Hence: the median within 0.005 dB, and at
  // least half of the detections and at least 20 of them within 0.01 dB.
  ASSERT_GE(errors_db.size(), 20u);
  std::sort(errors_db.begin(), errors_db.end());
  const double median = errors_db[errors_db.size() / 2];
  const auto within = static_cast<std::size_t>(
      std::count_if(errors_db.begin(), errors_db.end(), [](double e) { return e <= 0.01; }));
  EXPECT_LE(median, 0.005);
  EXPECT_GE(within, std::max<std::size_t>(errors_db.size() / 2, 20));
  std::printf(
      "fog (gamma %.4f dB/km): %zu detections in both runs, %zu within 0.01 dB of the "
      "two-way loss 2 gamma R, median error %.4f dB\n",
      gamma_db_per_m * 1e3, errors_db.size(), within, median);
}

TEST(ClosedLoopWeather, RainLossTakesTheScenariosPolarisation) {
  // ITU-R P.838-3: rain attenuates horizontal polarisation more than vertical (k_H > k_V at
  // 94 GHz). An HH radar in 16 mm/h of rain must lose k_H R^alpha_H (tilt 0) one way, not the
  // vertical figure; a VV radar the vertical one (tilt pi/2).
  constexpr double kRainMmph = 16.0;
  for (const auto pol :
       {radar_emu::radar::Polarisation::kHH, radar_emu::radar::Polarisation::kVV}) {
    loop::Scenario s = default_scenario();
    s.frames = 1;
    s.sbr.polarisation = pol;
    s.weather.enabled = true;
    s.weather.condition = "rain";
    s.weather.rain_mm_per_h = kRainMmph;
    const double tilt_rad =
        pol == radar_emu::radar::Polarisation::kHH ? 0.0 : std::numbers::pi / 2.0;
    const double f = s.sbr.carrier_hz;
    const double rain_db_per_km =
        radar_emu::radar::rain_specific_attenuation_db_per_km(f, kRainMmph, 0.0, tilt_rad);
    const radar_emu::radar::Atmosphere air{s.weather.pressure_hpa, s.weather.temperature_k,
                                           s.weather.humidity_gm3};
    const double gas_db_per_km =
        radar_emu::radar::gaseous_specific_attenuation(f, air).total_db_per_km();
    loop::ClosedLoop loop(s, {});
    const loop::RunResult r = loop.run();
    const loop::RunReport report = loop.report(r);
    const double range_m = 1000.0;
    std::printf(
        "%s: two-way loss over %.0f m in %.0f mm/h at %.0f GHz: %.4f dB (rain %.4f dB/km)\n",
        pol == radar_emu::radar::Polarisation::kHH ? "HH" : "VV", range_m, kRainMmph, f * 1e-9,
        2.0 * report.weather.total_db_per_m * range_m, report.weather.rain_db_per_km);
    EXPECT_NEAR(report.weather.rain_db_per_km, rain_db_per_km, 1e-9);
    EXPECT_NEAR(report.weather.total_db_per_m * 1e3, gas_db_per_km + rain_db_per_km, 1e-6);
  }
  // And the two differ: the test tells the polarisations apart.
  EXPECT_GT(radar_emu::radar::rain_specific_attenuation_db_per_km(94e9, kRainMmph, 0.0, 0.0),
            radar_emu::radar::rain_specific_attenuation_db_per_km(94e9, kRainMmph, 0.0,
                                                                  std::numbers::pi / 2.0));
}

TEST(ClosedLoop, TwoRunsWriteByteIdenticalLogs) {
  loop::Scenario s = default_scenario();
  s.frames = 40;
  const fs::path a = temp_dir("repeat_a"), b = temp_dir("repeat_b");
  for (const fs::path& dir : {a, b}) {
    loop::RunOptions options;
    options.out_dir = dir;
    loop::ClosedLoop loop(s, options);
    loop.write_outputs(loop.run());
  }
  for (const char* f : {"bus_out.log", "bus_in.log", "detections.json"}) {
    const std::string x = slurp(a / f), y = slurp(b / f);
    EXPECT_FALSE(x.empty()) << f;
    EXPECT_TRUE(x == y) << f << " differs between two runs with the same inputs";
  }
  fs::remove_all(a);
  fs::remove_all(b);
}

TEST(ClosedLoop, AStopRequestEndsTheRunAtAFrameBoundaryWithValidOutputs) {
  // The stop flag (what radar-emu's SIGINT / SIGTERM handler sets) is polled at each frame
  // boundary: raised before the first frame, the run does none and still writes every output;
  // raised after frame 3 (from the progress callback, between frames), it ends after 3.
  loop::Scenario s = default_scenario();
  s.frames = 40;
  for (const std::uint64_t stop_after : {std::uint64_t{0}, std::uint64_t{3}}) {
    const fs::path out = temp_dir("stop_" + std::to_string(stop_after));
    std::atomic<int> stop{stop_after == 0 ? SIGTERM : 0};
    loop::RunOptions options;
    options.out_dir = out;
    options.stop = &stop;
    options.progress = [&stop, stop_after](std::uint64_t done, std::uint64_t) {
      if (done == stop_after)
        stop.store(SIGINT);
    };
    loop::ClosedLoop loop(s, options);
    const loop::RunResult r = loop.run();
    EXPECT_EQ(r.frames, stop_after);
    EXPECT_TRUE(r.interrupted);
    EXPECT_EQ(r.stop_signal, stop_after == 0 ? SIGTERM : SIGINT);
    loop.write_outputs(r);
    std::ifstream in(out / "report.json");
    const nlohmann::json rep = nlohmann::json::parse(in);
    EXPECT_TRUE(rep.at("interrupted").get<bool>());
    EXPECT_EQ(rep.at("stop_signal"), stop_after == 0 ? "SIGTERM" : "SIGINT");
    EXPECT_EQ(rep.at("frames").get<std::uint64_t>(), stop_after);
    EXPECT_EQ(rep.at("frames_planned").get<std::uint64_t>(), 40u);
    EXPECT_TRUE(rep.at("output_stream").at("complete").get<bool>());
    for (const char* f : {"detections.json", "truth.json"}) {
      std::ifstream doc(out / f);
      EXPECT_EQ(nlohmann::json::parse(doc).at("frames").size(), stop_after) << f;
    }
    EXPECT_EQ(radar_emu::io::read_candump_file(out / "bus_out.log").empty(), stop_after == 0);
    for (const char* png : {"detections.png", "timing.png"}) {
      int w = 0, h = 0, channels = 0;
      unsigned char* px = stbi_load((out / png).c_str(), &w, &h, &channels, 3);
      EXPECT_NE(px, nullptr) << png;
      stbi_image_free(px);
    }
    fs::remove_all(out);
  }
}

TEST(ClosedLoop, MalformedInputFramesAreRejectedAndCounted) {
  loop::Scenario s = default_scenario();
  s.frames = 40;
  s.malformed_every_n_frames = 3;  // frames 0, 3, ..., 39: 14 malformed frames
  const fs::path out = temp_dir("malformed");
  loop::RunOptions options;
  options.out_dir = out;
  loop::ClosedLoop loop(s, options);
  const loop::RunResult r = loop.run();
  const std::uint64_t injected = r.injected_malformed[0] + r.injected_malformed[1] +
                                 r.injected_malformed[2] + r.injected_malformed[3];
  EXPECT_EQ(injected, 14u);
  EXPECT_EQ(r.decoder.short_frame, r.injected_malformed[0]);
  EXPECT_EQ(r.decoder.unknown_data_type, r.injected_malformed[1]);
  EXPECT_EQ(r.decoder.not_a_number, r.injected_malformed[2]);
  EXPECT_EQ(r.decoder.out_of_range, r.injected_malformed[3]);
  EXPECT_EQ(r.decoder.rejected(), injected);
  // The good data still flow: every frame valid, detections still produced.
  EXPECT_EQ(r.frames_valid, r.frames);
  EXPECT_GT(r.detections_total, 0u);
  loop.write_outputs(r);
  std::ifstream in(out / "report.json");
  const nlohmann::json rep = nlohmann::json::parse(in);
  EXPECT_EQ(rep["input"]["rejected"].get<std::uint64_t>(), injected);
  EXPECT_EQ(rep["input"]["rejected_by_reason"]["not_a_number"].get<std::uint64_t>(),
            r.injected_malformed[2]);
  fs::remove_all(out);
}

TEST(ClosedLoop, StaleStateMarksOutputInvalidAndEmitsNoDetections) {
  // Navigation at 0.2 Hz with a 0.5 s timeout: position is stale most of the time. Frames with a
  // stale state must carry the invalid flag and no detections computed from old data.
  loop::Scenario s = default_scenario();
  s.frames = 40;
  s.navigation_rate_hz = 0.2;
  loop::ClosedLoop loop(s, {});
  const loop::RunResult r = loop.run();
  std::size_t invalid = 0;
  for (const auto& rec : r.records) {
    const bool flagged = (rec.header.status & radar_emu::io::icd::status::kOwnshipInvalid) != 0;
    // The fix at t = 0 stays fresh until t = 0.5 s: frames 0..10 at 20 Hz are valid.
    EXPECT_EQ(flagged, rec.time_s > 0.5 + 1e-9) << "t=" << rec.time_s;
    if (flagged) {
      ++invalid;
      EXPECT_EQ(rec.detection_count, 0u);
    }
  }
  EXPECT_EQ(invalid, 29u);
  EXPECT_EQ(r.frames_valid, 11u);
}

// ---- Fault injection on the software bus (issue 6) ---------------------------------------

namespace {
// Frames that carry at least four detections, as many as the scene has reflector-carrying
// objects: a coarse check that the radar still sees the scene under faults (the geometric match
// of every detection is ClosedLoopDefault.DetectionsMatchIndependentGeometry's).
std::size_t frames_with_at_least_four_detections(const loop::RunResult& r) {
  std::size_t n = 0;
  for (const auto& rec : r.records) {
    if (rec.detection_count >= 4)
      ++n;
  }
  return n;
}
}  // namespace

TEST(ClosedLoopFaults, TenPercentDropWithJitterKeepsTheRateAndHoldsTheState) {
  // 10 % of the radar's input frames lost, the rest 20 +- 15 ms late (uniform). The INS sends
  // navigation at 10 Hz and attitude at 80 Hz, so the worst gap between two kept navigation
  // frames stays far below the 0.5 s timeout (P(5 losses in a row) = 1e-5): after start-up the
  // state is held (extrapolated with its velocity) in every frame, never flagged.
  loop::Scenario s = default_scenario();
  s.frames = 80;
  s.link_faults.drop_probability = 0.10;
  s.link_faults.delay_s = 0.020;
  s.link_faults.jitter_s = 0.015;
  s.link_faults.seed = 20261123;
  std::printf("  fault seed %llu\n", static_cast<unsigned long long>(s.link_faults.seed));
  loop::ClosedLoop loop(s, {});
  const loop::RunResult r = loop.run();
  EXPECT_EQ(r.frames, 80u);
  EXPECT_EQ(r.overruns, 0u);
  EXPECT_EQ(r.missed_periods, 0u);
  // Binomial: dropped / frames_in within 4 sigma of 0.1.
  const double n = static_cast<double>(r.link_faults.frames_in);
  const double p = static_cast<double>(r.link_faults.dropped) / n;
  std::printf("  %llu input frames, %.2f %% dropped, %llu delayed\n",
              static_cast<unsigned long long>(r.link_faults.frames_in), 100.0 * p,
              static_cast<unsigned long long>(r.link_faults.delayed));
  EXPECT_NEAR(p, 0.10, 4.0 * std::sqrt(0.1 * 0.9 / n));
  // Start-up: every field must have arrived once (the first navigation frames arrive 5-35 ms
  // late, or are lost). From the first valid frame on, every frame must be valid (the state is
  // held), and the worst field age stays below the timeout.
  ASSERT_FALSE(r.records.empty());
  double first_valid_s = -1.0;
  for (const auto& rec : r.records) {
    const bool flagged = (rec.header.status & radar_emu::io::icd::status::kOwnshipInvalid) != 0;
    if (first_valid_s < 0.0 && !flagged)
      first_valid_s = rec.time_s;
    if (first_valid_s >= 0.0) {
      EXPECT_FALSE(flagged) << "t=" << rec.time_s;
    }
  }
  std::printf("  first valid frame at t = %.2f s; then every frame valid\n", first_valid_s);
  EXPECT_GE(first_valid_s, 0.0);
  EXPECT_LE(first_valid_s, 0.5);
  for (std::size_t k = 0; k < r.field_age_max_s.size(); ++k)
    EXPECT_LT(r.field_age_max_s[k], s.state_timeout_s) << "field " << k;
  // The radar still sees the scene.
  EXPECT_GE(frames_with_at_least_four_detections(r), 70u);
}

TEST(ClosedLoopFaults, StaleSenderMakesExactlyTheFramesPastTheTimeoutInvalid) {
  // The INS stops sending from t = 2.0 s to 3.0 s. Its last navigation frame before the window
  // is the one at 1.9 s (10 Hz), so position is older than the 0.5 s timeout for frames with
  // t > 2.4 s until the one at 3.0 s arrives: frames 2.45 .. 2.95 s (11 frames) are flagged
  // OWNSHIP_INVALID with no detections; with stale_output "silent" nothing is sent for them.
  // A sender frozen on its last messages (message codes frozen too) is stale the same way: its
  // repeated messages are not taken (docs/icd/canaerospace_input.md).
  struct Case {
    radar_emu::sim_bus::StaleMode mode;
    bool silent;
  };
  for (const Case c : {Case{radar_emu::sim_bus::StaleMode::kSilent, false},
                       Case{radar_emu::sim_bus::StaleMode::kSilent, true},
                       Case{radar_emu::sim_bus::StaleMode::kFrozen, false}}) {
    const bool silent = c.silent;
    loop::Scenario s = default_scenario();
    s.frames = 70;
    s.stale_sender = true;
    s.stale.mode = c.mode;
    s.stale.start_s = 2.0;
    s.stale.end_s = 3.0;
    s.stale_output_silent = silent;
    loop::ClosedLoop loop(s, {});
    const loop::RunResult r = loop.run();
    std::size_t flagged_n = 0, sent_n = 0;
    for (const auto& rec : r.records) {
      const bool expect_stale = rec.time_s > 2.4 + 1e-9 && rec.time_s < 3.0 - 1e-9;
      const bool flagged = (rec.header.status & radar_emu::io::icd::status::kOwnshipInvalid) != 0;
      EXPECT_EQ(flagged, expect_stale) << "t=" << rec.time_s;
      EXPECT_EQ(rec.sent, !(silent && expect_stale)) << "t=" << rec.time_s;
      if (flagged) {
        EXPECT_EQ(rec.detection_count, 0u);
      }
      flagged_n += flagged;
      sent_n += rec.sent;
    }
    EXPECT_EQ(flagged_n, 11u);
    EXPECT_EQ(r.frames_valid, 59u);
    EXPECT_EQ(r.lists_suppressed, silent ? 11u : 0u);
    // The avionics sink saw one list per sent frame.
    EXPECT_EQ(r.sink_lists, sent_n);
    if (c.mode == radar_emu::sim_bus::StaleMode::kSilent) {
      EXPECT_GT(r.stale_sender.suppressed, 0u);
    } else {
      EXPECT_GT(r.stale_sender.replayed, 0u);
      EXPECT_EQ(r.decoder.repeated_message_code, r.stale_sender.replayed);
    }
  }
}

TEST(ClosedLoopFaults, CorruptedFramesAreRejectedOrIgnoredAndNeverCrashTheLoop) {
  // 5 % of the input frames have 1-3 bits flipped (identifier, DLC or payload). A flipped
  // identifier usually lands on an id the radar does not use (ignored), a flipped DLC is a short
  // frame, a flipped data-type byte an unknown type, a flipped exponent an out-of-range value:
  // all counted. Flips inside a mantissa pass as plausible values (the CRC of a real bus would
  // have caught them: sim_bus/fault_injector.hpp). The loop runs every frame.
  loop::Scenario s = default_scenario();
  s.frames = 60;
  s.link_faults.corrupt_probability = 0.05;
  s.link_faults.corrupt_max_bits = 3;
  s.link_faults.seed = 7;
  std::printf("  fault seed %llu\n", static_cast<unsigned long long>(s.link_faults.seed));
  loop::ClosedLoop loop(s, {});
  const loop::RunResult r = loop.run();
  EXPECT_EQ(r.frames, 60u);
  EXPECT_GT(r.link_faults.corrupted, 0u);
  const auto& c = r.decoder;
  std::printf(
      "  %llu corrupted: %llu rejected (short %llu, type %llu/%llu, nan %llu, range %llu, "
      "unpaired %llu), %llu ignored ids, %llu code gaps\n",
      static_cast<unsigned long long>(r.link_faults.corrupted),
      static_cast<unsigned long long>(c.rejected()), static_cast<unsigned long long>(c.short_frame),
      static_cast<unsigned long long>(c.unknown_data_type),
      static_cast<unsigned long long>(c.unsupported_data_type),
      static_cast<unsigned long long>(c.not_a_number),
      static_cast<unsigned long long>(c.out_of_range),
      static_cast<unsigned long long>(c.unpaired_double),
      static_cast<unsigned long long>(c.ignored_id),
      static_cast<unsigned long long>(c.message_code_gaps));
  EXPECT_GT(c.rejected(), 0u);
  // Every frame offered is accepted, pending as a DOUBLEH, ignored or rejected: nothing is lost.
  EXPECT_EQ(c.frames, r.bus_frames_in);
  EXPECT_GE(r.frames_valid, 55u);
}

TEST(ClosedLoopFaults, BabblingNodeIsIgnoredAndTheRadarKeepsItsState) {
  // A node floods identifier 0x010 (CANaerospace emergency-event range) at 5000 frames/s. The
  // radar ignores the identifier (counted), decodes the INS between the babble and stays valid.
  loop::Scenario s = default_scenario();
  s.frames = 40;
  s.babbling_node = true;
  s.babble.id = 0x010;
  s.babble.rate_hz = 5000.0;
  loop::ClosedLoop loop(s, {});
  const loop::RunResult r = loop.run();
  EXPECT_EQ(r.frames_valid, r.frames);
  EXPECT_GT(r.babble.sent, 9000u);  // 5000/s over the 1.95 s the 40 frames span
  EXPECT_GE(r.decoder.ignored_id, r.babble.sent);
  EXPECT_EQ(r.decoder.rejected(), 0u);
  EXPECT_EQ(r.bus_rx_overflows, 0u);
  EXPECT_GE(frames_with_at_least_four_detections(r), 36u);
}
