#pragma once
// The outputs of a run, written while it runs: the frame thread hands each frame's bus traffic,
// detections, ground truth and stage times to bounded single-producer single-consumer rings
// (io/spsc_ring.hpp); a writer thread formats them into bus_in.log and bus_out.log (candump -L),
// detections.json, truth.json, frames.csv and the B-scope (detections.png). Every buffer is
// allocated and touched at setup: memory does not grow with the run's length, and neither the
// frame thread's hand-over nor the writer allocates.
//
// A writer that falls behind never stalls a frame of a real-time run: what does not fit in the
// rings is dropped and counted (OutputCounters). On the simulated clock there is no deadline to
// miss, so the loop waits for the writer between frames instead (counted too), and the files are
// complete and the same whatever the machine's load (replay stays byte-identical). A file that
// cannot be written (disk full, I/O error) loses what did not fit, counted per file, and the
// writer carries on.

#include <array>
#include <atomic>
#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <memory>
#include <span>
#include <string>
#include <thread>
#include <vector>

#include "io/can_frame.hpp"
#include "io/detection_icd.hpp"
#include "io/spsc_ring.hpp"
#include "loop/frame_record.hpp"
#include "loop/scenario.hpp"
#include "loop/truth.hpp"
#include "radar/sensor/sensor.hpp"
#include "timing/profiler.hpp"

namespace radar_emu::loop {

class BScope;

struct OutputStreamConfig {
  std::filesystem::path dir;  ///< created if missing; the files are opened (truncated) at setup
  const Scenario* scenario = nullptr;     ///< name and B-scope geometry (must outlive the stream)
  std::uint64_t frames_planned = 1;       ///< colour scale of the B-scope
  std::vector<std::string> object_names;  ///< scene objects by id ("object" in the JSON)
  std::vector<std::uint32_t> truth_objects;  ///< ids truth.json covers (listed in its header)
  std::size_t max_detections = 64;           ///< per frame
  std::size_t bus_frames_per_frame = 64;     ///< in + out, expected most (ring sizing, waits)
  std::size_t slack_frames = 256;            ///< frames the rings hold before the writer drains
  bool wait_when_full = true;                ///< simulated clock: wait; real time: drop, count
  bool wake_latency = false;                 ///< frames.csv's wake_latency_ms is measured
  std::string interface_name = "can0";       ///< candump interface column
};

/// The files a run streams, in the order OutputCounters::files lists them.
inline constexpr std::array<const char*, 5> kStreamedFiles{
    "bus_in.log", "bus_out.log", "detections.json", "truth.json", "frames.csv"};

class OutputStream {
 public:
  /// Setup: creates the directory, opens every file (throws std::runtime_error naming the path
  /// on failure), allocates the rings and buffers, writes the JSON and CSV headers and starts
  /// the writer thread.
  explicit OutputStream(OutputStreamConfig config);
  ~OutputStream();
  OutputStream(const OutputStream&) = delete;
  OutputStream& operator=(const OutputStream&) = delete;

  // ---- the frame thread (real-time safe: no allocation, no lock, no exception) ----
  /// One frame the radar received (bus_in.log) or sent (bus_out.log).
  void bus_in(const io::CanFrame& frame) noexcept { push_bus(frame, false); }
  void bus_out(const io::CanFrame& frame) noexcept { push_bus(frame, true); }
  /// One finished frame: its record, stage times [ns] (-1: not measured), the detections as
  /// sent (`sensor` holds the same detections as the sensor saw them: their object ids) and the
  /// objects in the beam. All or nothing: when the rings cannot take the whole frame it is
  /// dropped and counted (or, with wait_when_full, waited for).
  void frame(const FrameRecord& record,
             const std::array<std::int64_t, timing::kStageCount>& stage_ns,
             std::span<const io::icd::Detection> detections,
             std::span<const radar::Detection> sensor, std::span<const ObjectTruth> truth) noexcept;
  /// With wait_when_full, at a frame boundary: waits until the bus ring has room for a frame's
  /// expected traffic (bus_frames_per_frame). Otherwise returns at once.
  void wait_for_room() noexcept;
  /// Bus frames the ring had no room for so far (frame thread).
  [[nodiscard]] std::uint64_t bus_frames_dropped() const noexcept { return bus_frames_dropped_; }

  // ---- teardown ----
  /// Stops the writer once it has written everything handed over, closes the JSON documents and
  /// the files, writes detections.png. Idempotent; never throws for a write failure (counted).
  /// Frames handed over afterwards are dropped and counted. Call it from the frame thread.
  const OutputCounters& finish();
  [[nodiscard]] bool finished() const noexcept { return finished_; }
  /// After finish(): what was written and lost. Before: the frame thread's drop and wait
  /// counts only.
  [[nodiscard]] OutputCounters counters() const;
  [[nodiscard]] const std::filesystem::path& dir() const noexcept { return config_.dir; }

  /// A buffered output file: write errors are counted, never thrown (after open).
  class File;

 private:
  struct BusEntry {
    io::CanFrame frame{};
    bool out = false;
  };
  struct FrameEntry {
    FrameRecord record{};
    std::array<std::int64_t, timing::kStageCount> stage_ns{};
  };
  struct DetectionEntry {
    io::icd::Detection detection{};
    std::uint32_t object_id = 0;
  };

  void push_bus(const io::CanFrame& frame, bool out) noexcept;
  void writer_main() noexcept;
  bool drain() noexcept;
  void write_frame(const FrameEntry& e) noexcept;  ///< one frame into the three files below
  void write_detections(const FrameRecord& rec, bool first) noexcept;  ///< detections.json
  void write_truth(const FrameRecord& rec, bool first) noexcept;       ///< truth.json
  void write_frames_csv(const FrameEntry& e) noexcept;                 ///< frames.csv
  void write_trailers() noexcept;
  [[nodiscard]] std::string_view object_json(std::uint32_t id) const noexcept;

  OutputStreamConfig config_;
  std::vector<std::unique_ptr<File>> files_;  ///< kStreamedFiles order
  io::SpscRing<BusEntry> bus_ring_;
  io::SpscRing<FrameEntry> frame_ring_;
  io::SpscRing<DetectionEntry> detection_ring_;
  io::SpscRing<ObjectTruth> truth_ring_;
  std::vector<std::string> object_json_;                ///< quoted, escaped names by id
  std::vector<io::icd::Detection> scratch_detections_;  ///< the writer's, for the B-scope
  std::unique_ptr<BScope> bscope_;
  // Counted by the frame thread.
  std::uint64_t frames_dropped_ = 0;
  std::uint64_t bus_frames_dropped_ = 0;
  std::uint64_t waits_ = 0;
  // Counted by the writer (read after it has stopped).
  std::uint64_t frames_written_ = 0;
  std::uint64_t bus_frames_written_ = 0;
  std::uint64_t detections_written_ = 0;
  std::atomic<bool> stop_{false};
  bool finished_ = false;
  OutputCounters counters_;
  std::thread writer_;
};

}  // namespace radar_emu::loop
