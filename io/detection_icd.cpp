#include "io/detection_icd.hpp"

#include <cmath>

namespace radar_emu::io::icd {

namespace {

constexpr std::uint8_t kDlc = 8;

void put_le(CanFrame& f, std::size_t at, std::uint32_t v, std::size_t bytes) noexcept {
  for (std::size_t i = 0; i < bytes; ++i)
    f.data[at + i] = static_cast<std::uint8_t>(v >> (8 * i));
}

std::uint32_t get_le(const CanFrame& f, std::size_t at, std::size_t bytes) noexcept {
  std::uint32_t v = 0;
  for (std::size_t i = 0; i < bytes; ++i)
    v |= static_cast<std::uint32_t>(f.data[at + i]) << (8 * i);
  return v;
}

std::int32_t sign_extend16(std::uint32_t v) noexcept {
  return static_cast<std::int32_t>(static_cast<std::int16_t>(static_cast<std::uint16_t>(v)));
}

// Raw value of `physical / scale` rounded to nearest, if it fits [lo, hi].
bool quantise(double physical, double scale, std::int64_t lo, std::int64_t hi,
              std::int64_t& raw) noexcept {
  if (!std::isfinite(physical))
    return false;
  const double r = std::round(physical / scale);
  if (r < static_cast<double>(lo) || r > static_cast<double>(hi))
    return false;
  raw = static_cast<std::int64_t>(r);
  return true;
}

struct RawDetection {
  std::int64_t range, velocity, snr, azimuth, elevation, rcs;
};

bool to_raw(const Detection& d, RawDetection& raw) noexcept {
  if (!(std::abs(d.azimuth_deg) <= kMaxAbsAngle_deg) ||
      !(std::abs(d.elevation_deg) <= kMaxAbsAngle_deg) ||
      !(std::abs(d.radial_velocity_mps) <= kMaxAbsRadialVelocity_mps) || std::isnan(d.snr_db)) {
    return false;
  }
  // SNR saturates at the field's ends rather than dropping the detection: a very strong or
  // very weak measured SNR is still a valid detection (documented in docs/icd/detections.md).
  const double snr = std::fmin(std::fmax(d.snr_db, 0.0), 255.0 * kSnrScale_db);
  return quantise(d.range_m, kRangeScale_m, 0, 0xFFFFFF, raw.range) &&
         quantise(d.radial_velocity_mps, kRadialVelocityScale_mps, -32768, 32767, raw.velocity) &&
         quantise(snr, kSnrScale_db, 0, 255, raw.snr) &&
         quantise(d.azimuth_deg, kAngleScale_deg, -32768, 32767, raw.azimuth) &&
         quantise(d.elevation_deg, kAngleScale_deg, -32768, 32767, raw.elevation) &&
         quantise(d.rcs_dbsm, kRcsScale_dbsm, -32768, 32767, raw.rcs);
}

CanFrame frame(std::uint32_t id) noexcept {
  CanFrame f;
  f.id = id;
  f.len = kDlc;
  return f;
}

}  // namespace

EncodeResult encode(Header header, std::span<const Detection> detections,
                    std::span<CanFrame> out) noexcept {
  EncodeResult result;
  if (out.empty()) {
    result.truncated = detections.size();
    return result;
  }
  const std::size_t room = (out.size() - 1) / 2;
  const std::size_t limit = room < kMaxDetectionsPerFrame ? room : kMaxDetectionsPerFrame;
  std::size_t n = 0;
  for (const Detection& d : detections) {
    RawDetection raw{};
    if (!to_raw(d, raw)) {
      ++result.dropped;
      continue;
    }
    if (n == limit) {
      ++result.truncated;
      continue;
    }
    const auto index = static_cast<std::uint32_t>(n);
    const std::uint32_t counter_low = header.frame_counter & 0xFFu;
    CanFrame a = frame(kDetectionAId);
    put_le(a, 0, index, 1);
    put_le(a, 1, counter_low, 1);
    put_le(a, 2, static_cast<std::uint32_t>(raw.range), 3);
    put_le(a, 5, static_cast<std::uint32_t>(raw.velocity) & 0xFFFFu, 2);
    put_le(a, 7, static_cast<std::uint32_t>(raw.snr), 1);
    CanFrame b = frame(kDetectionBId);
    put_le(b, 0, index, 1);
    put_le(b, 1, counter_low, 1);
    put_le(b, 2, static_cast<std::uint32_t>(raw.azimuth) & 0xFFFFu, 2);
    put_le(b, 4, static_cast<std::uint32_t>(raw.elevation) & 0xFFFFu, 2);
    put_le(b, 6, static_cast<std::uint32_t>(raw.rcs) & 0xFFFFu, 2);
    out[1 + 2 * n] = a;
    out[2 + 2 * n] = b;
    ++n;
  }
  if (result.dropped > 0)
    header.status |= status::kDropped;
  if (result.truncated > 0)
    header.status |= status::kTruncated;
  header.detection_count = static_cast<std::uint8_t>(n);
  CanFrame h = frame(kHeaderId);
  put_le(h, 0, header.frame_counter, 2);
  put_le(h, 2, header.detection_count, 1);
  put_le(h, 3, header.status, 1);
  put_le(h, 4, header.time_ms, 4);
  out[0] = h;
  result.frames = 1 + 2 * n;
  result.encoded = n;
  return result;
}

FeedStatus ListDecoder::feed(const CanFrame& f) noexcept {
  if (f.extended || (f.id != kHeaderId && f.id != kDetectionAId && f.id != kDetectionBId)) {
    return FeedStatus::kIgnored;
  }
  if (f.len != kDlc || f.fd) {
    ++malformed_;
    return FeedStatus::kMalformed;
  }
  if (f.id == kHeaderId) {
    if (in_list_)
      ++incomplete_;
    list_ = DetectionList{};
    list_.header.frame_counter = static_cast<std::uint16_t>(get_le(f, 0, 2));
    list_.header.detection_count = static_cast<std::uint8_t>(get_le(f, 2, 1));
    list_.header.status = static_cast<std::uint8_t>(get_le(f, 3, 1));
    list_.header.time_ms = get_le(f, 4, 4);
    list_.count = list_.header.detection_count;
    have_.fill(0);
    parts_seen_ = 0;
    in_list_ = list_.count > 0;
    return in_list_ ? FeedStatus::kConsumed : FeedStatus::kComplete;
  }
  if (!in_list_) {
    ++orphans_;
    return FeedStatus::kOrphan;
  }
  const std::size_t index = get_le(f, 0, 1);
  const std::uint32_t counter_low = get_le(f, 1, 1);
  const bool is_a = f.id == kDetectionAId;
  const std::uint8_t bit = is_a ? 1 : 2;
  if (index >= list_.count || counter_low != (list_.header.frame_counter & 0xFFu) ||
      (have_[index] & bit) != 0) {
    ++malformed_;
    return FeedStatus::kMalformed;
  }
  Detection& d = list_.detections[index];
  if (is_a) {
    d.range_m = static_cast<double>(get_le(f, 2, 3)) * kRangeScale_m;
    d.radial_velocity_mps =
        static_cast<double>(sign_extend16(get_le(f, 5, 2))) * kRadialVelocityScale_mps;
    d.snr_db = static_cast<double>(get_le(f, 7, 1)) * kSnrScale_db;
  } else {
    d.azimuth_deg = static_cast<double>(sign_extend16(get_le(f, 2, 2))) * kAngleScale_deg;
    d.elevation_deg = static_cast<double>(sign_extend16(get_le(f, 4, 2))) * kAngleScale_deg;
    d.rcs_dbsm = static_cast<double>(sign_extend16(get_le(f, 6, 2))) * kRcsScale_dbsm;
  }
  have_[index] |= bit;
  ++parts_seen_;
  if (parts_seen_ == 2 * list_.count) {
    in_list_ = false;
    return FeedStatus::kComplete;
  }
  return FeedStatus::kConsumed;
}

}  // namespace radar_emu::io::icd
