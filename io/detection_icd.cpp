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

// Bit-level little-endian (Intel, DBC "@1") access: bit k of a message is bit k % 8 of byte
// k / 8, and a signal's least significant bit sits at its start bit.
void put_bits(CanFrame& f, std::size_t bit, std::size_t width, std::uint32_t v) noexcept {
  for (std::size_t i = 0; i < width; ++i, ++bit) {
    const auto mask = static_cast<std::uint8_t>(1u << (bit % 8));
    if (((v >> i) & 1u) != 0)
      f.data[bit / 8] = static_cast<std::uint8_t>(f.data[bit / 8] | mask);
    else
      f.data[bit / 8] = static_cast<std::uint8_t>(f.data[bit / 8] & ~mask);
  }
}

std::uint32_t get_bits(const CanFrame& f, std::size_t bit, std::size_t width) noexcept {
  std::uint32_t v = 0;
  for (std::size_t i = 0; i < width; ++i, ++bit)
    v |= ((static_cast<std::uint32_t>(f.data[bit / 8]) >> (bit % 8)) & 1u) << i;
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

// Raw value of a one-sigma accuracy: NaN or negative is invalid; above the field it saturates.
bool quantise_std(double physical, double scale, std::uint32_t max_raw,
                  std::uint32_t& raw) noexcept {
  if (!(physical >= 0.0))
    return false;
  const double r = std::round(physical / scale);
  raw = r >= static_cast<double>(max_raw) ? max_raw : static_cast<std::uint32_t>(r);
  return true;
}

struct RawDetection {
  std::int64_t range, velocity, snr, azimuth, elevation, rcs;
};

struct RawAccuracy {
  std::uint32_t range, velocity, azimuth, elevation;
};

bool to_raw_accuracy(const Detection& d, RawAccuracy& raw) noexcept {
  return quantise_std(d.range_std_m, kRangeStdScale_m, kRangeStdMaxRaw, raw.range) &&
         quantise_std(d.radial_velocity_std_mps, kRadialVelocityStdScale_mps,
                      kRadialVelocityStdMaxRaw, raw.velocity) &&
         quantise_std(d.azimuth_std_deg, kAngleStdScale_deg, kAngleStdMaxRaw, raw.azimuth) &&
         quantise_std(d.elevation_std_deg, kAngleStdScale_deg, kAngleStdMaxRaw, raw.elevation);
}

// CAN FD slot layout: start bit and width of each signal, relative to the slot's first bit
// (docs/icd/detections.md, "CAN FD detection slot").
namespace slot {
constexpr std::size_t kRange = 0, kRangeWidth = 24;
constexpr std::size_t kVelocity = 24, kVelocityWidth = 16;
constexpr std::size_t kSnr = 40, kSnrWidth = 8;
constexpr std::size_t kAzimuth = 48, kAzimuthWidth = 16;
constexpr std::size_t kElevation = 64, kElevationWidth = 16;
constexpr std::size_t kRcs = 80, kRcsWidth = 16;
constexpr std::size_t kRangeStd = 96, kRangeStdWidth = 16;
constexpr std::size_t kVelocityStd = 112, kVelocityStdWidth = 12;
constexpr std::size_t kAzimuthStd = 124, kAzimuthStdWidth = 14;
constexpr std::size_t kElevationStd = 138, kElevationStdWidth = 14;
constexpr std::size_t kRangeAmbiguous = 152;
constexpr std::size_t kVelocityAmbiguous = 153;
static_assert(kVelocityAmbiguous < 8 * kFdSlotBytes);
}  // namespace slot

static_assert(kFdHeaderSlotOffset + kFdHeaderSlots * kFdSlotBytes == kFdHeaderBytes);
static_assert(kFdContinuationSlotOffset + kFdContinuationSlots * kFdSlotBytes ==
              kFdContinuationBytes);
static_assert(kFdContinuationBytes <= kCanFdMaxBytes);
static_assert(kFdHeaderSlots + kFdContinuationSlots * (frames_for_fd(kMaxDetectionsPerFrame) - 2) <
                  256,
              "a continuation's FirstIndex must fit a byte");

void put_slot(CanFrame& f, std::size_t byte, const RawDetection& r, const RawAccuracy& a,
              const Detection& d) noexcept {
  const std::size_t b = 8 * byte;
  put_bits(f, b + slot::kRange, slot::kRangeWidth, static_cast<std::uint32_t>(r.range));
  put_bits(f, b + slot::kVelocity, slot::kVelocityWidth,
           static_cast<std::uint32_t>(r.velocity) & 0xFFFFu);
  put_bits(f, b + slot::kSnr, slot::kSnrWidth, static_cast<std::uint32_t>(r.snr));
  put_bits(f, b + slot::kAzimuth, slot::kAzimuthWidth,
           static_cast<std::uint32_t>(r.azimuth) & 0xFFFFu);
  put_bits(f, b + slot::kElevation, slot::kElevationWidth,
           static_cast<std::uint32_t>(r.elevation) & 0xFFFFu);
  put_bits(f, b + slot::kRcs, slot::kRcsWidth, static_cast<std::uint32_t>(r.rcs) & 0xFFFFu);
  put_bits(f, b + slot::kRangeStd, slot::kRangeStdWidth, a.range);
  put_bits(f, b + slot::kVelocityStd, slot::kVelocityStdWidth, a.velocity);
  put_bits(f, b + slot::kAzimuthStd, slot::kAzimuthStdWidth, a.azimuth);
  put_bits(f, b + slot::kElevationStd, slot::kElevationStdWidth, a.elevation);
  put_bits(f, b + slot::kRangeAmbiguous, 1, d.range_ambiguous ? 1u : 0u);
  put_bits(f, b + slot::kVelocityAmbiguous, 1, d.velocity_ambiguous ? 1u : 0u);
}

Detection get_slot(const CanFrame& f, std::size_t byte) noexcept {
  const std::size_t b = 8 * byte;
  Detection d;
  d.range_m = static_cast<double>(get_bits(f, b + slot::kRange, slot::kRangeWidth)) * kRangeScale_m;
  d.radial_velocity_mps =
      static_cast<double>(sign_extend16(get_bits(f, b + slot::kVelocity, slot::kVelocityWidth))) *
      kRadialVelocityScale_mps;
  d.snr_db = static_cast<double>(get_bits(f, b + slot::kSnr, slot::kSnrWidth)) * kSnrScale_db;
  d.azimuth_deg =
      static_cast<double>(sign_extend16(get_bits(f, b + slot::kAzimuth, slot::kAzimuthWidth))) *
      kAngleScale_deg;
  d.elevation_deg =
      static_cast<double>(sign_extend16(get_bits(f, b + slot::kElevation, slot::kElevationWidth))) *
      kAngleScale_deg;
  d.rcs_dbsm = static_cast<double>(sign_extend16(get_bits(f, b + slot::kRcs, slot::kRcsWidth))) *
               kRcsScale_dbsm;
  d.range_std_m = static_cast<double>(get_bits(f, b + slot::kRangeStd, slot::kRangeStdWidth)) *
                  kRangeStdScale_m;
  d.radial_velocity_std_mps =
      static_cast<double>(get_bits(f, b + slot::kVelocityStd, slot::kVelocityStdWidth)) *
      kRadialVelocityStdScale_mps;
  d.azimuth_std_deg =
      static_cast<double>(get_bits(f, b + slot::kAzimuthStd, slot::kAzimuthStdWidth)) *
      kAngleStdScale_deg;
  d.elevation_std_deg =
      static_cast<double>(get_bits(f, b + slot::kElevationStd, slot::kElevationStdWidth)) *
      kAngleStdScale_deg;
  d.range_ambiguous = get_bits(f, b + slot::kRangeAmbiguous, 1) != 0;
  d.velocity_ambiguous = get_bits(f, b + slot::kVelocityAmbiguous, 1) != 0;
  return d;
}

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

// CAN FD flags as in candump's "##F" nibble (can_frame.hpp): bit-rate switch.
constexpr std::uint8_t kFdFlagBrs = 1;

CanFrame fd_frame(std::uint32_t id, std::uint8_t len) noexcept {
  CanFrame f;
  f.id = id;
  f.len = len;
  f.fd = true;
  f.fd_flags = kFdFlagBrs;
  return f;
}

// Byte of FD slot `k` of the list: frame index and byte offset inside that frame.
struct SlotPlace {
  std::size_t frame, byte;
};
constexpr SlotPlace slot_place(std::size_t k) noexcept {
  if (k < kFdHeaderSlots)
    return {0, kFdHeaderSlotOffset + k * kFdSlotBytes};
  const std::size_t c = k - kFdHeaderSlots;
  return {1 + c / kFdContinuationSlots,
          kFdContinuationSlotOffset + (c % kFdContinuationSlots) * kFdSlotBytes};
}

void put_header(CanFrame& h, const Header& header) noexcept {
  put_le(h, 0, header.frame_counter, 2);
  put_le(h, 2, header.detection_count, 1);
  put_le(h, 3, header.status, 1);
  put_le(h, 4, header.time_ms, 4);
}

Header get_header(const CanFrame& f) noexcept {
  Header h;
  h.frame_counter = static_cast<std::uint16_t>(get_le(f, 0, 2));
  h.detection_count = static_cast<std::uint8_t>(get_le(f, 2, 1));
  h.status = static_cast<std::uint8_t>(get_le(f, 3, 1));
  h.time_ms = get_le(f, 4, 4);
  return h;
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
  put_header(h, header);
  out[0] = h;
  result.frames = 1 + 2 * n;
  result.encoded = n;
  return result;
}

EncodeResult encode_fd(Header header, std::span<const Detection> detections,
                       std::span<CanFrame> out) noexcept {
  EncodeResult result;
  if (out.empty()) {
    result.truncated = detections.size();
    return result;
  }
  const std::size_t room = kFdHeaderSlots + kFdContinuationSlots * (out.size() - 1);
  const std::size_t limit = room < kMaxDetectionsPerFrame ? room : kMaxDetectionsPerFrame;
  out[0] = fd_frame(kFdHeaderId, kFdHeaderBytes);
  std::size_t n = 0;
  for (const Detection& d : detections) {
    RawDetection raw{};
    RawAccuracy acc{};
    if (!to_raw(d, raw) || !to_raw_accuracy(d, acc)) {
      ++result.dropped;
      continue;
    }
    if (n == limit) {
      ++result.truncated;
      continue;
    }
    const SlotPlace p = slot_place(n);
    CanFrame& f = out[p.frame];
    if (p.frame > 0 && p.byte == kFdContinuationSlotOffset) {
      // First slot of a continuation frame: FrameCounter, FirstIndex, SlotCount (so far 0).
      f = fd_frame(kFdContinuationId, kFdContinuationBytes);
      put_le(f, 0, header.frame_counter, 2);
      put_le(f, 2, static_cast<std::uint32_t>(n), 1);
    }
    if (p.frame > 0)
      f.data[3] = static_cast<std::uint8_t>(f.data[3] + 1);
    put_slot(f, p.byte, raw, acc, d);
    ++n;
  }
  if (result.dropped > 0)
    header.status |= status::kDropped;
  if (result.truncated > 0)
    header.status |= status::kTruncated;
  header.detection_count = static_cast<std::uint8_t>(n);
  put_header(out[0], header);
  result.frames = frames_for_fd(n);
  result.encoded = n;
  return result;
}

FeedStatus ListDecoder::feed(const CanFrame& f) noexcept {
  if (f.extended)
    return FeedStatus::kIgnored;
  if (f.id == kHeaderId || f.id == kDetectionAId || f.id == kDetectionBId)
    return feed_classic(f);
  if (f.id == kFdHeaderId || f.id == kFdContinuationId)
    return feed_fd(f);
  return FeedStatus::kIgnored;
}

FeedStatus ListDecoder::feed_classic(const CanFrame& f) noexcept {
  if (f.len != kDlc || f.fd) {
    ++malformed_;
    return FeedStatus::kMalformed;
  }
  if (f.id == kHeaderId) {
    if (in_list_)
      ++incomplete_;
    list_ = DetectionList{};
    list_.header = get_header(f);
    list_.count = list_.header.detection_count;
    have_.fill(0);
    parts_seen_ = 0;
    parts_expected_ = 2 * list_.count;
    in_list_ = list_.count > 0;
    return in_list_ ? FeedStatus::kConsumed : FeedStatus::kComplete;
  }
  if (!in_list_ || list_.fd) {
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
    const double az = static_cast<double>(sign_extend16(get_le(f, 2, 2))) * kAngleScale_deg;
    const double el = static_cast<double>(sign_extend16(get_le(f, 4, 2))) * kAngleScale_deg;
    if (!(std::abs(az) <= kMaxAbsAngle_deg && std::abs(el) <= kMaxAbsAngle_deg)) {
      ++malformed_;
      return FeedStatus::kMalformed;
    }
    d.azimuth_deg = az;
    d.elevation_deg = el;
    d.rcs_dbsm = static_cast<double>(sign_extend16(get_le(f, 6, 2))) * kRcsScale_dbsm;
  }
  have_[index] |= bit;
  ++parts_seen_;
  if (parts_seen_ == parts_expected_) {
    in_list_ = false;
    return FeedStatus::kComplete;
  }
  return FeedStatus::kConsumed;
}

namespace {
// The ICD's valid angles (kMaxAbsAngle_deg): the encoder never sends beyond them, so a frame
// that carries one is malformed.
bool angles_valid(const Detection& d) noexcept {
  return std::abs(d.azimuth_deg) <= kMaxAbsAngle_deg &&
         std::abs(d.elevation_deg) <= kMaxAbsAngle_deg;
}
}  // namespace

FeedStatus ListDecoder::feed_fd(const CanFrame& f) noexcept {
  const bool is_header = f.id == kFdHeaderId;
  if (!f.fd || f.len != (is_header ? kFdHeaderBytes : kFdContinuationBytes)) {
    ++malformed_;
    return FeedStatus::kMalformed;
  }
  if (is_header) {
    if (in_list_)
      ++incomplete_;
    list_ = DetectionList{};
    list_.fd = true;
    list_.header = get_header(f);
    list_.count = list_.header.detection_count;
    const std::size_t in_header = list_.count < kFdHeaderSlots ? list_.count : kFdHeaderSlots;
    bool valid = true;
    for (std::size_t k = 0; k < in_header; ++k) {
      list_.detections[k] = get_slot(f, kFdHeaderSlotOffset + k * kFdSlotBytes);
      valid = valid && angles_valid(list_.detections[k]);
    }
    if (!valid) {
      ++malformed_;
      in_list_ = false;
      return FeedStatus::kMalformed;
    }
    have_.fill(0);
    parts_seen_ = 0;
    parts_expected_ = frames_for_fd(list_.count) - 1;
    in_list_ = parts_expected_ > 0;
    return in_list_ ? FeedStatus::kConsumed : FeedStatus::kComplete;
  }
  if (!in_list_ || !list_.fd) {
    ++orphans_;
    return FeedStatus::kOrphan;
  }
  const auto counter = static_cast<std::uint16_t>(get_le(f, 0, 2));
  const std::size_t first = get_le(f, 2, 1);
  const std::size_t slots = get_le(f, 3, 1);
  // FirstIndex must be 2 + 3 k below the count, SlotCount what remains up to three, and each
  // continuation may arrive once.
  const bool index_ok = first >= kFdHeaderSlots && first < list_.count &&
                        (first - kFdHeaderSlots) % kFdContinuationSlots == 0;
  const std::size_t remaining = index_ok ? list_.count - first : 0;
  const std::size_t k = index_ok ? (first - kFdHeaderSlots) / kFdContinuationSlots : 0;
  if (counter != list_.header.frame_counter || !index_ok ||
      slots != (remaining < kFdContinuationSlots ? remaining : kFdContinuationSlots) ||
      have_[k] != 0) {
    ++malformed_;
    return FeedStatus::kMalformed;
  }
  for (std::size_t s = 0; s < slots; ++s) {
    const Detection d = get_slot(f, kFdContinuationSlotOffset + s * kFdSlotBytes);
    if (!angles_valid(d)) {
      ++malformed_;
      return FeedStatus::kMalformed;
    }
  }
  for (std::size_t s = 0; s < slots; ++s)
    list_.detections[first + s] = get_slot(f, kFdContinuationSlotOffset + s * kFdSlotBytes);
  have_[k] = 1;
  ++parts_seen_;
  if (parts_seen_ == parts_expected_) {
    in_list_ = false;
    return FeedStatus::kComplete;
  }
  return FeedStatus::kConsumed;
}

}  // namespace radar_emu::io::icd
