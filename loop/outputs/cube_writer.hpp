#pragma once
// Data cubes out (`radar-emu run --cube FILE.h5`, docs/cube.md): for each frame of a bounded
// range, the sensor's raw samples per beam, channel and pulse before processing and the
// range-Doppler-beam image the CFAR ran on, with the frame's detections, into one HDF5 file.
//
// The frame thread only copies: it arms the sensor with a preallocated slot before the frame
// (radar::Sensor::capture_next), and hands the filled slot, its record and its detections to a
// writer thread after it (an atomic state per slot; no lock, no allocation, no exception). The
// writer completes the image, synthesises the raw samples (radar::Sensor::complete_image,
// synthesise_raw) and writes the HDF5 groups. A frame that finds no free slot is waited for on
// the simulated clock (between frames, outside the timed stages) and dropped and counted in
// real time. A failed HDF5 write is counted, never thrown; the file is checked at setup.
// This is the only file of the project that includes hdf5.h.

#include <atomic>
#include <complex>
#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <memory>
#include <span>
#include <string>
#include <thread>
#include <vector>

#include "loop/frame_record.hpp"
#include "radar/sensor/sensor.hpp"

namespace radar_emu::loop {

/// Files larger than this are refused at setup, with their estimate.
inline constexpr std::uint64_t kCubeMaxBytes = 4ull << 30;

struct CubeWriterConfig {
  std::filesystem::path file;     ///< created (truncated) at setup
  std::uint64_t first_frame = 0;  ///< frame indices (FrameRecord::frame_index), inclusive
  std::uint64_t last_frame = 0;
  std::uint64_t run_frames = 1;  ///< the run's frames: the range is clipped to them
  /// Where the file and the range were given, for setup errors: "--cube" and "--cube-frames"
  /// (the CLI), or "FILE: [output] cube" and "FILE: [output] cube_frames" (a scenario).
  std::string file_source = "--cube";
  std::string frames_source = "--cube-frames";
  const radar::Sensor* sensor = nullptr;  ///< must outlive the writer
  std::string scenario_name;
  /// Frames in flight between the frame thread and the writer: 0 picks 2 on the simulated
  /// clock (the loop waits), and in real time one a frame of the range up to 4 (a captured
  /// frame costs the writer a few frame periods; more frames than slots may be dropped).
  std::size_t slots = 0;
  bool wait_when_full = true;  ///< simulated clock: wait for a slot; real time: drop, count
  std::size_t max_returns = std::size_t{1} << 17;  ///< per frame (beyond: counted, not in raw)
  std::size_t max_false_alarms_per_beam = 256;
};

/// What the cube file got and lost.
struct CubeCounters {
  std::uint64_t frames_written = 0;
  std::uint64_t frames_dropped = 0;        ///< real time: no free slot
  std::uint64_t frames_without_state = 0;  ///< in the range, no ownship state: nothing sensed
  std::uint64_t waits = 0;                 ///< simulated clock: the loop waited for the writer
  std::uint64_t capture_dropped = 0;       ///< returns and false alarms that found no room
  std::uint64_t write_errors = 0;          ///< failed HDF5 calls (their frame is incomplete)
  std::uint64_t bytes_written = 0;         ///< cube data (raw and image)
  std::string first_error;                 ///< "" when none
  std::string file;                        ///< the file, and the range it covers (clipped)
  std::uint64_t first_frame = 0, last_frame = 0;
  [[nodiscard]] bool complete() const noexcept {
    return frames_dropped == 0 && write_errors == 0 && capture_dropped == 0;
  }
};

/// A frame range FIRST:LAST (frame indices from 0, inclusive; `--cube-frames`, `[output]
/// cube_frames`) into `first` and `last`: "" when it parses, else what is wrong.
[[nodiscard]] std::string parse_cube_frames(const std::string& text, std::uint64_t& first,
                                            std::uint64_t& last);

/// Bytes a captured frame adds to the file (raw and image, complex64), for the estimate.
[[nodiscard]] std::uint64_t cube_bytes_per_frame(const radar::CaptureShape& shape) noexcept;

class CubeWriter {
 public:
  /// Setup: checks the range (throws std::runtime_error: first frame past the run, or the
  /// estimated size over kCubeMaxBytes, with the estimate), creates the file (throws naming the
  /// path when HDF5 cannot), writes the layout's attributes, allocates the slots and starts the
  /// writer thread.
  explicit CubeWriter(CubeWriterConfig config);
  ~CubeWriter();
  CubeWriter(const CubeWriter&) = delete;
  CubeWriter& operator=(const CubeWriter&) = delete;

  // ---- the frame thread (real-time safe but for the documented wait on the simulated clock) ----
  /// Before frame `frame_index`'s sensor stage: the capture to arm the sensor with, or nullptr
  /// (outside the range, or no free slot in real time: counted).
  [[nodiscard]] radar::SensorCapture* begin_frame(std::uint64_t frame_index) noexcept;
  /// After the frame: hands the capture begin_frame() gave, filled or not, to the writer with
  /// the frame's record and detections. Does nothing when begin_frame() gave nullptr.
  void end_frame(const FrameRecord& record, std::span<const radar::Detection> detections) noexcept;

  // ---- teardown ----
  /// Writes what was handed over, stops the writer and closes the file. Idempotent; never throws
  /// for a write failure (counted). Call it from the frame thread.
  const CubeCounters& finish();
  /// After finish(): everything; before: the frame thread's counts only.
  [[nodiscard]] const CubeCounters& counters() const noexcept { return counters_; }
  [[nodiscard]] const CubeWriterConfig& config() const noexcept { return config_; }

 private:
  struct Slot;
  struct Hdf5;
  void writer_main() noexcept;
  void write_slot(Slot& slot) noexcept;

  CubeWriterConfig config_;
  radar::CaptureShape shape_;
  std::vector<std::unique_ptr<Slot>> slots_;
  std::unique_ptr<Hdf5> h5_;
  std::size_t next_write_ = 0;  ///< frame thread: the slot the next capture fills
  std::size_t next_read_ = 0;   ///< writer: the slot it writes next
  Slot* armed_ = nullptr;       ///< frame thread: the slot of the frame in flight
  // The writer's own buffers (allocated at setup).
  std::vector<std::complex<float>> raw_;
  std::unique_ptr<radar::Sensor::RawWorkspace> raw_workspace_;
  std::vector<std::uint64_t> written_frames_;
  std::atomic<std::uint32_t> wake_{0};  ///< bumped (and notified) when a slot is ready or on stop
  std::atomic<bool> stop_{false};
  bool finished_ = false;
  CubeCounters counters_;  ///< the frame thread's counts; the writer's are merged at finish()
  CubeCounters written_;   ///< the writer's counts (read after it has stopped)
  std::thread writer_;
};

}  // namespace radar_emu::loop
