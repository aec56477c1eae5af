#include "loop/outputs/live_view.hpp"

#include <algorithm>
#include <charconv>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <stdexcept>
#include <thread>

#include "common/units.hpp"
#include "loop/frame_record.hpp"
#include "loop/scenario.hpp"

namespace radar_emu::loop {

namespace {

std::string json_string(std::string_view s) {
  std::string o = "\"";
  for (const char ch : s) {
    const auto c = static_cast<unsigned char>(ch);
    if (c == '"' || c == '\\') {
      o += '\\';
      o += ch;
    } else if (c < 0x20) {
      char buf[8];
      std::snprintf(buf, sizeof buf, "\\u%04x", c);
      o += buf;
    } else {
      o += ch;
    }
  }
  return o + '"';
}

// Appends a number as JSON: finite values with `digits` decimals, anything else as null.
void number(std::string& o, double v, int digits = 3) {
  if (!std::isfinite(v)) {
    o += "null";
    return;
  }
  char buf[48];
  std::snprintf(buf, sizeof buf, "%.*f", digits, v);
  o += buf;
}

void integer(std::string& o, std::uint64_t v) {
  char buf[24];
  const auto [end, ec] = std::to_chars(buf, buf + sizeof buf, v);
  (void)ec;
  o.append(buf, end);
}

LiveView::Snapshot initial_snapshot(const LiveViewConfig& c) {
  LiveView::Snapshot s;
  s.detections.resize(std::max<std::size_t>(c.max_detections, 1));
  s.truth.resize(std::max<std::size_t>(c.max_truth, 1));
  s.targets.resize(std::max<std::size_t>(c.max_truth, 1));
  return s;
}

}  // namespace

ServeAddress parse_serve_address(std::string_view spec) {
  const std::size_t colon = spec.rfind(':');
  std::string_view host = colon == std::string_view::npos ? "" : spec.substr(0, colon);
  const std::string_view port = colon == std::string_view::npos ? spec : spec.substr(colon + 1);
  unsigned value = 0;
  const auto [end, ec] = std::from_chars(port.data(), port.data() + port.size(), value);
  if (port.empty() || ec != std::errc{} || end != port.data() + port.size() || value > 65535) {
    throw std::invalid_argument("--serve '" + std::string(spec) +
                                "': expected HOST:PORT, :PORT or PORT with a port 0-65535");
  }
  if (host.size() >= 2 && host.front() == '[' && host.back() == ']')
    host = host.substr(1, host.size() - 2);  // [::1]:8080
  // The loopback interface unless told otherwise: the view is no business of the wider network
  // by default.
  return ServeAddress{host.empty() ? std::string("127.0.0.1") : std::string(host),
                      static_cast<std::uint16_t>(value)};
}

LiveView::LiveView(LiveViewConfig config)
    : config_(std::move(config)), buffer_(initial_snapshot(config_)) {
  if (config_.scenario == nullptr)
    throw std::invalid_argument("LiveView: no scenario");
  const Scenario& s = *config_.scenario;
  budget_ms_ = 1e3 / s.rate_hz;
  // The B-scope's axes, as detections.png (loop/outputs/run_plots.cpp BScope).
  azimuth_min_deg_ = common::degrees(s.sbr.azimuth_min_rad);
  azimuth_max_deg_ = common::degrees(s.sbr.azimuth_max_rad);
  range_max_m_ = s.sensor.max_range_m;
  scenario_json_ = json_string(s.name);
  for (const std::string& n : config_.object_names)
    object_json_.push_back(json_string(n));
  const ServeAddress a = parse_serve_address(config_.serve);
  io::ws::ServerConfig sc;
  sc.host = a.host;
  sc.port = a.port;
  sc.page = std::string(live_view_page());
  sc.poll_interval_ms = config_.update_interval_ms;
  sc.source = [this](std::string& message, std::uint64_t clients) {
    return take(message, clients);
  };
  try {
    server_ = std::make_unique<io::ws::Server>(std::move(sc));
  } catch (const std::runtime_error& e) {
    throw std::runtime_error(std::string("--serve ") + e.what());
  }
}

LiveView::~LiveView() {
  server_.reset();  // joins the thread before the snapshots go
}

const std::string& LiveView::address() const noexcept {
  return server_->address();
}

void LiveView::publish(const FrameRecord& rec, const glm::dvec3& velocity_enu_mps,
                       const std::array<std::int64_t, timing::kStageCount>& stage_ns,
                       std::span<const io::icd::Detection> detections,
                       std::span<const ObjectTruth> truth, const OutcomeSoFar& outcome) noexcept {
  Snapshot& s = buffer_.write_slot();
  s.frame_index = rec.frame_index;
  s.time_s = rec.time_s;
  s.ownship_valid = rec.ownship_valid;
  s.late = rec.late;
  s.degraded = (rec.header.status & io::icd::status::kDegraded) != 0;
  s.sent = rec.sent;
  s.governor_level = rec.governor_level;
  s.ownship_enu_m = rec.ownship_enu_m;
  s.velocity_enu_mps = velocity_enu_mps;
  s.stage_ns = stage_ns;
  s.detection_count = std::min(detections.size(), s.detections.size());
  std::copy_n(detections.begin(), s.detection_count, s.detections.begin());
  s.truth_count = std::min(truth.size(), s.truth.size());
  std::copy_n(truth.begin(), s.truth_count, s.truth.begin());
  s.target_count = std::min(outcome.targets.size(), s.targets.size());
  std::copy_n(outcome.targets.begin(), s.target_count, s.targets.begin());
  s.frames_scored = outcome.frames_scored;
  s.false_alarms = outcome.false_alarms;
  ++published_;
  s.published = published_;
  s.dropped = dropped_.load(std::memory_order_relaxed);
  if (buffer_.publish())
    dropped_.fetch_add(1, std::memory_order_relaxed);
  published_shared_.store(published_, std::memory_order_relaxed);
}

void LiveView::end() noexcept {
  ended_.store(true, std::memory_order_release);
}

bool LiveView::wait_for_client(double timeout_s, const std::atomic<int>* stop) const {
  const auto until = std::chrono::steady_clock::now() + std::chrono::duration<double>(timeout_s);
  while (server_->clients() == 0) {
    if (std::chrono::steady_clock::now() >= until)
      return false;
    if (stop != nullptr && stop->load(std::memory_order_relaxed) != 0)
      return false;
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
  return true;
}

bool LiveView::take(std::string& message, std::uint64_t clients) {
  const bool fresh = buffer_.update();
  const bool ended = ended_.load(std::memory_order_acquire);
  if (!fresh && !(ended && !ended_sent_))
    return false;
  if (fresh) {
    taken_.fetch_add(1, std::memory_order_relaxed);
    (clients > 0 ? sent_ : unseen_).fetch_add(1, std::memory_order_relaxed);
  }
  ended_sent_ = ended;
  format(buffer_.read_slot(), ended, message);
  return true;
}

void LiveView::format(const Snapshot& s, bool ended, std::string& o) const {
  o.clear();
  o += "{\"scenario\":";
  o += scenario_json_;
  o += ",\"frame\":";
  integer(o, s.frame_index);
  o += ",\"frames_seen\":";
  integer(o, s.published);
  o += ",\"time_s\":";
  number(o, s.time_s);
  o += ",\"ended\":";
  o += ended ? "true" : "false";
  o += ",\"layout\":{\"azimuth_min_deg\":";
  number(o, azimuth_min_deg_, 6);
  o += ",\"azimuth_max_deg\":";
  number(o, azimuth_max_deg_, 6);
  o += ",\"range_max_m\":";
  number(o, range_max_m_);
  o += "},\"status\":{\"late\":";
  o += s.late ? "true" : "false";
  o += ",\"degraded\":";
  o += s.degraded ? "true" : "false";
  o += ",\"sent\":";
  o += s.sent ? "true" : "false";
  o += ",\"governor_level\":";
  integer(o, static_cast<std::uint64_t>(std::max(0, s.governor_level)));
  o += "},\"ownship\":{\"valid\":";
  o += s.ownship_valid ? "true" : "false";
  if (s.ownship_valid) {
    const glm::dvec3& p = s.ownship_enu_m;
    const glm::dvec3& v = s.velocity_enu_mps;
    double track_deg = common::degrees(std::atan2(v.x, v.y));  // from north toward east
    if (track_deg < 0.0)
      track_deg += 360.0;
    o += ",\"east_m\":";
    number(o, p.x, 1);
    o += ",\"north_m\":";
    number(o, p.y, 1);
    o += ",\"up_m\":";
    number(o, p.z, 1);
    o += ",\"ground_speed_mps\":";
    number(o, std::hypot(v.x, v.y), 2);
    o += ",\"track_deg\":";
    number(o, track_deg, 2);
    o += ",\"climb_mps\":";
    number(o, v.z, 2);
  }
  o += "},\"budget_ms\":";
  number(o, budget_ms_);
  o += ",\"stages_ms\":{";
  for (std::size_t k = 0; k < timing::kStageCount; ++k) {
    if (k > 0)
      o += ',';
    o += '"';
    o += timing::stage_name(static_cast<timing::Stage>(k));
    o += "\":";
    if (s.stage_ns[k] < 0)
      o += "null";
    else
      number(o, static_cast<double>(s.stage_ns[k]) * 1e-6, 4);
  }
  o += "},\"view\":{\"published\":";
  integer(o, s.published);
  o += ",\"dropped\":";
  integer(o, s.dropped);
  o += "},\"detections\":[";
  for (std::size_t i = 0; i < s.detection_count; ++i) {
    const io::icd::Detection& d = s.detections[i];
    o += i > 0 ? ",{" : "{";
    o += "\"azimuth_deg\":";
    number(o, d.azimuth_deg, 4);
    o += ",\"range_m\":";
    number(o, d.range_m, 2);
    o += ",\"radial_velocity_mps\":";
    number(o, d.radial_velocity_mps, 2);
    o += ",\"snr_db\":";
    number(o, d.snr_db, 1);
    o += '}';
  }
  o += "],\"truth\":[";
  for (std::size_t i = 0; i < s.truth_count; ++i) {
    const ObjectTruth& t = s.truth[i];
    o += i > 0 ? ",{" : "{";
    o += "\"object\":";
    o += t.object_id < object_json_.size() ? object_json_[t.object_id] : std::string("null");
    o += ",\"azimuth_deg\":";
    number(o, common::degrees(t.azimuth_rad), 4);
    o += ",\"range_m\":";
    number(o, t.range_m, 2);
    o += '}';
  }
  // The outcome per target so far (loop/outcome.hpp): the objects that have been in the beam.
  o += "],\"outcome\":{\"frames_scored\":";
  integer(o, s.frames_scored);
  o += ",\"false_alarms\":";
  integer(o, s.false_alarms);
  o += ",\"false_alarms_per_frame\":";
  number(o, s.frames_scored > 0
                ? static_cast<double>(s.false_alarms) / static_cast<double>(s.frames_scored)
                : 0.0);
  o += ",\"targets\":[";
  bool first = true;
  for (std::size_t i = 0; i < s.target_count; ++i) {
    const TargetOutcome& t = s.targets[i];
    if (t.frames_in_beam == 0)
      continue;
    o += first ? "{" : ",{";
    first = false;
    o += "\"object\":";
    o += t.object_id < object_json_.size() ? object_json_[t.object_id] : std::string("null");
    o += ",\"frames_in_beam\":";
    integer(o, t.frames_in_beam);
    o += ",\"frames_detected\":";
    integer(o, t.frames_detected);
    o += ",\"pd\":";
    number(o, t.pd());
    o += ",\"range_error_m\":[";
    number(o, t.range_m.mean, 2);
    o += ',';
    number(o, t.range_m.std_dev(), 2);
    o += "],\"azimuth_error_deg\":[";
    number(o, common::degrees(t.azimuth_rad.mean), 4);
    o += ',';
    number(o, common::degrees(t.azimuth_rad.std_dev()), 4);
    o += "],\"elevation_error_deg\":[";
    number(o, common::degrees(t.elevation_rad.mean), 4);
    o += ',';
    number(o, common::degrees(t.elevation_rad.std_dev()), 4);
    o += "],\"radial_velocity_error_mps\":[";
    number(o, t.radial_velocity_mps.mean, 2);
    o += ',';
    number(o, t.radial_velocity_mps.std_dev(), 2);
    o += "]}";
  }
  o += "]}}";
}

LiveViewCounters LiveView::counters() const {
  LiveViewCounters c;
  c.address = server_->address();
  c.updates_published = published_shared_.load(std::memory_order_relaxed);
  c.updates_dropped = dropped_.load(std::memory_order_relaxed);
  c.updates_taken = taken_.load(std::memory_order_relaxed);
  c.updates_sent = sent_.load(std::memory_order_relaxed);
  c.updates_unseen = unseen_.load(std::memory_order_relaxed);
  c.server = server_->counters();
  return c;
}

}  // namespace radar_emu::loop
