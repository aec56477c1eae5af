#include "loop/outputs/output_stream.hpp"

#include <fcntl.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <charconv>
#include <chrono>
#include <cmath>
#include <cstring>
#include <nlohmann/json.hpp>
#include <stdexcept>
#include <string_view>
#include <system_error>

#include "common/units.hpp"
#include "io/candump.hpp"
#include "loop/outputs/run_plots.hpp"

namespace radar_emu::loop {

namespace {

constexpr std::size_t kFileBuffer = 1u << 20;  // 1 MiB a file
// A typical frame of detections.json fits (64 detections of about 500 characters): it then
// goes to the file in one write. Larger ones are split (File::put flushes when full).
constexpr std::size_t kLargestRecord = 64u * 1024u;
constexpr auto kWriterIdle = std::chrono::milliseconds(2);
constexpr auto kProducerWait = std::chrono::microseconds(100);

// Ring slots for `frames` frames of `per_frame` entries each (at least one frame's worth).
std::size_t slots(std::size_t frames, std::size_t per_frame) {
  return std::max<std::size_t>(1, frames) * std::max<std::size_t>(1, per_frame);
}

}  // namespace

// ---- one buffered file -------------------------------------------------------------------

class OutputStream::File {
 public:
  File(const std::filesystem::path& path, std::string name)
      : name_(std::move(name)), buffer_(kFileBuffer, '\0') {
    fd_ = ::open(path.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
    if (fd_ < 0) {
      throw std::runtime_error(path.string() +
                               ": cannot open for writing: " + std::strerror(errno));
    }
  }
  ~File() { close(); }
  File(const File&) = delete;
  File& operator=(const File&) = delete;

  void put(std::string_view s) noexcept {
    if (used_ + s.size() > buffer_.size())
      flush();
    if (s.size() > buffer_.size()) {
      write_all(s.data(), s.size());
      return;
    }
    std::memcpy(buffer_.data() + used_, s.data(), s.size());
    used_ += s.size();
  }
  void put(char c) noexcept { put(std::string_view(&c, 1)); }
  void put_uint(std::uint64_t v) noexcept {
    char b[24];
    const auto r = std::to_chars(b, b + sizeof b, v);
    put(std::string_view(b, static_cast<std::size_t>(r.ptr - b)));
  }
  /// Shortest text that reads back as the same double; JSON null when not finite.
  void put_double(double v) noexcept {
    if (!std::isfinite(v)) {
      put("null");
      return;
    }
    char b[32];
    const auto r = std::to_chars(b, b + sizeof b, v);
    put(std::string_view(b, static_cast<std::size_t>(r.ptr - b)));
  }
  void put_fixed(double v, int decimals) noexcept {
    char b[48];
    const auto r = std::to_chars(b, b + sizeof b, v, std::chars_format::fixed, decimals);
    if (r.ec == std::errc())
      put(std::string_view(b, static_cast<std::size_t>(r.ptr - b)));
  }
  /// Room for one whole record: flushes first when the buffer cannot take `bytes` more.
  void reserve(std::size_t bytes) noexcept {
    if (used_ + bytes > buffer_.size())
      flush();
  }
  [[nodiscard]] std::span<char> tail() noexcept {
    return std::span(buffer_.data() + used_, buffer_.size() - used_);
  }
  void commit(std::size_t n) noexcept { used_ += n; }

  void flush() noexcept {
    if (used_ > 0)
      write_all(buffer_.data(), used_);
    used_ = 0;
  }
  void close() noexcept {
    if (fd_ < 0)
      return;
    flush();
    if (::close(fd_) != 0)
      count_error(errno, 0);
    fd_ = -1;
  }
  [[nodiscard]] OutputFileCounters counters() const {
    OutputFileCounters c;
    c.name = name_;
    c.bytes_written = bytes_written_;
    c.write_errors = write_errors_;
    c.bytes_lost = bytes_lost_;
    if (first_errno_ != 0)
      c.first_error = std::strerror(first_errno_);
    return c;
  }
  void count_error(int err, std::size_t lost) noexcept {
    ++write_errors_;
    bytes_lost_ += lost;
    if (first_errno_ == 0)
      first_errno_ = err;
  }

 private:
  // Writes everything or counts what could not be written (disk full, I/O error): the writer
  // carries on with the next record.
  void write_all(const char* p, std::size_t n) noexcept {
    while (n > 0) {
      const ssize_t w = ::write(fd_, p, n);
      if (w < 0 && errno == EINTR)
        continue;
      if (w <= 0) {
        count_error(w < 0 ? errno : EIO, n);
        return;
      }
      bytes_written_ += static_cast<std::uint64_t>(w);
      p += w;
      n -= static_cast<std::size_t>(w);
    }
  }

  std::string name_;
  std::vector<char> buffer_;  ///< filled at construction: its pages are resident from setup
  std::size_t used_ = 0;
  int fd_ = -1;
  std::uint64_t bytes_written_ = 0;
  std::uint64_t write_errors_ = 0;
  std::uint64_t bytes_lost_ = 0;
  int first_errno_ = 0;
};

namespace {
enum FileIndex : std::size_t { kBusIn = 0, kBusOut, kDetections, kTruth, kFramesCsv };
}  // namespace

// ---- setup and teardown ------------------------------------------------------------------

OutputStream::OutputStream(OutputStreamConfig config)
    : config_(std::move(config)),
      bus_ring_(slots(config_.slack_frames, config_.bus_frames_per_frame)),
      frame_ring_(slots(config_.slack_frames, 1)),
      detection_ring_(slots(config_.slack_frames, config_.max_detections)),
      truth_ring_(slots(config_.slack_frames, config_.truth_objects.size())),
      scratch_detections_(std::max<std::size_t>(1, config_.max_detections)) {
  if (config_.scenario == nullptr)
    throw std::invalid_argument("OutputStream: no scenario");
  std::error_code ec;
  std::filesystem::create_directories(config_.dir, ec);
  if (ec) {
    throw std::runtime_error(config_.dir.string() +
                             ": cannot create the output directory: " + ec.message());
  }
  for (const char* name : kStreamedFiles)
    files_.push_back(std::make_unique<File>(config_.dir / name, name));
  bscope_ = std::make_unique<BScope>(*config_.scenario, config_.frames_planned);
  // Object names as JSON strings, escaped once here.
  for (const std::string& n : config_.object_names)
    object_json_.push_back(nlohmann::json(n).dump());

  // The documents' heads: everything but the frames, which follow as they come.
  const Scenario& s = *config_.scenario;
  nlohmann::ordered_json dets;
  dets["scenario"] = s.name;
  dets["units"] = {
      {"range", "m"},
      {"azimuth", "deg, positive right of boresight"},
      {"elevation", "deg, positive up"},
      {"radial_velocity", "m/s, positive receding"},
      {"snr", "dB"},
      {"rcs", "dBsm"},
      {"*_std", "one-sigma thermal-noise accuracy, same unit as the value"},
      {"range_ambiguous / velocity_ambiguous",
       "the waveform may have folded this value (unambiguous interval in report.json)"},
      {"object_id / object",
       "scene object whose return dominates the cell (truth.json); null / \"clutter\" when "
       "clutter or noise dominates"}};
  nlohmann::ordered_json truth;
  truth["scenario"] = s.name;
  truth["definition"] = {
      {"objects",
       "scene objects with a conducting material (the tracer's targets; pure terrain is left "
       "out) whose reference point is inside the field of view and within max_range_m"},
      {"reference_point", "centre of the object's world axis-aligned bounding box at the frame"},
      {"range_m", "antenna phase centre to the reference point"},
      {"azimuth_deg", "antenna frame, positive right of boresight"},
      {"elevation_deg", "antenna frame, positive up"},
      {"radial_velocity_mps",
       "range rate of the reference point, positive receding, ownship motion included"}};
  nlohmann::ordered_json objs = nlohmann::ordered_json::array();
  for (std::uint32_t id : config_.truth_objects) {
    objs.push_back({{"object_id", id},
                    {"object", id < config_.object_names.size() ? config_.object_names[id]
                                                                : std::string("unknown")}});
  }
  truth["objects"] = std::move(objs);
  // {"a":...,"b":...} -> {"a":...,"b":...,"frames":[  (one frame a line follows)
  auto head = [](const nlohmann::ordered_json& j) {
    std::string h = j.dump();
    h.pop_back();
    return h + ",\"frames\":[\n";
  };
  files_[kDetections]->put(head(dets));
  files_[kTruth]->put(head(truth));
  files_[kFramesCsv]->put(
      "frame,time_s,frame_counter,status,ownship_valid,sent,late,detections,objects_in_beam,"
      "input_ms,scene_update_ms,trace_ms,sensor_ms,output_ms,frame_ms,wake_latency_ms,"
      "governor_level,governor_predicted_ms,governor_estimated_snr_error_db,rays,"
      "governor_predicted_trace_ms,governor_predicted_sensor_ms,kept_returns,returns,"
      "cells_synthesised,terrain_patches,terrain_facets,target_facets,terrain_returns,"
      "merged_returns\n");
  writer_ = std::thread([this] { writer_main(); });
}

OutputStream::~OutputStream() {
  try {
    (void)finish();
  } catch (...) {  // a destructor does not throw; finish() counts write failures itself
  }
}

const OutputCounters& OutputStream::finish() {
  if (finished_)
    return counters_;
  finished_ = true;
  stop_.store(true, std::memory_order_release);
  if (writer_.joinable())
    writer_.join();
  write_trailers();
  for (auto& f : files_)
    f->close();
  counters_ = {};
  counters_.frames_written = frames_written_;
  counters_.frames_dropped = frames_dropped_;
  counters_.bus_frames_written = bus_frames_written_;
  counters_.bus_frames_dropped = bus_frames_dropped_;
  counters_.detections_written = detections_written_;
  counters_.waits = waits_;
  for (const auto& f : files_)
    counters_.files.push_back(f->counters());
  OutputFileCounters png;
  png.name = "detections.png";
  try {
    bscope_->write_png(config_.dir / png.name);
    std::error_code ec;
    png.bytes_written = std::filesystem::file_size(config_.dir / png.name, ec);
  } catch (const std::exception& e) {
    png.write_errors = 1;
    png.first_error = e.what();
  }
  counters_.files.push_back(std::move(png));
  return counters_;
}

OutputCounters OutputStream::counters() const {
  if (finished_)
    return counters_;
  OutputCounters c;
  c.frames_dropped = frames_dropped_;
  c.bus_frames_dropped = bus_frames_dropped_;
  c.waits = waits_;
  return c;
}

// ---- the frame thread --------------------------------------------------------------------

void OutputStream::push_bus(const io::CanFrame& frame, bool out) noexcept {
  const BusEntry e{frame, out};
  if (bus_ring_.push(e))
    return;
  if (!config_.wait_when_full || finished_) {  // no writer left to wait for
    ++bus_frames_dropped_;
    return;
  }
  ++waits_;
  while (!bus_ring_.push(e))
    std::this_thread::sleep_for(kProducerWait);
}

void OutputStream::wait_for_room() noexcept {
  if (!config_.wait_when_full || finished_)
    return;
  const std::size_t need = std::min(config_.bus_frames_per_frame, bus_ring_.capacity());
  if (bus_ring_.capacity() - bus_ring_.size() >= need)
    return;
  ++waits_;
  while (bus_ring_.capacity() - bus_ring_.size() < need)
    std::this_thread::sleep_for(kProducerWait);
}

void OutputStream::frame(const FrameRecord& record,
                         const std::array<std::int64_t, timing::kStageCount>& stage_ns,
                         std::span<const io::icd::Detection> detections,
                         std::span<const radar::Detection> sensor,
                         std::span<const ObjectTruth> truth) noexcept {
  // Never more than a ring holds (the frame thread's buffers are sized like the rings).
  detections = detections.first(std::min(detections.size(), detection_ring_.capacity()));
  truth = truth.first(std::min(truth.size(), truth_ring_.capacity()));
  // The producer's view of the free space is conservative: the writer only frees more.
  auto room = [&] {
    return frame_ring_.size() < frame_ring_.capacity() &&
           detection_ring_.capacity() - detection_ring_.size() >= detections.size() &&
           truth_ring_.capacity() - truth_ring_.size() >= truth.size();
  };
  if (!room() || finished_) {
    if (!config_.wait_when_full || finished_) {
      ++frames_dropped_;
      return;
    }
    ++waits_;
    while (!room())
      std::this_thread::sleep_for(kProducerWait);
  }
  // Detections and truth first: the writer takes them once it has seen the frame entry.
  for (std::size_t i = 0; i < detections.size(); ++i) {
    DetectionEntry d;
    d.detection = detections[i];
    d.object_id = i < sensor.size() ? sensor[i].object_id : radar::kNoObject;
    (void)detection_ring_.push(d);
  }
  for (const ObjectTruth& t : truth)
    (void)truth_ring_.push(t);
  FrameEntry e;
  e.record = record;
  e.record.detection_count = static_cast<std::uint32_t>(detections.size());
  e.record.truth_count = static_cast<std::uint32_t>(truth.size());
  e.stage_ns = stage_ns;
  (void)frame_ring_.push(e);
}

// ---- the writer thread -------------------------------------------------------------------

void OutputStream::writer_main() noexcept {
  for (;;) {
    // Seen before the drain: once stop is set, the frame thread has handed over everything, so
    // a drain that finds the rings empty has written all of it.
    const bool stopping = stop_.load(std::memory_order_acquire);
    if (drain())
      continue;
    for (auto& f : files_)
      f->flush();  // idle: the files on disk are current within a few milliseconds
    if (stopping)
      return;
    std::this_thread::sleep_for(kWriterIdle);
  }
}

bool OutputStream::drain() noexcept {
  bool any = false;
  BusEntry b;
  for (int n = 0; n < 4096 && bus_ring_.pop(b); ++n) {
    any = true;
    File& f = *files_[b.out ? kBusOut : kBusIn];
    f.reserve(io::kCandumpMaxLine);
    const std::size_t len = io::format_candump(b.frame, config_.interface_name, f.tail());
    f.commit(len);
    ++bus_frames_written_;
  }
  FrameEntry e;
  for (int n = 0; n < 64 && frame_ring_.pop(e); ++n) {
    any = true;
    write_frame(e);
  }
  return any;
}

std::string_view OutputStream::object_json(std::uint32_t id) const noexcept {
  if (id == radar::kNoObject)
    return "\"clutter\"";
  return id < object_json_.size() ? std::string_view(object_json_[id]) : "\"unknown\"";
}

void OutputStream::write_frame(const FrameEntry& e) noexcept {
  const bool first = frames_written_ == 0;
  write_detections(e.record, first);
  write_truth(e.record, first);
  write_frames_csv(e);
  ++frames_written_;
}

void OutputStream::write_detections(const FrameRecord& rec, bool first) noexcept {
  // detections.json: one frame a line, values before ICD quantisation.
  File& d = *files_[kDetections];
  d.reserve(kLargestRecord);
  if (!first)
    d.put(",\n");
  d.put("{\"frame_counter\":");
  d.put_uint(rec.header.frame_counter);
  d.put(",\"time_s\":");
  d.put_double(rec.time_s);
  d.put(",\"status\":");
  d.put_uint(rec.header.status);
  if (!rec.sent)
    d.put(",\"sent\":false");  // stale_output = "silent": nothing went on the bus
  if (rec.ownship_valid) {
    d.put(",\"ownship_enu_m\":[");
    d.put_double(rec.ownship_enu_m.x);
    d.put(',');
    d.put_double(rec.ownship_enu_m.y);
    d.put(',');
    d.put_double(rec.ownship_enu_m.z);
    d.put(']');
  }
  d.put(",\"detections\":[");
  const std::size_t n_det = std::min<std::size_t>(rec.detection_count, scratch_detections_.size());
  DetectionEntry de;
  for (std::size_t i = 0; i < rec.detection_count; ++i) {
    if (!detection_ring_.pop(de))
      break;  // cannot happen: pushed before the frame entry
    if (i < n_det)
      scratch_detections_[i] = de.detection;
    const io::icd::Detection& x = de.detection;
    d.put(i == 0 ? "{\"range_m\":" : ",{\"range_m\":");
    d.put_double(x.range_m);
    d.put(",\"azimuth_deg\":");
    d.put_double(x.azimuth_deg);
    d.put(",\"elevation_deg\":");
    d.put_double(x.elevation_deg);
    d.put(",\"radial_velocity_mps\":");
    d.put_double(x.radial_velocity_mps);
    d.put(",\"snr_db\":");
    d.put_double(x.snr_db);
    d.put(",\"rcs_dbsm\":");
    d.put_double(x.rcs_dbsm);
    d.put(",\"range_std_m\":");
    d.put_double(x.range_std_m);
    d.put(",\"azimuth_std_deg\":");
    d.put_double(x.azimuth_std_deg);
    d.put(",\"elevation_std_deg\":");
    d.put_double(x.elevation_std_deg);
    d.put(",\"radial_velocity_std_mps\":");
    d.put_double(x.radial_velocity_std_mps);
    d.put(x.range_ambiguous ? ",\"range_ambiguous\":true" : ",\"range_ambiguous\":false");
    d.put(x.velocity_ambiguous ? ",\"velocity_ambiguous\":true" : ",\"velocity_ambiguous\":false");
    d.put(",\"object_id\":");
    if (de.object_id == radar::kNoObject)
      d.put("null");
    else
      d.put_uint(de.object_id);
    d.put(",\"object\":");
    d.put(object_json(de.object_id));
    d.put('}');
  }
  d.put("]}");
  detections_written_ += rec.detection_count;
  bscope_->add_frame(std::span<const io::icd::Detection>(scratch_detections_.data(), n_det));
}

void OutputStream::write_truth(const FrameRecord& rec, bool first) noexcept {
  // truth.json: the objects in the beam.
  File& t = *files_[kTruth];
  t.reserve(kLargestRecord);
  if (!first)
    t.put(",\n");
  t.put("{\"frame_counter\":");
  t.put_uint(rec.header.frame_counter);
  t.put(",\"time_s\":");
  t.put_double(rec.time_s);
  t.put(rec.ownship_valid ? ",\"ownship_valid\":true" : ",\"ownship_valid\":false");
  t.put(",\"objects\":[");
  ObjectTruth o;
  for (std::uint32_t i = 0; i < rec.truth_count && truth_ring_.pop(o); ++i) {
    t.put(i == 0 ? "{\"object_id\":" : ",{\"object_id\":");
    t.put_uint(o.object_id);
    t.put(",\"object\":");
    t.put(object_json(o.object_id));
    t.put(",\"range_m\":");
    t.put_double(o.range_m);
    t.put(",\"azimuth_deg\":");
    t.put_double(common::degrees(o.azimuth_rad));
    t.put(",\"elevation_deg\":");
    t.put_double(common::degrees(o.elevation_rad));
    t.put(",\"radial_velocity_mps\":");
    t.put_double(o.radial_velocity_mps);
    t.put('}');
  }
  t.put("]}");
}

void OutputStream::write_frames_csv(const FrameEntry& e) noexcept {
  const FrameRecord& rec = e.record;
  // frames.csv: one line a frame, the stage times in ms (empty when not measured).
  File& c = *files_[kFramesCsv];
  c.reserve(1024);
  c.put_uint(rec.frame_index);
  c.put(',');
  c.put_double(rec.time_s);
  c.put(',');
  c.put_uint(rec.header.frame_counter);
  c.put(',');
  c.put_uint(rec.header.status);
  c.put(rec.ownship_valid ? ",1" : ",0");
  c.put(rec.sent ? ",1" : ",0");
  c.put(rec.late ? ",1," : ",0,");
  c.put_uint(rec.detection_count);
  c.put(',');
  c.put_uint(rec.truth_count);
  for (timing::Stage st : {timing::Stage::kInput, timing::Stage::kSceneUpdate,
                           timing::Stage::kTrace, timing::Stage::kSensor, timing::Stage::kOutput,
                           timing::Stage::kFrame, timing::Stage::kWakeLatency}) {
    c.put(',');
    const std::int64_t ns = e.stage_ns[static_cast<std::size_t>(st)];
    if (ns >= 0 && (st != timing::Stage::kWakeLatency || config_.wake_latency))
      c.put_fixed(static_cast<double>(ns) * 1e-6, 6);
  }
  c.put(',');
  c.put_uint(static_cast<std::uint64_t>(rec.governor_level));
  c.put(',');
  c.put_fixed(rec.governor_predicted_ms, 3);
  c.put(',');
  c.put_fixed(rec.governor_error_db, 2);
  c.put(',');
  c.put_uint(rec.rays);
  c.put(',');
  c.put_fixed(rec.governor_predicted_trace_ms, 3);
  c.put(',');
  c.put_fixed(rec.governor_predicted_sensor_ms, 3);
  for (std::uint64_t v :
       {rec.kept_returns, rec.returns, rec.cells_synthesised, rec.terrain_patches,
        rec.terrain_facets, rec.target_facets, rec.terrain_returns, rec.merged_returns}) {
    c.put(',');
    c.put_uint(v);
  }
  c.put('\n');
}

void OutputStream::write_trailers() noexcept {
  auto close_doc = [&](File& f) {
    f.put(frames_written_ == 0 ? "]" : "\n]");
    f.put(",\"frames_dropped\":");
    f.put_uint(frames_dropped_);
    f.put("}\n");
  };
  close_doc(*files_[kDetections]);
  close_doc(*files_[kTruth]);
}

}  // namespace radar_emu::loop
