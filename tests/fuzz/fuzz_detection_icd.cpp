// Harnesses: the detection ICD (io/detection_icd.hpp), classic CAN and CAN FD.
//
// Input byte 0, bit 0 picks the mode:
//  - frames (bit 0 clear): arbitrary frame sequences into ListDecoder. Each frame: a control
//    byte (low 2 bits pick the ICD identifiers of the harness's kind or a raw one; bit 2 flips
//    the FD flag; bit 3 takes the length from the next byte instead of the kind's own), then
//    the payload. Oracle: every completed list holds detection_count detections, each finite
//    and inside the ICD's ranges (docs/icd/detections.md).
//  - round trip (bit 0 set): a header and up to 255 detections built from the input on grids
//    that keep every value a quarter step from a rounding boundary, encoded (encode or
//    encode_fd, with an output span cut short by the input), the frames fed back (optionally
//    in reverse after the header). Oracles, from the ICD's documented rules and not from the
//    encoder: which detections are dropped (NaN, angle beyond +-90 deg, |velocity| > 655.34
//    m/s, range or RCS outside its field; FD: a negative or NaN accuracy), which truncated,
//    and that each decoded value is within half a step of the one sent (SNR saturated to
//    0..127.5 dB, accuracies to their field).

#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

#include "io/detection_icd.hpp"
#include "tests/fuzz/fuzz_input.hpp"
#include "tests/fuzz/harnesses.hpp"

namespace radar_emu::fuzz {

namespace {

namespace icd = io::icd;

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

void check_list(const icd::DetectionList& list, bool fd) {
  FUZZ_CHECK(list.count == list.header.detection_count);
  FUZZ_CHECK(list.count <= icd::kMaxDetectionsPerFrame);
  FUZZ_CHECK(list.fd == fd);
  for (std::size_t i = 0; i < list.count; ++i) {
    const icd::Detection& d = list.detections[i];
    FUZZ_CHECK(d.range_m >= 0.0 && d.range_m <= icd::kMaxRange_m + 1e-9);
    FUZZ_CHECK(std::abs(d.azimuth_deg) <= icd::kMaxAbsAngle_deg);
    FUZZ_CHECK(std::abs(d.elevation_deg) <= icd::kMaxAbsAngle_deg);
    FUZZ_CHECK(std::abs(d.radial_velocity_mps) <= 32768 * icd::kRadialVelocityScale_mps);
    FUZZ_CHECK(d.snr_db >= 0.0 && d.snr_db <= 255 * icd::kSnrScale_db);
    FUZZ_CHECK(std::abs(d.rcs_dbsm) <= 32768 * icd::kRcsScale_dbsm);
    FUZZ_CHECK(d.range_std_m >= 0.0 && d.azimuth_std_deg >= 0.0 && d.elevation_std_deg >= 0.0 &&
               d.radial_velocity_std_mps >= 0.0);
    if (!fd) {
      FUZZ_CHECK(d.range_std_m == 0.0 && d.azimuth_std_deg == 0.0 && d.elevation_std_deg == 0.0 &&
                 d.radial_velocity_std_mps == 0.0);
      FUZZ_CHECK(!d.range_ambiguous && !d.velocity_ambiguous);
    }
  }
}

int feed_frames(FuzzInput& in, bool fd) {
  icd::ListDecoder decoder;
  std::uint64_t malformed = 0, orphans = 0;
  const std::uint32_t ids[3] = {fd ? icd::kFdHeaderId : icd::kHeaderId,
                                fd ? icd::kFdContinuationId : icd::kDetectionAId,
                                fd ? icd::kFdContinuationId : icd::kDetectionBId};
  while (!in.empty()) {
    io::CanFrame f;
    const std::uint8_t ctl = in.u8();
    f.id = (ctl & 3) < 3 ? ids[ctl & 3] : (in.u16() & 0x7FFu);
    f.fd = fd != ((ctl & 4) != 0);
    if ((ctl & 8) != 0) {
      f.len = static_cast<std::uint8_t>(in.u8() % (f.fd ? io::kCanFdMaxBytes + 1 : 9));
    } else if (fd) {
      f.len = f.id == icd::kFdHeaderId ? icd::kFdHeaderBytes : icd::kFdContinuationBytes;
    } else {
      f.len = 8;
    }
    in.bytes(std::span(f.data.data(), f.len));
    const icd::FeedStatus st = decoder.feed(f);
    if (st == icd::FeedStatus::kMalformed)
      ++malformed;
    if (st == icd::FeedStatus::kOrphan)
      ++orphans;
    if (st == icd::FeedStatus::kComplete)
      check_list(decoder.list(), decoder.list().fd);
    FUZZ_CHECK(decoder.malformed() == malformed);
    FUZZ_CHECK(decoder.orphans() == orphans);
  }
  return 0;
}

// A value on the grid k * step + {0, +1/4, -1/4} * step (never near a rounding boundary), or
// NaN / +-infinity when the selector says so.
double grid(FuzzInput& in, double step, std::int32_t k_lo, std::int32_t k_hi) {
  const std::uint8_t sel = in.u8();
  const std::uint32_t raw = in.u32();
  switch (sel % 16) {
    case 13:
      return kNaN;
    case 14:
      return std::numeric_limits<double>::infinity();
    case 15:
      return -std::numeric_limits<double>::infinity();
    default:
      break;
  }
  const auto span = static_cast<std::uint32_t>(k_hi - k_lo + 1);
  const std::int32_t k = k_lo + static_cast<std::int32_t>(raw % span);
  const double frac = (sel % 3 == 0) ? 0.0 : (sel % 3 == 1 ? 0.25 : -0.25);
  return (static_cast<double>(k) + frac) * step;
}

// The ICD's documented acceptance rules (docs/icd/detections.md), restated here.
bool icd_accepts(const icd::Detection& d, bool fd) {
  const auto fits = [](double v, double step, double lo, double hi) {
    return std::isfinite(v) && std::round(v / step) >= lo && std::round(v / step) <= hi;
  };
  bool ok = std::abs(d.azimuth_deg) <= 90.0 && std::abs(d.elevation_deg) <= 90.0 &&
            std::abs(d.radial_velocity_mps) <= 655.34 && !std::isnan(d.snr_db) &&
            fits(d.range_m, 0.01, 0, 16777215) && fits(d.rcs_dbsm, 0.01, -32768, 32767);
  if (fd) {
    ok = ok && d.range_std_m >= 0.0 && d.azimuth_std_deg >= 0.0 && d.elevation_std_deg >= 0.0 &&
         d.radial_velocity_std_mps >= 0.0;
  }
  return ok;
}

void check_close(double got, double sent, double step) {
  FUZZ_CHECK(std::abs(got - sent) <= 0.5 * step + 1e-9 * std::max(1.0, std::abs(sent)));
}

// An accuracy as sent: saturated at the field's top.
void check_std(double got, double sent, double step, std::uint32_t max_raw) {
  const double top = max_raw * step;
  if (sent >= top) {
    FUZZ_CHECK(std::abs(got - top) <= 1e-9);
  } else {
    check_close(got, sent, step);
  }
}

int round_trip(FuzzInput& in, bool fd) {
  icd::Header header;
  header.frame_counter = in.u16();
  header.status = static_cast<std::uint8_t>(in.u8() & 0x03);  // dropped/truncated set by encode
  header.time_ms = in.u32();
  const std::size_t n = in.u8();
  std::vector<icd::Detection> sent(n);
  for (icd::Detection& d : sent) {
    d.range_m = grid(in, 0.01, -200, 16777215 + 200);
    d.radial_velocity_mps = grid(in, 0.02, -33000, 33000);
    d.snr_db = grid(in, 0.5, -300, 300);
    d.azimuth_deg = grid(in, 0.01, -9100, 9100);
    d.elevation_deg = grid(in, 0.01, -9100, 9100);
    d.rcs_dbsm = grid(in, 0.01, -33000, 33000);
    d.range_std_m = grid(in, 0.01, -10, 0xFFFF + 100);
    d.radial_velocity_std_mps = grid(in, 0.01, -10, 0xFFF + 100);
    d.azimuth_std_deg = grid(in, 0.002, -10, 0x3FFF + 100);
    d.elevation_std_deg = grid(in, 0.002, -10, 0x3FFF + 100);
    const std::uint8_t flags = in.u8();
    d.range_ambiguous = (flags & 1) != 0;
    d.velocity_ambiguous = (flags & 2) != 0;
  }
  const std::size_t full = fd ? icd::frames_for_fd(n) : icd::frames_for(n);
  const std::uint8_t cut = in.u8();
  const std::size_t capacity = cut < 200 ? full : std::min<std::size_t>(full, cut - 200);
  std::vector<io::CanFrame> frames(std::max<std::size_t>(capacity, 1));
  const std::span<io::CanFrame> out(frames.data(), capacity);
  const icd::EncodeResult enc =
      fd ? icd::encode_fd(header, sent, out) : icd::encode(header, sent, out);

  // Expected outcome, from the documented rules.
  std::vector<const icd::Detection*> accepted;
  std::size_t dropped = 0;
  for (const icd::Detection& d : sent) {
    if (icd_accepts(d, fd))
      accepted.push_back(&d);
    else
      ++dropped;
  }
  if (capacity == 0) {
    FUZZ_CHECK(enc.frames == 0 && enc.encoded == 0 && enc.truncated == n);
    return 0;
  }
  const std::size_t room = fd ? icd::kFdHeaderSlots + 3 * (capacity - 1) : (capacity - 1) / 2;
  const std::size_t limit = std::min(room, icd::kMaxDetectionsPerFrame);
  const std::size_t expect_encoded = std::min(accepted.size(), limit);
  FUZZ_CHECK(enc.dropped == dropped);
  FUZZ_CHECK(enc.encoded == expect_encoded);
  FUZZ_CHECK(enc.truncated == accepted.size() - expect_encoded);
  FUZZ_CHECK(enc.frames == (fd ? icd::frames_for_fd(enc.encoded) : icd::frames_for(enc.encoded)));
  FUZZ_CHECK(enc.frames <= capacity);

  // Decode (optionally with the detection frames reversed: order is not part of the ICD).
  if ((in.u8() & 1) != 0)
    std::reverse(frames.begin() + 1, frames.begin() + static_cast<std::ptrdiff_t>(enc.frames));
  icd::ListDecoder decoder;
  for (std::size_t i = 0; i < enc.frames; ++i) {
    const icd::FeedStatus st = decoder.feed(frames[i]);
    FUZZ_CHECK(st ==
               (i + 1 == enc.frames ? icd::FeedStatus::kComplete : icd::FeedStatus::kConsumed));
  }
  FUZZ_CHECK(decoder.malformed() == 0 && decoder.orphans() == 0);
  const icd::DetectionList& list = decoder.list();
  check_list(list, fd);
  FUZZ_CHECK(list.count == enc.encoded);
  FUZZ_CHECK(list.header.frame_counter == header.frame_counter);
  FUZZ_CHECK(list.header.time_ms == header.time_ms);
  std::uint8_t status = header.status;
  if (enc.dropped > 0)
    status |= icd::status::kDropped;
  if (enc.truncated > 0)
    status |= icd::status::kTruncated;
  FUZZ_CHECK(list.header.status == status);
  for (std::size_t i = 0; i < list.count; ++i) {
    const icd::Detection& s = *accepted[i];
    const icd::Detection& g = list.detections[i];
    check_close(g.range_m, s.range_m, 0.01);
    check_close(g.radial_velocity_mps, s.radial_velocity_mps, 0.02);
    check_close(g.snr_db, std::clamp(s.snr_db, 0.0, 127.5), 0.5);
    check_close(g.azimuth_deg, s.azimuth_deg, 0.01);
    check_close(g.elevation_deg, s.elevation_deg, 0.01);
    check_close(g.rcs_dbsm, s.rcs_dbsm, 0.01);
    if (fd) {
      check_std(g.range_std_m, s.range_std_m, 0.01, 0xFFFF);
      check_std(g.radial_velocity_std_mps, s.radial_velocity_std_mps, 0.01, 0xFFF);
      check_std(g.azimuth_std_deg, s.azimuth_std_deg, 0.002, 0x3FFF);
      check_std(g.elevation_std_deg, s.elevation_std_deg, 0.002, 0x3FFF);
      FUZZ_CHECK(g.range_ambiguous == s.range_ambiguous);
      FUZZ_CHECK(g.velocity_ambiguous == s.velocity_ambiguous);
    }
  }
  return 0;
}

int run(const std::uint8_t* data, std::size_t size, bool fd) {
  FuzzInput in(data, size);
  return (in.u8() & 1) != 0 ? round_trip(in, fd) : feed_frames(in, fd);
}

}  // namespace

int icd_classic(const std::uint8_t* data, std::size_t size) {
  return run(data, size, false);
}

int icd_fd(const std::uint8_t* data, std::size_t size) {
  return run(data, size, true);
}

}  // namespace radar_emu::fuzz
