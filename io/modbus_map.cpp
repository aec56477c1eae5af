#include "io/modbus_map.hpp"

#include <algorithm>
#include <bit>
#include <cmath>

#include "common/units.hpp"

namespace radar_emu::io::modbus {

namespace {

// Rounds half away from zero and range-checks against [lo, hi] (as doubles, exactly
// representable for 16- and 32-bit integers).
std::optional<double> scaled_raw(double physical, double scale, double lo, double hi) noexcept {
  if (!std::isfinite(physical) || !(scale > 0.0) || !std::isfinite(scale))
    return std::nullopt;
  const double raw = std::round(physical / scale);
  if (!(raw >= lo && raw <= hi))
    return std::nullopt;
  return raw;
}

// double -> float without undefined behaviour for finite values beyond the float range
// (C++20 [conv.double]): those become +-infinity, as IEEE-754 rounding would give.
float to_float(double v) noexcept {
  constexpr double kMax = static_cast<double>(std::numeric_limits<float>::max());
  if (v > kMax)
    return std::numeric_limits<float>::infinity();
  if (v < -kMax)
    return -std::numeric_limits<float>::infinity();
  return static_cast<float>(v);
}

bool fits(std::size_t size, std::size_t offset, std::size_t n) noexcept {
  return offset <= size && size - offset >= n;
}

}  // namespace

// ---- Value codecs ---------------------------------------------------------------------------

std::array<std::uint16_t, 2> encode_u32(std::uint32_t value, WordOrder order) noexcept {
  const auto high = static_cast<std::uint16_t>(value >> 16);
  const auto low = static_cast<std::uint16_t>(value & 0xFFFFu);
  if (order == WordOrder::kCDAB)
    return {low, high};
  return {high, low};
}

std::uint32_t decode_u32(std::array<std::uint16_t, 2> regs, WordOrder order) noexcept {
  const std::uint16_t high = order == WordOrder::kCDAB ? regs[1] : regs[0];
  const std::uint16_t low = order == WordOrder::kCDAB ? regs[0] : regs[1];
  return (static_cast<std::uint32_t>(high) << 16) | low;
}

std::array<std::uint16_t, 2> encode_i32(std::int32_t value, WordOrder order) noexcept {
  return encode_u32(std::bit_cast<std::uint32_t>(value), order);
}

std::int32_t decode_i32(std::array<std::uint16_t, 2> regs, WordOrder order) noexcept {
  return std::bit_cast<std::int32_t>(decode_u32(regs, order));
}

std::array<std::uint16_t, 2> encode_f32(float value, WordOrder order) noexcept {
  return encode_u32(std::bit_cast<std::uint32_t>(value), order);
}

float decode_f32(std::array<std::uint16_t, 2> regs, WordOrder order) noexcept {
  return std::bit_cast<float>(decode_u32(regs, order));
}

std::array<std::uint16_t, 4> encode_f64(double value, WordOrder order) noexcept {
  const auto bits = std::bit_cast<std::uint64_t>(value);
  std::array<std::uint16_t, 4> regs{};
  for (std::size_t i = 0; i < 4; ++i) {  // i = 0: most significant register
    const auto word = static_cast<std::uint16_t>((bits >> (48 - 16 * i)) & 0xFFFFu);
    regs[order == WordOrder::kCDAB ? 3 - i : i] = word;
  }
  return regs;
}

double decode_f64(std::array<std::uint16_t, 4> regs, WordOrder order) noexcept {
  std::uint64_t bits = 0;
  for (std::size_t i = 0; i < 4; ++i) {
    const std::uint16_t word = regs[order == WordOrder::kCDAB ? 3 - i : i];
    bits = (bits << 16) | word;
  }
  return std::bit_cast<double>(bits);
}

std::optional<std::int32_t> to_scaled_i32(double physical, double scale) noexcept {
  // The "no data" code INT32_MIN is excluded from the value range.
  const auto raw = scaled_raw(physical, scale, -2147483647.0, 2147483647.0);
  if (!raw)
    return std::nullopt;
  return static_cast<std::int32_t>(*raw);
}

std::optional<std::int16_t> to_scaled_i16(double physical, double scale) noexcept {
  const auto raw = scaled_raw(physical, scale, -32767.0, 32767.0);
  if (!raw)
    return std::nullopt;
  return static_cast<std::int16_t>(*raw);
}

std::optional<std::uint16_t> to_scaled_u16(double physical, double scale) noexcept {
  const auto raw = scaled_raw(physical, scale, 0.0, 65535.0);
  if (!raw)
    return std::nullopt;
  return static_cast<std::uint16_t>(*raw);
}

double from_scaled_i32(std::int32_t raw, double scale) noexcept {
  if (raw == kScaledI32NoData)
    return std::numeric_limits<double>::quiet_NaN();
  return static_cast<double>(raw) * scale;
}

double from_scaled_i16(std::int16_t raw, double scale) noexcept {
  if (raw == kScaledI16NoData)
    return std::numeric_limits<double>::quiet_NaN();
  return static_cast<double>(raw) * scale;
}

double from_scaled_u16(std::uint16_t raw, double scale) noexcept {
  return static_cast<double>(raw) * scale;
}

bool put_u16(std::span<std::uint16_t> regs, std::size_t offset, std::uint16_t value) noexcept {
  if (!fits(regs.size(), offset, 1))
    return false;
  regs[offset] = value;
  return true;
}

bool put_u32(std::span<std::uint16_t> regs, std::size_t offset, std::uint32_t value,
             WordOrder order) noexcept {
  if (!fits(regs.size(), offset, 2))
    return false;
  const auto r = encode_u32(value, order);
  std::copy(r.begin(), r.end(), regs.begin() + static_cast<std::ptrdiff_t>(offset));
  return true;
}

bool put_i32(std::span<std::uint16_t> regs, std::size_t offset, std::int32_t value,
             WordOrder order) noexcept {
  return put_u32(regs, offset, std::bit_cast<std::uint32_t>(value), order);
}

bool put_f32(std::span<std::uint16_t> regs, std::size_t offset, float value,
             WordOrder order) noexcept {
  return put_u32(regs, offset, std::bit_cast<std::uint32_t>(value), order);
}

bool put_f64(std::span<std::uint16_t> regs, std::size_t offset, double value,
             WordOrder order) noexcept {
  if (!fits(regs.size(), offset, 4))
    return false;
  const auto r = encode_f64(value, order);
  std::copy(r.begin(), r.end(), regs.begin() + static_cast<std::ptrdiff_t>(offset));
  return true;
}

std::optional<std::uint16_t> get_u16(std::span<const std::uint16_t> regs,
                                     std::size_t offset) noexcept {
  if (!fits(regs.size(), offset, 1))
    return std::nullopt;
  return regs[offset];
}

std::optional<std::uint32_t> get_u32(std::span<const std::uint16_t> regs, std::size_t offset,
                                     WordOrder order) noexcept {
  if (!fits(regs.size(), offset, 2))
    return std::nullopt;
  return decode_u32({regs[offset], regs[offset + 1]}, order);
}

std::optional<std::int32_t> get_i32(std::span<const std::uint16_t> regs, std::size_t offset,
                                    WordOrder order) noexcept {
  const auto u = get_u32(regs, offset, order);
  if (!u)
    return std::nullopt;
  return std::bit_cast<std::int32_t>(*u);
}

std::optional<float> get_f32(std::span<const std::uint16_t> regs, std::size_t offset,
                             WordOrder order) noexcept {
  const auto u = get_u32(regs, offset, order);
  if (!u)
    return std::nullopt;
  return std::bit_cast<float>(*u);
}

std::optional<double> get_f64(std::span<const std::uint16_t> regs, std::size_t offset,
                              WordOrder order) noexcept {
  if (!fits(regs.size(), offset, 4))
    return std::nullopt;
  return decode_f64({regs[offset], regs[offset + 1], regs[offset + 2], regs[offset + 3]}, order);
}

// ---- Navigation map -------------------------------------------------------------------------

NavLayout nav_layout(NavMapConfig::Encoding encoding) noexcept {
  // docs/icd/modbus.md, "Navigation map": a 4-register header, then the values in a fixed order.
  NavLayout l;
  const std::size_t lat_lon = encoding == NavMapConfig::Encoding::kFloat32 ? 4 : 2;
  std::size_t at = 4;
  l.latitude = at;
  at += lat_lon;
  l.longitude = at;
  at += lat_lon;
  std::size_t* rest[] = {&l.height,   &l.true_heading, &l.pitch, &l.roll,
                         &l.vel_east, &l.vel_north,    &l.vel_up};
  for (std::size_t* r : rest) {
    *r = at;
    at += 2;
  }
  l.count = at;
  return l;
}

std::size_t nav_register_count(const NavMapConfig& config) noexcept {
  return nav_layout(config.encoding).count;
}

namespace {

using canas::Field;

struct FieldSlot {
  Field field;
  std::size_t NavLayout::*offset;
  std::uint16_t valid_bit;
  bool angle;               // map unit deg, stored in rad
  bool lat_lon;             // float64 / 1e-7 deg
  double scale;             // kScaledInt scale
  double NavState::*value;  // SI value for the encoder
};

constexpr FieldSlot kSlots[] = {
    {Field::kLatitude, &NavLayout::latitude, nav_status::kPositionValid, true, true,
     nav_scale::kLatLon_deg, &NavState::latitude_rad},
    {Field::kLongitude, &NavLayout::longitude, nav_status::kPositionValid, true, true,
     nav_scale::kLatLon_deg, &NavState::longitude_rad},
    {Field::kHeight, &NavLayout::height, nav_status::kPositionValid, false, false,
     nav_scale::kHeight_m, &NavState::height_m},
    {Field::kTrueHeading, &NavLayout::true_heading, nav_status::kAttitudeValid, true, false,
     nav_scale::kAngle_deg, &NavState::true_heading_rad},
    {Field::kPitch, &NavLayout::pitch, nav_status::kAttitudeValid, true, false,
     nav_scale::kAngle_deg, &NavState::pitch_rad},
    {Field::kRoll, &NavLayout::roll, nav_status::kAttitudeValid, true, false, nav_scale::kAngle_deg,
     &NavState::roll_rad},
    {Field::kVelEast, &NavLayout::vel_east, nav_status::kVelocityValid, false, false,
     nav_scale::kVelocity_mps, &NavState::vel_east_mps},
    {Field::kVelNorth, &NavLayout::vel_north, nav_status::kVelocityValid, false, false,
     nav_scale::kVelocity_mps, &NavState::vel_north_mps},
    {Field::kVelUp, &NavLayout::vel_up, nav_status::kVelocityValid, false, false,
     nav_scale::kVelocity_mps, &NavState::vel_up_mps},
};

}  // namespace

NavDecoder::NavDecoder(const NavMapConfig& config) noexcept
    : config_(config), layout_(nav_layout(config.encoding)) {}

NavDecodeStatus NavDecoder::decode(std::span<const std::uint16_t> regs,
                                   std::int64_t now_ns) noexcept {
  ++counters_.samples;
  if (regs.size() != layout_.count) {
    ++counters_.wrong_size;
    return NavDecodeStatus::kWrongSize;
  }
  const std::uint16_t counter = regs[layout_.update_counter];
  if (seen_ && counter == last_counter_) {
    ++counters_.stale;
    return NavDecodeStatus::kStale;
  }
  if (seen_ && counter != static_cast<std::uint16_t>(last_counter_ + 1))
    ++counters_.counter_gaps;
  seen_ = true;
  last_counter_ = counter;
  last_status_ = regs[layout_.status];
  last_time_ms_ = decode_u32({regs[layout_.time_ms], regs[layout_.time_ms + 1]}, config_.order);
  ++counters_.new_samples;

  const bool floats = config_.encoding == NavMapConfig::Encoding::kFloat32;
  std::size_t stored = 0;
  std::size_t skipped = 0;
  for (const FieldSlot& slot : kSlots) {
    if ((last_status_ & slot.valid_bit) == 0) {
      ++counters_.flagged_invalid;
      ++skipped;
      continue;
    }
    const std::size_t at = layout_.*slot.offset;
    double value = 0.0;  // map units
    if (floats && slot.lat_lon) {
      value = decode_f64({regs[at], regs[at + 1], regs[at + 2], regs[at + 3]}, config_.order);
    } else if (floats) {
      value = static_cast<double>(decode_f32({regs[at], regs[at + 1]}, config_.order));
    } else {
      value = from_scaled_i32(decode_i32({regs[at], regs[at + 1]}, config_.order), slot.scale);
    }
    // The CANaerospace input's limits and conversion: both inputs accept the same states.
    double si = 0.0;
    const canas::FieldCheck check = canas::si_from_bus_units(slot.field, value, si);
    if (check != canas::FieldCheck::kOk) {
      ++(check == canas::FieldCheck::kNotANumber ? counters_.not_a_number : counters_.out_of_range);
      ++skipped;
      continue;
    }
    canas::FieldSample& sample = state_.fields[static_cast<std::size_t>(slot.field)];
    sample.value = si;
    sample.updated_ns = now_ns;
    sample.received = true;
    ++stored;
  }
  counters_.fields_accepted += stored;
  if (stored == 0)
    return NavDecodeStatus::kRejected;
  return skipped == 0 ? NavDecodeStatus::kAccepted : NavDecodeStatus::kPartial;
}

NavEncoder::NavEncoder(const NavMapConfig& config) noexcept
    : config_(config), layout_(nav_layout(config.encoding)) {}

bool NavEncoder::encode(const NavState& state, std::uint16_t status, std::uint32_t time_ms,
                        std::span<std::uint16_t> out) noexcept {
  if (out.size() < layout_.count)
    return false;
  ++counter_;
  out[layout_.update_counter] = counter_;
  out[layout_.status] = status;
  (void)put_u32(out, layout_.time_ms, time_ms, config_.order);
  const bool floats = config_.encoding == NavMapConfig::Encoding::kFloat32;
  for (const FieldSlot& slot : kSlots) {
    const std::size_t at = layout_.*slot.offset;
    const double si = state.*slot.value;
    const double value = slot.angle ? common::degrees(si) : si;
    if (floats && slot.lat_lon) {
      (void)put_f64(out, at, value, config_.order);
    } else if (floats) {
      (void)put_f32(out, at, to_float(value), config_.order);
    } else {
      const auto raw = to_scaled_i32(value, slot.scale);
      (void)put_i32(out, at, raw ? *raw : kScaledI32NoData, config_.order);
    }
  }
  return true;
}

// ---- Detection table ------------------------------------------------------------------------

std::size_t detection_table_registers(const DetectionTableConfig& config) noexcept {
  return kDetectionHeaderRegisters + config.max_detections * kDetectionRecordRegisters + 1;
}

namespace {

bool table_config_valid(const DetectionTableConfig& c) noexcept {
  return c.max_detections >= 1 && c.max_detections <= icd::kMaxDetectionsPerFrame &&
         static_cast<std::size_t>(c.base_address) + detection_table_registers(c) <= 65536;
}

// Same acceptance as the CAN ICD's angles (docs/icd/detections.md); float32 carries any
// finite range, velocity, SNR and RCS.
bool detection_encodable(const icd::Detection& d) noexcept {
  return std::isfinite(d.range_m) && d.range_m >= 0.0 && std::isfinite(d.azimuth_deg) &&
         std::abs(d.azimuth_deg) <= icd::kMaxAbsAngle_deg && std::isfinite(d.elevation_deg) &&
         std::abs(d.elevation_deg) <= icd::kMaxAbsAngle_deg &&
         std::isfinite(d.radial_velocity_mps) && std::isfinite(d.snr_db) &&
         std::isfinite(d.rcs_dbsm) && std::isfinite(d.range_std_m) && d.range_std_m >= 0.0 &&
         std::isfinite(d.azimuth_std_deg) && d.azimuth_std_deg >= 0.0 &&
         std::isfinite(d.elevation_std_deg) && d.elevation_std_deg >= 0.0 &&
         std::isfinite(d.radial_velocity_std_mps) && d.radial_velocity_std_mps >= 0.0;
}

}  // namespace

TableEncodeResult encode_detection_table(const icd::Header& header,
                                         std::span<const icd::Detection> detections,
                                         std::span<std::uint16_t> out,
                                         const DetectionTableConfig& config) noexcept {
  TableEncodeResult result;
  const std::size_t total = detection_table_registers(config);
  if (!table_config_valid(config) || out.size() < total)
    return result;
  const WordOrder order = config.order;
  std::fill(out.begin(), out.begin() + static_cast<std::ptrdiff_t>(total), std::uint16_t{0});
  for (const icd::Detection& d : detections) {
    if (!detection_encodable(d)) {
      ++result.dropped;
      continue;
    }
    if (result.encoded == config.max_detections) {
      ++result.truncated;
      continue;
    }
    const std::size_t at = table_offset::kRecords + result.encoded * kDetectionRecordRegisters;
    auto put = [&](std::size_t field, double v) {
      (void)put_f32(out, at + field, to_float(v), order);
    };
    put(record_offset::kRange, d.range_m);
    put(record_offset::kAzimuth, d.azimuth_deg);
    put(record_offset::kElevation, d.elevation_deg);
    put(record_offset::kRadialVelocity, d.radial_velocity_mps);
    put(record_offset::kSnr, d.snr_db);
    put(record_offset::kRcs, d.rcs_dbsm);
    put(record_offset::kRangeStd, d.range_std_m);
    put(record_offset::kAzimuthStd, d.azimuth_std_deg);
    put(record_offset::kElevationStd, d.elevation_std_deg);
    put(record_offset::kRadialVelocityStd, d.radial_velocity_std_mps);
    out[at + record_offset::kFlags] =
        static_cast<std::uint16_t>((d.range_ambiguous ? record_flags::kRangeAmbiguous : 0) |
                                   (d.velocity_ambiguous ? record_flags::kVelocityAmbiguous : 0));
    ++result.encoded;
  }
  std::uint8_t status = header.status;
  if (result.dropped > 0)
    status |= icd::status::kDropped;
  if (result.truncated > 0)
    status |= icd::status::kTruncated;
  out[table_offset::kFrameCounter] = header.frame_counter;
  out[table_offset::kDetectionCount] = static_cast<std::uint16_t>(result.encoded);
  out[table_offset::kStatus] = status;
  out[table_offset::kMaxDetections] = static_cast<std::uint16_t>(config.max_detections);
  (void)put_u32(out, table_offset::kTimeMs, header.time_ms, order);
  out[table_offset::kRecordRegisters] = static_cast<std::uint16_t>(kDetectionRecordRegisters);
  out[table_offset::kVersion] = kDetectionTableVersion;
  out[total - 1] = header.frame_counter;
  result.ok = true;
  return result;
}

TableDecodeStatus decode_detection_table(std::span<const std::uint16_t> regs,
                                         const DetectionTableConfig& config,
                                         icd::DetectionList& out) noexcept {
  if (!table_config_valid(config) || regs.size() != detection_table_registers(config))
    return TableDecodeStatus::kWrongSize;
  const std::uint16_t count = regs[table_offset::kDetectionCount];
  if (regs[table_offset::kVersion] != kDetectionTableVersion ||
      regs[table_offset::kRecordRegisters] != kDetectionRecordRegisters ||
      regs[table_offset::kMaxDetections] != config.max_detections ||
      count > config.max_detections || regs[table_offset::kStatus] > 0xFF) {
    return TableDecodeStatus::kBadHeader;
  }
  if (regs.back() != regs[table_offset::kFrameCounter])
    return TableDecodeStatus::kTorn;
  const WordOrder order = config.order;
  out.header.frame_counter = regs[table_offset::kFrameCounter];
  out.header.detection_count = static_cast<std::uint8_t>(count);
  out.header.status = static_cast<std::uint8_t>(regs[table_offset::kStatus]);
  out.header.time_ms =
      decode_u32({regs[table_offset::kTimeMs], regs[table_offset::kTimeMs + 1]}, order);
  for (std::size_t i = 0; i < count; ++i) {
    const std::size_t at = table_offset::kRecords + i * kDetectionRecordRegisters;
    auto get = [&](std::size_t field) {
      return static_cast<double>(decode_f32({regs[at + field], regs[at + field + 1]}, order));
    };
    icd::Detection& d = out.detections[i];
    d.range_m = get(record_offset::kRange);
    d.azimuth_deg = get(record_offset::kAzimuth);
    d.elevation_deg = get(record_offset::kElevation);
    d.radial_velocity_mps = get(record_offset::kRadialVelocity);
    d.snr_db = get(record_offset::kSnr);
    d.rcs_dbsm = get(record_offset::kRcs);
    d.range_std_m = get(record_offset::kRangeStd);
    d.azimuth_std_deg = get(record_offset::kAzimuthStd);
    d.elevation_std_deg = get(record_offset::kElevationStd);
    d.radial_velocity_std_mps = get(record_offset::kRadialVelocityStd);
    const std::uint16_t flags = regs[at + record_offset::kFlags];
    d.range_ambiguous = (flags & record_flags::kRangeAmbiguous) != 0;
    d.velocity_ambiguous = (flags & record_flags::kVelocityAmbiguous) != 0;
  }
  out.count = count;
  return TableDecodeStatus::kOk;
}

}  // namespace radar_emu::io::modbus
