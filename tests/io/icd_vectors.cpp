// Writes test vectors for tests/io/check_dbc.py: random detection lists (fixed seed, printed)
// encoded with the ICD, classic (detections.log) and CAN FD (detections_fd.log), as candump logs
// plus their physical values as JSON, and CANaerospace frames with their values.
// usage: icd_vectors OUT_DIR

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <ostream>
#include <random>
#include <vector>

#include "io/canaerospace.hpp"
#include "io/candump.hpp"
#include "io/detection_icd.hpp"

namespace io = radar_emu::io;
namespace icd = radar_emu::io::icd;

namespace {
// One list's physical values as JSON (the FD lists also carry accuracies and flags).
void write_list_json(std::ostream& json, bool first, const icd::Header& h,
                     const std::vector<icd::Detection>& dets, bool fd) {
  json << (first ? "" : ",\n") << "{\"frame_counter\": " << h.frame_counter
       << ", \"status\": " << int(h.status) << ", \"time_ms\": " << h.time_ms
       << ", \"detections\": [";
  for (std::size_t i = 0; i < dets.size(); ++i) {
    const auto& d = dets[i];
    json << (i ? ", " : "") << "{\"range_m\": " << d.range_m
         << ", \"azimuth_deg\": " << d.azimuth_deg << ", \"elevation_deg\": " << d.elevation_deg
         << ", \"radial_velocity_mps\": " << d.radial_velocity_mps << ", \"snr_db\": " << d.snr_db
         << ", \"rcs_dbsm\": " << d.rcs_dbsm;
    if (fd) {
      json << ", \"range_std_m\": " << d.range_std_m
           << ", \"radial_velocity_std_mps\": " << d.radial_velocity_std_mps
           << ", \"azimuth_std_deg\": " << d.azimuth_std_deg
           << ", \"elevation_std_deg\": " << d.elevation_std_deg
           << ", \"range_ambiguous\": " << (d.range_ambiguous ? "true" : "false")
           << ", \"velocity_ambiguous\": " << (d.velocity_ambiguous ? "true" : "false");
    }
    json << "}";
  }
  json << "]}";
}
}  // namespace

int main(int argc, char** argv) {
  if (argc != 2) {
    std::fprintf(stderr, "usage: icd_vectors OUT_DIR\n");
    return 2;
  }
  const std::filesystem::path dir = argv[1];
  std::filesystem::create_directories(dir);
  const std::uint32_t seed = 20261122;
  std::printf("icd_vectors: seed %u\n", seed);
  std::mt19937 rng(seed);
  auto u = [&](double lo, double hi) {
    return std::uniform_real_distribution<double>(lo, hi)(rng);
  };

  io::CandumpRecorder log("can0", 100000);
  std::ofstream json(dir / "vectors.json");
  json.precision(17);
  json << "{\"lists\": [\n";
  std::vector<io::CanFrame> frames(icd::frames_for(icd::kMaxDetectionsPerFrame));
  for (int list = 0; list < 200; ++list) {
    std::vector<icd::Detection> dets(rng() % 12);
    for (auto& d : dets) {
      d.range_m = u(0, 167000);
      d.azimuth_deg = u(-90, 90);
      d.elevation_deg = u(-90, 90);
      d.radial_velocity_mps = u(-650, 650);
      d.snr_db = u(0, 127);
      d.rcs_dbsm = u(-300, 300);
    }
    icd::Header h;
    h.frame_counter = static_cast<std::uint16_t>(list * 331);
    h.status = static_cast<std::uint8_t>(rng() % 32);
    h.time_ms = static_cast<std::uint32_t>(list * 50);
    const icd::EncodeResult r = icd::encode(h, dets, frames);
    for (std::size_t i = 0; i < r.frames; ++i) {
      frames[i].timestamp_ns = 1'767'225'600'000'000'000 + list * 50'000'000LL;
      (void)log.record(frames[i]);
    }
    write_list_json(json, list == 0, h, dets, false);
  }
  json << "],\n";
  log.write_file(dir / "detections.log");

  // CAN FD: a few hundred lists of 0..40 detections (one of 255: every FirstIndex), with
  // accuracies up to beyond their fields (saturated) and random ambiguity flags.
  io::CandumpRecorder fd_log("can0", 100000);
  std::vector<io::CanFrame> fd_frames(icd::frames_for_fd(icd::kMaxDetectionsPerFrame));
  json << "\"fd_lists\": [\n";
  for (int list = 0; list < 300; ++list) {
    std::vector<icd::Detection> dets(list == 7 ? icd::kMaxDetectionsPerFrame : rng() % 41);
    for (auto& d : dets) {
      d.range_m = u(0, 167000);
      d.azimuth_deg = u(-90, 90);
      d.elevation_deg = u(-90, 90);
      d.radial_velocity_mps = u(-650, 650);
      d.snr_db = u(0, 127);
      d.rcs_dbsm = u(-300, 300);
      d.range_std_m = u(0, 700);
      d.radial_velocity_std_mps = u(0, 45);
      d.azimuth_std_deg = u(0, 35);
      d.elevation_std_deg = rng() % 8 == 0 ? 0.0 : u(0, 35);
      d.range_ambiguous = rng() % 2 == 0;
      d.velocity_ambiguous = rng() % 3 == 0;
    }
    icd::Header h;
    h.frame_counter = static_cast<std::uint16_t>(list * 4099 + 17);
    h.status = static_cast<std::uint8_t>(rng() % 32);
    h.time_ms = static_cast<std::uint32_t>(list * 50 + 3);
    const icd::EncodeResult r = icd::encode_fd(h, dets, fd_frames);
    if (r.encoded != dets.size()) {
      std::fprintf(stderr, "icd_vectors: FD list %d encoded %zu of %zu\n", list, r.encoded,
                   dets.size());
      return 1;
    }
    for (std::size_t i = 0; i < r.frames; ++i) {
      fd_frames[i].timestamp_ns = 1'767'225'600'000'000'000 + list * 50'000'000LL;
      (void)fd_log.record(fd_frames[i]);
    }
    write_list_json(json, list == 0, h, dets, true);
  }
  json << "],\n";
  if (fd_log.overflowed() != 0) {
    std::fprintf(stderr, "icd_vectors: FD log overflowed\n");
    return 1;
  }
  fd_log.write_file(dir / "detections_fd.log");

  // CANaerospace: FLOAT pitch and a DOUBLEH/DOUBLEL latitude.
  io::CandumpRecorder canas_log("can0", 16);
  (void)canas_log.record(io::canas::encode_float(io::canas::id::kPitchAngle, 1, 7, 2.5f));
  const auto [h, l] = io::canas::encode_double(io::canas::id::kGpsLatitude, 1, 4, 48.1234567);
  (void)canas_log.record(h);
  (void)canas_log.record(l);
  canas_log.write_file(dir / "canaerospace.log");
  json << "\"canaerospace\": {\"pitch_deg\": 2.5, \"latitude_deg\": 48.1234567}}\n";
  return json ? 0 : 1;
}
