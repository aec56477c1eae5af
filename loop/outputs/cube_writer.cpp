#include "loop/outputs/cube_writer.hpp"

#include <hdf5.h>

#include <algorithm>
#include <array>
#include <cstdio>
#include <stdexcept>
#include <string_view>

#include "radar/constants.hpp"
#include "radar/sensor/capture_storage.hpp"
#include "radar/sensor/waveform.hpp"

namespace radar_emu::loop {

namespace {

constexpr int kFree = 0, kFilling = 1, kReady = 2;

// One detection row of a frame's `detections` table (docs/cube.md).
struct DetectionRow {
  double range_m;
  double radial_velocity_mps;
  double azimuth_rad;
  double elevation_rad;
  double snr;
  double rcs_m2;
  std::uint32_t range_cell;
  std::uint32_t doppler_cell;
  std::uint32_t azimuth_cell;
  std::uint32_t object_id;
};

std::string mib(std::uint64_t bytes) {
  char buf[64];
  std::snprintf(buf, sizeof buf, "%.1f MiB", static_cast<double>(bytes) / (1024.0 * 1024.0));
  return buf;
}

}  // namespace

std::string parse_cube_frames(const std::string& text, std::uint64_t& first, std::uint64_t& last) {
  const std::size_t colon = text.find(':');
  auto number = [](const std::string& t, std::uint64_t& v) {
    if (t.empty() || t.find_first_not_of("0123456789") != std::string::npos || t.size() > 18)
      return false;
    v = std::stoull(t);
    return true;
  };
  if (colon == std::string::npos || !number(text.substr(0, colon), first) ||
      !number(text.substr(colon + 1), last))
    return "'" + text + "' is not FIRST:LAST (frame indices from 0, e.g. 0:3)";
  if (last < first)
    return "'" + text + "': LAST is before FIRST";
  return {};
}

std::uint64_t cube_bytes_per_frame(const radar::CaptureShape& shape) noexcept {
  return 8ull * (shape.raw_values() + shape.image_values());
}

struct CubeWriter::Slot : radar::CaptureStorage {
  using radar::CaptureStorage::CaptureStorage;
  FrameRecord record{};
  std::vector<radar::Detection> detections;
  std::size_t detection_count = 0;
  std::atomic<int> state{kFree};
};

// HDF5 handles the writer uses (types made once; the file open from setup to finish()).
struct CubeWriter::Hdf5 {
  hid_t file = -1;
  hid_t complex64 = -1;  ///< compound {r, i} of float32: h5py reads it as complex64
  hid_t detection = -1;
  hid_t text = -1;  ///< variable-length UTF-8 string
  ~Hdf5() {
    for (hid_t t : {complex64, detection, text})
      if (t >= 0)
        H5Tclose(t);
    if (file >= 0)
      H5Fclose(file);
  }
};

namespace {

// Attribute writers: each returns false on an HDF5 failure.
bool attr_doubles(hid_t loc, const char* name, std::span<const double> v) {
  const hsize_t n = v.size();
  const hid_t space = v.size() == 1 ? H5Screate(H5S_SCALAR) : H5Screate_simple(1, &n, nullptr);
  if (space < 0)
    return false;
  const hid_t a = H5Acreate2(loc, name, H5T_NATIVE_DOUBLE, space, H5P_DEFAULT, H5P_DEFAULT);
  const bool ok = a >= 0 && H5Awrite(a, H5T_NATIVE_DOUBLE, v.data()) >= 0;
  if (a >= 0)
    H5Aclose(a);
  H5Sclose(space);
  return ok;
}
bool attr_double(hid_t loc, const char* name, double v) {
  return attr_doubles(loc, name, std::span(&v, 1));
}
bool attr_u64(hid_t loc, const char* name, std::uint64_t v) {
  const hid_t space = H5Screate(H5S_SCALAR);
  if (space < 0)
    return false;
  const hid_t a = H5Acreate2(loc, name, H5T_NATIVE_UINT64, space, H5P_DEFAULT, H5P_DEFAULT);
  const bool ok = a >= 0 && H5Awrite(a, H5T_NATIVE_UINT64, &v) >= 0;
  if (a >= 0)
    H5Aclose(a);
  H5Sclose(space);
  return ok;
}
bool attr_text(hid_t loc, hid_t text, const char* name, const std::string& v) {
  const hid_t space = H5Screate(H5S_SCALAR);
  if (space < 0)
    return false;
  const hid_t a = H5Acreate2(loc, name, text, space, H5P_DEFAULT, H5P_DEFAULT);
  const char* p = v.c_str();
  const bool ok = a >= 0 && H5Awrite(a, text, &p) >= 0;
  if (a >= 0)
    H5Aclose(a);
  H5Sclose(space);
  return ok;
}
// A dataset of `rank` dimensions written in one call.
bool dataset(hid_t loc, const char* name, hid_t type, std::span<const hsize_t> dims,
             const void* data) {
  const hid_t space = H5Screate_simple(static_cast<int>(dims.size()), dims.data(), nullptr);
  if (space < 0)
    return false;
  const hid_t d = H5Dcreate2(loc, name, type, space, H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT);
  bool ok = d >= 0;
  if (ok && H5Sget_simple_extent_npoints(space) > 0)
    ok = H5Dwrite(d, type, H5S_ALL, H5S_ALL, H5P_DEFAULT, data) >= 0;
  if (d >= 0)
    ok = H5Dclose(d) >= 0 && ok;
  H5Sclose(space);
  return ok;
}

}  // namespace

CubeWriter::CubeWriter(CubeWriterConfig config) : config_(std::move(config)) {
  if (config_.sensor == nullptr)
    throw std::invalid_argument("cube: no sensor");
  const radar::Sensor& sensor = *config_.sensor;
  shape_ = sensor.capture_shape();
  const std::string where = config_.file_source + " " + config_.file.string();
  const std::string& frames_option = config_.frames_source;
  if (config_.run_frames == 0 || config_.first_frame >= config_.run_frames) {
    throw std::runtime_error(where + ": " + frames_option + " starts at frame " +
                             std::to_string(config_.first_frame) + ", past the run's " +
                             std::to_string(config_.run_frames) + " frames (0.." +
                             std::to_string(config_.run_frames - 1) + ")");
  }
  if (config_.last_frame < config_.first_frame)
    throw std::runtime_error(where + ": " + frames_option + " FIRST:LAST needs FIRST <= LAST");
  config_.last_frame = std::min(config_.last_frame, config_.run_frames - 1);
  const std::uint64_t n_frames = config_.last_frame - config_.first_frame + 1;
  const std::uint64_t per_frame = cube_bytes_per_frame(shape_);
  if (n_frames * per_frame > kCubeMaxBytes) {
    throw std::runtime_error(
        where + ": frames " + std::to_string(config_.first_frame) + ".." +
        std::to_string(config_.last_frame) + " would write " + mib(n_frames * per_frame) + " (" +
        mib(per_frame) + " a frame: " + std::to_string(shape_.beams) + " beams x " +
        std::to_string(shape_.channels) + " channels x " + std::to_string(shape_.pulses) +
        " pulses x " + std::to_string(shape_.fast_samples) + " samples raw, " +
        std::to_string(shape_.velocity_bins) + " x " + std::to_string(shape_.range_bins) +
        " cells a beam after), over the " + mib(kCubeMaxBytes) + " limit: narrow " + frames_option +
        " (at most " + std::to_string(kCubeMaxBytes / per_frame) + " frames)");
  }

  counters_.file = config_.file.string();
  counters_.first_frame = config_.first_frame;
  counters_.last_frame = config_.last_frame;

  // The file, its types and the layout's attributes (docs/cube.md).
  H5Eset_auto2(H5E_DEFAULT, nullptr, nullptr);  // failures are reported here, not printed
  h5_ = std::make_unique<Hdf5>();
  Hdf5& h = *h5_;
  h.file = H5Fcreate(config_.file.c_str(), H5F_ACC_TRUNC, H5P_DEFAULT, H5P_DEFAULT);
  if (h.file < 0)
    throw std::runtime_error(where +
                             ": cannot create the HDF5 file (directory missing or not "
                             "writable?)");
  h.complex64 = H5Tcreate(H5T_COMPOUND, 2 * sizeof(float));
  H5Tinsert(h.complex64, "r", 0, H5T_NATIVE_FLOAT);
  H5Tinsert(h.complex64, "i", sizeof(float), H5T_NATIVE_FLOAT);
  h.detection = H5Tcreate(H5T_COMPOUND, sizeof(DetectionRow));
  H5Tinsert(h.detection, "range_m", HOFFSET(DetectionRow, range_m), H5T_NATIVE_DOUBLE);
  H5Tinsert(h.detection, "radial_velocity_mps", HOFFSET(DetectionRow, radial_velocity_mps),
            H5T_NATIVE_DOUBLE);
  H5Tinsert(h.detection, "azimuth_rad", HOFFSET(DetectionRow, azimuth_rad), H5T_NATIVE_DOUBLE);
  H5Tinsert(h.detection, "elevation_rad", HOFFSET(DetectionRow, elevation_rad), H5T_NATIVE_DOUBLE);
  H5Tinsert(h.detection, "snr", HOFFSET(DetectionRow, snr), H5T_NATIVE_DOUBLE);
  H5Tinsert(h.detection, "rcs_m2", HOFFSET(DetectionRow, rcs_m2), H5T_NATIVE_DOUBLE);
  H5Tinsert(h.detection, "range_cell", HOFFSET(DetectionRow, range_cell), H5T_NATIVE_UINT32);
  H5Tinsert(h.detection, "doppler_cell", HOFFSET(DetectionRow, doppler_cell), H5T_NATIVE_UINT32);
  H5Tinsert(h.detection, "azimuth_cell", HOFFSET(DetectionRow, azimuth_cell), H5T_NATIVE_UINT32);
  H5Tinsert(h.detection, "object_id", HOFFSET(DetectionRow, object_id), H5T_NATIVE_UINT32);
  h.text = H5Tcopy(H5T_C_S1);
  H5Tset_size(h.text, H5T_VARIABLE);
  H5Tset_cset(h.text, H5T_CSET_UTF8);

  const radar::SensorConfig& sc = sensor.config();
  const radar::Waveform& w = sc.processing.waveform;
  const radar::RangeDopplerProcessor& proc = sensor.processor();
  const bool pulsed = w.kind == radar::WaveformKind::kPulsedLfm;
  const double lambda = radar::wavelength_m(w);
  const hid_t root = h.file;
  bool ok = attr_text(root, h.text, "format", "radar-emu cube 1");
  ok = attr_text(root, h.text, "scenario", config_.scenario_name) && ok;
  ok = attr_text(root, h.text, "waveform", pulsed ? "pulsed_lfm" : "fmcw") && ok;
  ok = attr_double(root, "carrier_hz", w.carrier_hz) && ok;
  ok = attr_double(root, "wavelength_m", lambda) && ok;
  ok = attr_double(root, "bandwidth_hz", w.bandwidth_hz) && ok;
  ok = attr_double(root, "pulse_width_s", w.pulse_width_s) && ok;
  ok = attr_double(root, "chirp_rate_hz_per_s", radar::chirp_rate_hz_per_s(w)) && ok;
  ok = attr_double(root, "sample_rate_hz", radar::fast_sample_rate_hz(w)) && ok;
  ok = attr_double(root, "first_sample_time_s",
                   pulsed ? 2.0 * radar::first_range_m(w) / radar::kSpeedOfLight_mps : 0.0) &&
       ok;
  ok = attr_double(root, "pri_s", w.pri_s) && ok;
  ok = attr_double(root, "prf_hz", 1.0 / w.pri_s) && ok;
  ok = attr_u64(root, "pulses", shape_.pulses) && ok;
  ok = attr_u64(root, "fast_samples", shape_.fast_samples) && ok;
  ok = attr_u64(root, "range_bins", shape_.range_bins) && ok;
  ok = attr_double(root, "range_bin0_m", proc.range_of_bin(0.0)) && ok;
  ok = attr_double(root, "range_bin_m", proc.range_of_bin(1.0) - proc.range_of_bin(0.0)) && ok;
  ok = attr_u64(root, "velocity_bins", shape_.velocity_bins) && ok;
  ok = attr_double(root, "velocity_bin0_mps", proc.velocity_of_bin(0.0)) && ok;
  const double dv = proc.velocity_of_bin(1.0) - proc.velocity_of_bin(0.0);
  ok = attr_double(root, "velocity_bin_mps", dv) && ok;
  ok = attr_double(root, "doppler_bin_hz", 2.0 * dv / lambda) && ok;
  ok = attr_double(root, "processing_gain", proc.processing_gain()) && ok;
  ok = attr_u64(root, "beams", shape_.beams) && ok;
  ok = attr_doubles(root, "beam_azimuth_rad", sc.antenna.beam_azimuth_rad) && ok;
  ok = attr_double(root, "beam_elevation_rad", sc.antenna.beam_elevation_rad) && ok;
  ok =
      attr_text(root, h.text, "channels", shape_.channels == 3 ? "sum,delta_az,delta_el" : "sum") &&
      ok;
  ok = attr_u64(root, "noise_seed", sc.noise_seed) && ok;
  ok = attr_u64(root, "first_frame", config_.first_frame) && ok;
  ok = attr_u64(root, "last_frame", config_.last_frame) && ok;
  const std::array<hsize_t, 1> n_range{proc.range_weights().size()};
  ok = dataset(root, "range_window", H5T_NATIVE_DOUBLE, n_range, proc.range_weights().data()) && ok;
  const std::array<hsize_t, 1> n_doppler{proc.doppler_weights().size()};
  ok = dataset(root, "doppler_window", H5T_NATIVE_DOUBLE, n_doppler,
               proc.doppler_weights().data()) &&
       ok;
  if (!ok)
    throw std::runtime_error(where + ": cannot write the file's attributes");

  // Slots and the writer's buffers: everything the frames need, now.
  const std::size_t n_slots = config_.slots > 0 ? config_.slots
                              : config_.wait_when_full
                                  ? 2
                                  : static_cast<std::size_t>(std::min<std::uint64_t>(n_frames, 4));
  for (std::size_t i = 0; i < n_slots; ++i) {
    auto s = std::make_unique<Slot>(shape_, config_.max_false_alarms_per_beam, config_.max_returns);
    s->detections.resize(sc.max_detections);
    slots_.push_back(std::move(s));
  }
  raw_.resize(shape_.raw_values());
  // Real time: the writer synthesises on its own thread only, leaving the other cores to the
  // frames; on the simulated clock the loop waits for it, so it takes what TBB has.
  raw_workspace_ = sensor.make_raw_workspace(config_.wait_when_full ? 4 : 1);
  written_frames_.reserve(n_frames);
  writer_ = std::thread([this] { writer_main(); });
}

CubeWriter::~CubeWriter() {
  try {
    finish();
  } catch (...) {  // NOLINT(bugprone-empty-catch): a destructor must not throw
  }
}

radar::SensorCapture* CubeWriter::begin_frame(std::uint64_t frame_index) noexcept {
  armed_ = nullptr;
  if (finished_ || frame_index < config_.first_frame || frame_index > config_.last_frame)
    return nullptr;
  Slot& s = *slots_[next_write_];
  int st = s.state.load(std::memory_order_acquire);
  if (st != kFree) {
    if (!config_.wait_when_full) {
      ++counters_.frames_dropped;
      return nullptr;
    }
    ++counters_.waits;
    while ((st = s.state.load(std::memory_order_acquire)) != kFree)
      s.state.wait(st, std::memory_order_acquire);
  }
  s.state.store(kFilling, std::memory_order_relaxed);
  s.capture.filled = false;
  armed_ = &s;
  return &s.capture;
}

void CubeWriter::end_frame(const FrameRecord& record,
                           std::span<const radar::Detection> detections) noexcept {
  Slot* s = armed_;
  armed_ = nullptr;
  if (s == nullptr)
    return;
  if (!s->capture.filled) {  // no ownship state: the sensor did not run
    ++counters_.frames_without_state;
    s->state.store(kFree, std::memory_order_release);
    return;
  }
  s->record = record;
  s->detection_count = std::min(detections.size(), s->detections.size());
  std::copy_n(detections.begin(), s->detection_count, s->detections.begin());
  s->state.store(kReady, std::memory_order_release);
  next_write_ = (next_write_ + 1) % slots_.size();
  wake_.fetch_add(1, std::memory_order_release);
  wake_.notify_one();
}

void CubeWriter::writer_main() noexcept {
  for (;;) {
    const std::uint32_t seen = wake_.load(std::memory_order_acquire);
    Slot& s = *slots_[next_read_];
    if (s.state.load(std::memory_order_acquire) == kReady) {
      write_slot(s);
      s.state.store(kFree, std::memory_order_release);
      s.state.notify_all();
      next_read_ = (next_read_ + 1) % slots_.size();
      continue;
    }
    if (stop_.load(std::memory_order_acquire))
      return;
    wake_.wait(seen, std::memory_order_acquire);
  }
}

void CubeWriter::write_slot(Slot& s) noexcept {
  const radar::Sensor& sensor = *config_.sensor;
  sensor.complete_image(s.capture);
  sensor.synthesise_raw(s.capture, raw_, *raw_workspace_);
  written_.capture_dropped += s.capture.dropped;
  Hdf5& h = *h5_;
  const std::uint64_t index = s.record.frame_index;
  char name[48];
  std::snprintf(name, sizeof name, "frame_%06llu", static_cast<unsigned long long>(index));
  auto fail = [&](const char* what) {
    ++written_.write_errors;
    if (written_.first_error.empty())
      written_.first_error = std::string(what) + " of " + name + " failed";
  };
  const hid_t g = H5Gcreate2(h.file, name, H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT);
  if (g < 0) {
    fail("creating the group");
    return;
  }
  bool ok = attr_u64(g, "frame_index", index);
  ok = attr_double(g, "time_s", s.record.time_s) && ok;
  const std::array<double, 3> enu{s.record.ownship_enu_m.x, s.record.ownship_enu_m.y,
                                  s.record.ownship_enu_m.z};
  ok = attr_doubles(g, "ownship_enu_m", enu) && ok;
  ok = attr_u64(g, "detection_count", s.detection_count) && ok;
  ok = attr_u64(g, "returns", s.capture.return_count) && ok;
  ok = attr_u64(g, "governor_level", static_cast<std::uint64_t>(s.record.governor_level)) && ok;
  if (!ok)
    fail("an attribute");
  const std::array<hsize_t, 4> raw_dims{shape_.beams, shape_.channels, shape_.pulses,
                                        shape_.fast_samples};
  if (dataset(g, "raw", h.complex64, raw_dims, raw_.data()))
    written_.bytes_written += 8ull * shape_.raw_values();
  else
    fail("writing raw");
  const std::array<hsize_t, 3> image_dims{shape_.beams, shape_.velocity_bins, shape_.range_bins};
  if (dataset(g, "image", h.complex64, image_dims, s.image.data()))
    written_.bytes_written += 8ull * shape_.image_values();
  else
    fail("writing image");
  std::array<DetectionRow, 256> rows{};
  const std::size_t n = std::min(s.detection_count, rows.size());
  for (std::size_t i = 0; i < n; ++i) {
    const radar::Detection& d = s.detections[i];
    rows[i] = {d.range_m, d.radial_velocity_mps, d.azimuth_rad,  d.elevation_rad, d.snr,
               d.rcs_m2,  d.range_cell,          d.doppler_cell, d.azimuth_cell,  d.object_id};
  }
  const std::array<hsize_t, 1> det_dims{n};
  if (!dataset(g, "detections", h.detection, det_dims, rows.data()))
    fail("writing detections");
  if (H5Gclose(g) < 0)
    fail("closing the group");
  // Data on disk frame by frame: a run that is killed keeps the frames written so far.
  if (H5Fflush(h.file, H5F_SCOPE_LOCAL) < 0)
    fail("flushing");
  ++written_.frames_written;
  written_frames_.push_back(index);
}

const CubeCounters& CubeWriter::finish() {
  if (finished_)
    return counters_;
  finished_ = true;
  if (armed_ != nullptr) {  // a frame that never ended
    armed_->state.store(kFree, std::memory_order_release);
    armed_ = nullptr;
  }
  stop_.store(true, std::memory_order_release);
  wake_.fetch_add(1, std::memory_order_release);
  wake_.notify_one();
  if (writer_.joinable())
    writer_.join();
  counters_.frames_written = written_.frames_written;
  counters_.write_errors = written_.write_errors;
  counters_.bytes_written = written_.bytes_written;
  counters_.capture_dropped = written_.capture_dropped;
  counters_.first_error = written_.first_error;
  // The index of what the file holds, and its counts.
  Hdf5& h = *h5_;
  const std::array<hsize_t, 1> dims{written_frames_.size()};
  bool ok = dataset(h.file, "frames", H5T_NATIVE_UINT64, dims, written_frames_.data());
  ok = attr_u64(h.file, "frames_written", counters_.frames_written) && ok;
  ok = attr_u64(h.file, "frames_dropped", counters_.frames_dropped) && ok;
  ok = attr_u64(h.file, "write_errors", counters_.write_errors) && ok;
  if (!ok) {
    ++counters_.write_errors;
    if (counters_.first_error.empty())
      counters_.first_error = "writing the frame index failed";
  }
  if (H5Fclose(h.file) < 0) {
    ++counters_.write_errors;
    if (counters_.first_error.empty())
      counters_.first_error = "closing the file failed";
  }
  h.file = -1;
  return counters_;
}

}  // namespace radar_emu::loop
