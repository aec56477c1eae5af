#include "io/canaerospace.hpp"

#include <bit>
#include <cmath>
#include <numbers>
#include <stdexcept>
#include <string>

#include "common/units.hpp"

namespace radar_emu::io::canas {

namespace {

// Header bytes (spec sec. 4.1).
constexpr std::size_t kNodeIdByte = 0;
constexpr std::size_t kDataTypeByte = 1;
constexpr std::size_t kMessageCodeByte = 3;
constexpr std::size_t kHeaderBytes = 4;
constexpr std::size_t kValue32Bytes = 8;

std::uint32_t read_be32(const CanFrame& f) noexcept {
  return (static_cast<std::uint32_t>(f.data[4]) << 24) |
         (static_cast<std::uint32_t>(f.data[5]) << 16) |
         (static_cast<std::uint32_t>(f.data[6]) << 8) | static_cast<std::uint32_t>(f.data[7]);
}

void write_be32(CanFrame& f, std::uint32_t v) noexcept {
  f.data[4] = static_cast<std::uint8_t>(v >> 24);
  f.data[5] = static_cast<std::uint8_t>(v >> 16);
  f.data[6] = static_cast<std::uint8_t>(v >> 8);
  f.data[7] = static_cast<std::uint8_t>(v);
}

CanFrame header_frame(std::uint16_t can_id, std::uint8_t node_id, DataType type,
                      std::uint8_t message_code) noexcept {
  CanFrame f;
  f.id = can_id;
  f.len = static_cast<std::uint8_t>(kValue32Bytes);
  f.data[kNodeIdByte] = node_id;
  f.data[kDataTypeByte] = static_cast<std::uint8_t>(type);
  f.data[2] = 0;  // service code: 0 for normal operation data
  f.data[kMessageCodeByte] = message_code;
  return f;
}

// 11-bit identifiers (spec sec. 3: CAN 2.0A).
constexpr std::uint32_t kMaxStandardId = 0x7FF;

std::string quoted(Field f) {
  return "'" + std::string(field_name(f)) + "'";
}

// Physical validity limits on the bus units (deg, m, m/s).
struct Limits {
  double lo, hi;
};
Limits limits_of(Field f) noexcept {
  switch (f) {
    case Field::kPitch:
      return {-90.0, 90.0};
    case Field::kRoll:
      return {-180.0, 180.0};
    case Field::kTrueHeading:
      return {-360.0, 360.0};
    case Field::kLatitude:
      return {-90.0, 90.0};
    case Field::kLongitude:
      return {-180.0, 180.0};
    case Field::kHeight:
      return {-1000.0, 60000.0};
    case Field::kVelEast:
    case Field::kVelNorth:
    case Field::kVelUp:
      return {-1500.0, 1500.0};
    case Field::kCount:
      break;
  }
  return {0.0, 0.0};
}

bool is_angle(Field f) noexcept {
  return f == Field::kPitch || f == Field::kRoll || f == Field::kTrueHeading ||
         f == Field::kLatitude || f == Field::kLongitude;
}

}  // namespace

FieldCheck si_from_bus_units(Field field, double value, double& si) noexcept {
  if (!std::isfinite(value))
    return FieldCheck::kNotANumber;
  const Limits lim = limits_of(field);
  if (value < lim.lo || value > lim.hi)
    return FieldCheck::kOutOfRange;
  double v = is_angle(field) ? common::radians(value) : value;
  if (field == Field::kTrueHeading) {
    v = std::fmod(v, 2.0 * std::numbers::pi);
    if (v < 0.0)
      v += 2.0 * std::numbers::pi;
    // A tiny negative angle rounds to exactly 2 pi when 2 pi is added: keep [0, 2 pi).
    if (v >= 2.0 * std::numbers::pi)
      v = 0.0;
  }
  si = v;
  return FieldCheck::kOk;
}

std::uint16_t can_id_of(Field field) noexcept {
  switch (field) {
    case Field::kPitch:
      return id::kPitchAngle;
    case Field::kRoll:
      return id::kRollAngle;
    case Field::kTrueHeading:
      return id::kTrueHeading;
    case Field::kLatitude:
      return id::kGpsLatitude;
    case Field::kLongitude:
      return id::kGpsLongitude;
    case Field::kHeight:
      return id::kGpsHeight;
    case Field::kVelEast:
      return id::kTrueEastVelocity;
    case Field::kVelNorth:
      return id::kTrueNorthVelocity;
    case Field::kVelUp:
      return id::kTrueUpVelocity;
    case Field::kCount:
      break;
  }
  return 0;
}

std::string_view field_name(Field field) noexcept {
  switch (field) {
    case Field::kPitch:
      return "pitch";
    case Field::kRoll:
      return "roll";
    case Field::kTrueHeading:
      return "true_heading";
    case Field::kLatitude:
      return "latitude";
    case Field::kLongitude:
      return "longitude";
    case Field::kHeight:
      return "height";
    case Field::kVelEast:
      return "vel_east";
    case Field::kVelNorth:
      return "vel_north";
    case Field::kVelUp:
      return "vel_up";
    case Field::kCount:
      break;
  }
  return "";
}

std::optional<Field> field_from_name(std::string_view name) noexcept {
  for (std::size_t i = 0; i < kFieldCount; ++i) {
    if (field_name(static_cast<Field>(i)) == name)
      return static_cast<Field>(i);
  }
  return std::nullopt;
}

std::array<FieldInput, kFieldCount> DecoderConfig::default_fields() noexcept {
  std::array<FieldInput, kFieldCount> t{};
  for (std::size_t i = 0; i < kFieldCount; ++i) {
    t[i].can_id = can_id_of(static_cast<Field>(i));
    t[i].accepted = accept::kFloat | accept::kDouble;
  }
  // Latitude/longitude also as LONG in 1e-7 deg (a common vendor practice; see buses notes in
  // docs/icd/canaerospace_input.md).
  for (Field f : {Field::kLatitude, Field::kLongitude}) {
    t[static_cast<std::size_t>(f)].accepted |= accept::kLong;
    t[static_cast<std::size_t>(f)].long_lsb = 1e-7;
  }
  return t;
}

void validate(const DecoderConfig& config) {
  for (std::size_t i = 0; i < kFieldCount; ++i) {
    const auto f = static_cast<Field>(i);
    const FieldInput& in = config.fields[i];
    if (in.can_id > kMaxStandardId) {
      throw std::invalid_argument("canaerospace input: field " + quoted(f) + " identifier " +
                                  std::to_string(in.can_id) +
                                  " is outside the 11-bit range 0..2047");
    }
    for (std::size_t j = 0; j < i; ++j) {
      if (config.fields[j].can_id == in.can_id) {
        throw std::invalid_argument("canaerospace input: field " + quoted(f) + " identifier " +
                                    std::to_string(in.can_id) + " is already used by field " +
                                    quoted(static_cast<Field>(j)));
      }
    }
    if (in.accepted == 0 || (in.accepted & ~accept::kAll) != 0) {
      throw std::invalid_argument("canaerospace input: field " + quoted(f) +
                                  " must accept one or more of FLOAT, DOUBLE, LONG");
    }
    if ((in.accepted & accept::kLong) != 0 && !(in.long_lsb > 0.0 && std::isfinite(in.long_lsb))) {
      throw std::invalid_argument("canaerospace input: field " + quoted(f) +
                                  " accepts LONG but long_lsb is not a positive number");
    }
  }
}

Decoder::Decoder() noexcept {
  index_identifiers();
}

Decoder::Decoder(const DecoderConfig& config) : config_(config) {
  validate(config_);
  index_identifiers();
}

void Decoder::index_identifiers() noexcept {
  field_by_id_.fill(kNoField);
  for (std::size_t i = 0; i < kFieldCount; ++i) {
    const std::uint16_t can_id = config_.fields[i].can_id;
    if (can_id <= kMaxStandardId)
      field_by_id_[can_id] = static_cast<std::uint8_t>(i);
  }
}

double OwnshipState::age_s(Field f, std::int64_t now_ns) const noexcept {
  const FieldSample& s = (*this)[f];
  if (!s.received)
    return std::numeric_limits<double>::infinity();
  return static_cast<double>(now_ns - s.updated_ns) * 1e-9;
}

bool OwnshipState::fresh(Field f, std::int64_t now_ns, std::int64_t timeout_ns) const noexcept {
  const FieldSample& s = (*this)[f];
  return s.received && now_ns - s.updated_ns <= timeout_ns;
}

bool OwnshipState::all_fresh(std::int64_t now_ns, std::int64_t timeout_ns) const noexcept {
  for (std::size_t i = 0; i < kFieldCount; ++i) {
    if (!fresh(static_cast<Field>(i), now_ns, timeout_ns))
      return false;
  }
  return true;
}

DecodeStatus Decoder::decode(const CanFrame& frame, std::int64_t now_ns) noexcept {
  ++counters_.frames;
  if (frame.extended) {
    ++counters_.extended_id;
    return DecodeStatus::kExtendedId;
  }
  const std::uint8_t index = frame.id <= kMaxStandardId ? field_by_id_[frame.id] : kNoField;
  if (index == kNoField) {
    ++counters_.ignored_id;
    return DecodeStatus::kIgnoredId;
  }
  const auto field = static_cast<Field>(index);
  const FieldInput& input = config_.fields[index];
  if (frame.len < kHeaderBytes) {
    ++counters_.short_frame;
    return DecodeStatus::kShortFrame;
  }
  if (config_.node_id && frame.data[kNodeIdByte] != *config_.node_id) {
    ++counters_.other_node;
    return DecodeStatus::kOtherNode;
  }
  const std::uint8_t type_code = frame.data[kDataTypeByte];
  if (type_code > static_cast<std::uint8_t>(DataType::kDoubleL)) {
    ++counters_.unknown_data_type;
    return DecodeStatus::kUnknownDataType;
  }
  const auto type = static_cast<DataType>(type_code);
  const bool accepted_type = (type == DataType::kFloat && (input.accepted & accept::kFloat) != 0) ||
                             ((type == DataType::kDoubleH || type == DataType::kDoubleL) &&
                              (input.accepted & accept::kDouble) != 0) ||
                             (type == DataType::kLong && (input.accepted & accept::kLong) != 0);
  if (!accepted_type) {
    ++counters_.unsupported_data_type;
    return DecodeStatus::kUnsupportedDataType;
  }
  if (frame.len < kValue32Bytes) {
    ++counters_.short_frame;
    return DecodeStatus::kShortFrame;
  }

  // Message-code tracking (spec sec. 4.1.4: incremented by one per message, wraps at 255).
  IdTrack& track = track_[index];
  const std::uint8_t code = frame.data[kMessageCodeByte];
  if (track.seen &&
      (code == track.last_message_code ||
       (type == DataType::kDoubleH && track.pair_seen && code == track.last_pair_high_code))) {
    // The same message again: nothing new, and taking it would make stale data look fresh.
    ++counters_.repeated_message_code;
    return DecodeStatus::kRepeatedMessageCode;
  }
  if (track.seen && code != static_cast<std::uint8_t>(track.last_message_code + 1)) {
    ++counters_.message_code_gaps;
    ++counters_.message_code_gaps_by_field[index];
  }
  track.seen = true;
  track.last_message_code = code;

  const std::uint32_t bits = read_be32(frame);
  double value = 0.0;
  switch (type) {
    case DataType::kDoubleH:
      if (track.double_high_pending)
        ++counters_.unpaired_double;  // previous high never closed
      track.double_high_pending = true;
      track.double_high_bits = bits;
      track.double_high_code = code;
      return DecodeStatus::kPendingDoubleLow;
    case DataType::kDoubleL: {
      if (!track.double_high_pending) {
        ++counters_.unpaired_double;
        return DecodeStatus::kUnpairedDouble;
      }
      track.double_high_pending = false;
      track.last_pair_high_code = track.double_high_code;
      track.pair_seen = true;
      const std::uint64_t all = (static_cast<std::uint64_t>(track.double_high_bits) << 32) | bits;
      value = std::bit_cast<double>(all);
      break;
    }
    case DataType::kFloat:
      value = static_cast<double>(std::bit_cast<float>(bits));
      break;
    case DataType::kLong:
      value = static_cast<double>(std::bit_cast<std::int32_t>(bits)) * input.long_lsb;
      break;
    default:
      ++counters_.unsupported_data_type;
      return DecodeStatus::kUnsupportedDataType;
  }
  // A value in any other type breaks a pending DOUBLEH/DOUBLEL pair.
  if (type != DataType::kDoubleL && track.double_high_pending) {
    track.double_high_pending = false;
    ++counters_.unpaired_double;
  }

  double si = 0.0;
  switch (si_from_bus_units(field, value, si)) {
    case FieldCheck::kNotANumber:
      ++counters_.not_a_number;
      return DecodeStatus::kNotANumber;
    case FieldCheck::kOutOfRange:
      ++counters_.out_of_range;
      return DecodeStatus::kOutOfRange;
    case FieldCheck::kOk:
      break;
  }
  FieldSample& sample = state_.fields[static_cast<std::size_t>(field)];
  sample.value = si;
  sample.updated_ns = now_ns;
  sample.received = true;
  ++counters_.accepted;
  return DecodeStatus::kAccepted;
}

CanFrame encode_float(std::uint16_t can_id, std::uint8_t node_id, std::uint8_t message_code,
                      float value) noexcept {
  CanFrame f = header_frame(can_id, node_id, DataType::kFloat, message_code);
  write_be32(f, std::bit_cast<std::uint32_t>(value));
  return f;
}

CanFrame encode_long(std::uint16_t can_id, std::uint8_t node_id, std::uint8_t message_code,
                     std::int32_t value) noexcept {
  CanFrame f = header_frame(can_id, node_id, DataType::kLong, message_code);
  write_be32(f, std::bit_cast<std::uint32_t>(value));
  return f;
}

std::pair<CanFrame, CanFrame> encode_double(std::uint16_t can_id, std::uint8_t node_id,
                                            std::uint8_t message_code, double value) noexcept {
  const auto bits = std::bit_cast<std::uint64_t>(value);
  CanFrame high = header_frame(can_id, node_id, DataType::kDoubleH, message_code);
  write_be32(high, static_cast<std::uint32_t>(bits >> 32));
  CanFrame low = header_frame(can_id, node_id, DataType::kDoubleL,
                              static_cast<std::uint8_t>(message_code + 1));
  write_be32(low, static_cast<std::uint32_t>(bits & 0xFFFFFFFFu));
  return {high, low};
}

}  // namespace radar_emu::io::canas
