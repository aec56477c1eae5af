#pragma once
// The live view (`radar-emu run --serve HOST:PORT`): a web page that shows the current frame as
// it runs, a B-scope (azimuth across, range up, the geometry of detections.png) of the frame's
// detections against the ground truth, the ownship state, and the stage times against the frame
// budget.
//
// It never slows the frame loop: the frame thread copies the frame into a preallocated snapshot
// and publishes it through a wait-free triple buffer (io/triple_buffer.hpp): no allocation, no
// lock, no system call. A server thread (io/websocket.hpp) takes the newest snapshot every
// 40 ms, formats it as JSON and pushes it to the connected browsers. A snapshot superseded
// before the server took it is a dropped update, counted (report.json "live_view"); a browser
// needs no more than 25 updates a second, so at high frame rates most are.

#include <array>
#include <atomic>
#include <cstdint>
#include <glm/glm.hpp>
#include <memory>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "io/detection_icd.hpp"
#include "io/triple_buffer.hpp"
#include "io/websocket.hpp"
#include "loop/outcome.hpp"
#include "loop/truth.hpp"
#include "timing/profiler.hpp"

namespace radar_emu::loop {

struct Scenario;
struct FrameRecord;

/// "HOST:PORT", ":PORT" (127.0.0.1) or "PORT" (127.0.0.1) with a port 0-65535 (0: a free one).
/// Throws std::invalid_argument "--serve 'SPEC': ..." otherwise.
struct ServeAddress {
  std::string host;
  std::uint16_t port = 0;
};
[[nodiscard]] ServeAddress parse_serve_address(std::string_view spec);

/// The page the server serves (HTML + JavaScript, no external resources).
[[nodiscard]] std::string_view live_view_page() noexcept;

/// What the live view did.
struct LiveViewCounters {
  std::string address;                  ///< "HOST:PORT" served
  std::uint64_t updates_published = 0;  ///< frames the loop handed over
  std::uint64_t updates_dropped = 0;    ///< superseded before the server took them
  std::uint64_t updates_taken = 0;      ///< taken by the server
  std::uint64_t updates_sent = 0;       ///< ... and pushed to at least one client
  std::uint64_t updates_unseen = 0;     ///< ... taken with no client connected
  io::ws::ServerCounters server{};
};

struct LiveViewConfig {
  std::string serve;                      ///< parse_serve_address() syntax
  const Scenario* scenario = nullptr;     ///< name, B-scope geometry, frame period
  std::vector<std::string> object_names;  ///< scene objects by id (truth labels)
  std::size_t max_detections = 64;        ///< per frame
  std::size_t max_truth = 64;             ///< per frame; also the truth objects of the outcome
  int update_interval_ms = 40;            ///< how often the server takes the newest frame
};

class LiveView {
 public:
  /// Setup: allocates the snapshots, binds the server (throws std::runtime_error "--serve
  /// HOST:PORT: cannot listen: ..." when the port is taken) and starts its thread.
  explicit LiveView(LiveViewConfig config);
  ~LiveView();
  LiveView(const LiveView&) = delete;
  LiveView& operator=(const LiveView&) = delete;

  /// The frame thread, once a frame: copies the frame (at most max_detections and max_truth
  /// entries) into the free snapshot and publishes it. Real-time safe: no allocation, no lock,
  /// no exception. `velocity_enu_mps` is the ownship's (used when record.ownship_valid);
  /// `outcome` the outcome per target so far (at most max_truth targets copied).
  void publish(const FrameRecord& record, const glm::dvec3& velocity_enu_mps,
               const std::array<std::int64_t, timing::kStageCount>& stage_ns,
               std::span<const io::icd::Detection> detections, std::span<const ObjectTruth> truth,
               const OutcomeSoFar& outcome = {}) noexcept;
  /// The run is over: the page says so (the last frame stays shown).
  void end() noexcept;
  /// Waits until a browser has connected its WebSocket, at most `timeout_s`, or until `*stop`
  /// is raised (may be null). Returns whether one did.
  bool wait_for_client(double timeout_s, const std::atomic<int>* stop) const;

  [[nodiscard]] const std::string& address() const noexcept;
  /// Thread-safe.
  [[nodiscard]] LiveViewCounters counters() const;

  /// One frame as the view holds it (fixed capacity: set at setup).
  struct Snapshot {
    std::uint64_t frame_index = 0;
    double time_s = 0.0;
    bool ownship_valid = false, late = false, degraded = false, sent = true;
    int governor_level = 0;
    glm::dvec3 ownship_enu_m{0.0}, velocity_enu_mps{0.0};
    std::array<std::int64_t, timing::kStageCount> stage_ns{};
    std::uint64_t published = 0, dropped = 0;  ///< counts at publish time
    std::size_t detection_count = 0, truth_count = 0;
    std::vector<io::icd::Detection> detections;  ///< max_detections, first detection_count used
    std::vector<ObjectTruth> truth;              ///< max_truth, first truth_count used
    /// The outcome per target so far: max_truth, first target_count used.
    std::vector<TargetOutcome> targets;
    std::size_t target_count = 0;
    std::uint64_t frames_scored = 0, false_alarms = 0;
  };
  /// The JSON message of a snapshot (the server thread; exposed for tests).
  void format(const Snapshot& s, bool ended, std::string& out) const;

 private:
  bool take(std::string& message, std::uint64_t clients);

  LiveViewConfig config_;
  double budget_ms_ = 0.0;
  double azimuth_min_deg_ = 0.0, azimuth_max_deg_ = 0.0, range_max_m_ = 0.0;
  std::string scenario_json_;             ///< quoted, escaped name
  std::vector<std::string> object_json_;  ///< quoted, escaped names by id
  io::TripleBuffer<Snapshot> buffer_;
  // The frame thread's.
  std::uint64_t published_ = 0;
  std::atomic<std::uint64_t> dropped_{0};
  std::atomic<std::uint64_t> published_shared_{0};
  // The server thread's (read by counters()).
  std::atomic<std::uint64_t> taken_{0}, sent_{0}, unseen_{0};
  std::atomic<bool> ended_{false};
  bool ended_sent_ = false;  ///< server thread
  std::unique_ptr<io::ws::Server> server_;
};

}  // namespace radar_emu::loop
