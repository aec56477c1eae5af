#pragma once
// CANaerospace (Stock Flight Systems, "CANaerospace - Interface specification for airborne CAN
// applications", v1.7, 2006): aircraft state in. Message layout (spec sec. 4): byte 0 node-ID,
// byte 1 data type, byte 2 service code, byte 3 message code, bytes 4..7 value, big-endian.

#include <array>
#include <cstdint>
#include <limits>
#include <optional>
#include <string_view>
#include <utility>

#include "io/can_frame.hpp"

namespace radar_emu::io::canas {

/// Data type codes (spec table 4.x "CANaerospace data types").
enum class DataType : std::uint8_t {
  kNoData = 0,
  kError = 1,
  kFloat = 2,
  kLong = 3,
  kULong = 4,
  kBLong = 5,
  kShort = 6,
  kUShort = 7,
  kBShort = 8,
  kChar = 9,
  kUChar = 10,
  kBChar = 11,
  kShort2 = 12,
  kUShort2 = 13,
  kBShort2 = 14,
  kChar4 = 15,
  kUChar4 = 16,
  kBChar4 = 17,
  kChar2 = 18,
  kUChar2 = 19,
  kBChar2 = 20,
  kMemId = 21,
  kChksum = 22,
  kAChar = 23,
  kAChar2 = 24,
  kAChar4 = 25,
  kChar3 = 26,
  kUChar3 = 27,
  kBChar3 = 28,
  kAChar3 = 29,
  kDoubleH = 30,
  kDoubleL = 31,
  // 32..99 reserved; 100..255 user-defined
};

/// Normal-operation identifiers radar-emu consumes (spec appendix A, default identifier
/// distribution). Units on the bus: degrees, metres, metres per second.
namespace id {
inline constexpr std::uint16_t kPitchAngle = 311;          ///< [deg]
inline constexpr std::uint16_t kRollAngle = 312;           ///< [deg]
inline constexpr std::uint16_t kGpsLatitude = 1036;        ///< [deg]
inline constexpr std::uint16_t kGpsLongitude = 1037;       ///< [deg]
inline constexpr std::uint16_t kGpsHeight = 1038;          ///< height above WGS84 ellipsoid [m]
inline constexpr std::uint16_t kTrueEastVelocity = 1130;   ///< [m/s]
inline constexpr std::uint16_t kTrueNorthVelocity = 1131;  ///< [m/s]
inline constexpr std::uint16_t kTrueUpVelocity = 1132;     ///< [m/s]
inline constexpr std::uint16_t kTrueHeading = 1133;        ///< [deg], 0 = true north, clockwise
}  // namespace id

/// The ownship state fields radar-emu tracks. Stored in SI (radians, metres, m/s).
enum class Field : std::uint8_t {
  kPitch = 0,    ///< pitch angle [rad], nose up positive
  kRoll,         ///< roll angle [rad], right wing down positive
  kTrueHeading,  ///< true heading [rad], 0 = north, clockwise, wrapped to [0, 2 pi)
  kLatitude,     ///< WGS84 geodetic latitude [rad]
  kLongitude,    ///< WGS84 longitude [rad]
  kHeight,       ///< height above the WGS84 ellipsoid [m]
  kVelEast,      ///< true east velocity [m/s]
  kVelNorth,     ///< true north velocity [m/s]
  kVelUp,        ///< true up velocity [m/s]
  kCount
};
inline constexpr std::size_t kFieldCount = static_cast<std::size_t>(Field::kCount);

/// Outcome of checking one field value against its physical limits.
enum class FieldCheck : std::uint8_t { kOk = 0, kNotANumber, kOutOfRange };

/// A field value in bus units (deg, m, m/s) to its stored SI value (rad, m, m/s; true heading
/// wrapped to [0, 2 pi)), after the physical limits of docs/icd/canaerospace_input.md. Every
/// ownship input (CANaerospace, the Modbus navigation map) goes through it, so all accept the
/// same states. `si` is written only for kOk. Real-time safe.
[[nodiscard]] FieldCheck si_from_bus_units(Field field, double value, double& si) noexcept;

/// CAN identifier carrying `field` in the default configuration (the id:: constants).
[[nodiscard]] std::uint16_t can_id_of(Field field) noexcept;

/// Name of `field` in configuration files and errors: "pitch", "roll", "true_heading",
/// "latitude", "longitude", "height", "vel_east", "vel_north", "vel_up".
[[nodiscard]] std::string_view field_name(Field field) noexcept;

/// The field named `name` (see field_name()), or nullopt.
[[nodiscard]] std::optional<Field> field_from_name(std::string_view name) noexcept;

/// Encodings a field accepts (bit set; docs/icd/canaerospace_input.md).
namespace accept {
inline constexpr std::uint8_t kFloat = 0x01;   ///< FLOAT (2): IEEE-754 single
inline constexpr std::uint8_t kDouble = 0x02;  ///< DOUBLEH (30) + DOUBLEL (31) pair, high first
inline constexpr std::uint8_t kLong = 0x04;    ///< LONG (3): signed 32-bit x FieldInput::long_lsb
inline constexpr std::uint8_t kAll = kFloat | kDouble | kLong;
}  // namespace accept

/// Where one field comes from on the bus.
struct FieldInput {
  std::uint16_t can_id = 0;  ///< 11-bit identifier carrying the field (0..2047)
  std::uint8_t accepted = accept::kFloat | accept::kDouble;  ///< accept:: bits, at least one
  double long_lsb = 0.0;  ///< bus units [deg, m or m/s] per LSB of a LONG; > 0 if LONG accepted
};

/// Per-field identifiers and encodings, and the node-ID filter. Default-constructed, it is the
/// table radar-emu has always used: the id:: identifiers, FLOAT and DOUBLE everywhere, LONG in
/// 1e-7 deg for latitude and longitude, frames from any node.
struct DecoderConfig {
  std::array<FieldInput, kFieldCount> fields = default_fields();
  /// Accept only frames whose node-ID (byte 0) equals this; any node when empty. Frames of a
  /// consumed identifier from another node are counted as `other_node`, not as errors.
  std::optional<std::uint8_t> node_id;

  [[nodiscard]] FieldInput& operator[](Field f) noexcept {
    return fields[static_cast<std::size_t>(f)];
  }
  [[nodiscard]] const FieldInput& operator[](Field f) const noexcept {
    return fields[static_cast<std::size_t>(f)];
  }
  [[nodiscard]] static std::array<FieldInput, kFieldCount> default_fields() noexcept;
};

/// Checks `config` at setup. Throws std::invalid_argument with one line naming the field for an
/// identifier outside 11 bits, an identifier used by two fields, no accepted encoding (or
/// unknown accept:: bits), or LONG accepted without a positive, finite long_lsb.
void validate(const DecoderConfig& config);

/// Latest value of one field.
struct FieldSample {
  double value = 0.0;           ///< SI value (see Field)
  std::int64_t updated_ns = 0;  ///< decode time of the last accepted value [ns]
  bool received = false;        ///< at least one value accepted
};

/// Ownship state assembled from the bus, with per-field age.
struct OwnshipState {
  std::array<FieldSample, kFieldCount> fields{};

  [[nodiscard]] const FieldSample& operator[](Field f) const noexcept {
    return fields[static_cast<std::size_t>(f)];
  }
  /// Age of `f` at `now_ns` [s]; +infinity when never received.
  [[nodiscard]] double age_s(Field f, std::int64_t now_ns) const noexcept;
  /// True when `f` was received and is not older than `timeout_ns`.
  [[nodiscard]] bool fresh(Field f, std::int64_t now_ns, std::int64_t timeout_ns) const noexcept;
  /// True when every field is fresh.
  [[nodiscard]] bool all_fresh(std::int64_t now_ns, std::int64_t timeout_ns) const noexcept;
};

/// Outcome of decoding one frame.
enum class DecodeStatus : std::uint8_t {
  kAccepted = 0,         ///< value stored
  kPendingDoubleLow,     ///< DOUBLEH stored, waiting for its DOUBLEL
  kIgnoredId,            ///< identifier radar-emu does not consume (not an error)
  kShortFrame,           ///< DLC too small for the header or for the data type's payload
  kUnknownDataType,      ///< data-type byte not defined by the spec (32..99) or user-defined
  kUnsupportedDataType,  ///< defined by the spec but not accepted for this identifier
  kNotANumber,           ///< NaN or infinity
  kOutOfRange,           ///< physically impossible value for the field
  kUnpairedDouble,       ///< DOUBLEL without a preceding DOUBLEH on the same identifier
  kExtendedId,           ///< CANaerospace uses 11-bit identifiers only
  kOtherNode,            ///< consumed identifier, but not from the configured node (not an error)
  /// The identifier's message code is the same as in its last frame, or a DOUBLEH repeats the
  /// code of the last completed pair (spec sec. 4.1.4: +1 per message): a repetition (a
  /// duplicated frame, or a sender stuck on its last message). The value is not taken, so the
  /// field's age keeps growing (not an error).
  kRepeatedMessageCode,
};

/// Rejection and bookkeeping counters (reported in report.json).
struct DecoderCounters {
  std::uint64_t frames = 0;    ///< frames offered to the decoder
  std::uint64_t accepted = 0;  ///< values stored
  std::uint64_t ignored_id = 0;
  std::uint64_t short_frame = 0;
  std::uint64_t unknown_data_type = 0;
  std::uint64_t unsupported_data_type = 0;
  std::uint64_t not_a_number = 0;
  std::uint64_t out_of_range = 0;
  std::uint64_t unpaired_double = 0;
  std::uint64_t extended_id = 0;
  std::uint64_t message_code_gaps = 0;  ///< message code did not follow the previous one + 1
  /// message_code_gaps split by field (indexed by Field).
  std::array<std::uint64_t, kFieldCount> message_code_gaps_by_field{};
  std::uint64_t other_node = 0;  ///< frames of a consumed identifier from another node-ID
  std::uint64_t repeated_message_code = 0;  ///< kRepeatedMessageCode frames (value not taken)
  [[nodiscard]] std::uint64_t rejected() const noexcept {
    return short_frame + unknown_data_type + unsupported_data_type + not_a_number + out_of_range +
           unpaired_double + extended_id;
  }
};

/// Decodes CANaerospace frames into an OwnshipState; decode() is real-time safe. Accepted
/// encodings per field (DecoderConfig): FLOAT; a DOUBLEH + DOUBLEL pair on the same identifier
/// (high word first, the two frames consecutive on that identifier); LONG scaled by long_lsb
/// (by default latitude/longitude only, in 1e-7 deg, a common vendor practice).
class Decoder {
 public:
  /// The default configuration (DecoderConfig{}): today's identifiers, any node.
  Decoder() noexcept;
  /// A configured decoder. Throws std::invalid_argument (see validate()) at setup.
  explicit Decoder(const DecoderConfig& config);

  [[nodiscard]] DecodeStatus decode(const CanFrame& frame, std::int64_t now_ns) noexcept;
  [[nodiscard]] const OwnshipState& state() const noexcept { return state_; }
  [[nodiscard]] const DecoderCounters& counters() const noexcept { return counters_; }
  [[nodiscard]] const DecoderConfig& config() const noexcept { return config_; }

 private:
  struct IdTrack {
    std::uint8_t last_message_code = 0;
    bool seen = false;
    bool double_high_pending = false;
    std::uint32_t double_high_bits = 0;
    std::uint8_t double_high_code = 0;     // message code of the pending DOUBLEH
    std::uint8_t last_pair_high_code = 0;  // DOUBLEH code of the last completed pair
    bool pair_seen = false;
  };
  static constexpr std::uint8_t kNoField = 0xFF;
  void index_identifiers() noexcept;

  DecoderConfig config_{};
  std::array<std::uint8_t, 2048> field_by_id_{};  ///< Field per 11-bit identifier, or kNoField
  OwnshipState state_{};
  DecoderCounters counters_{};
  std::array<IdTrack, kFieldCount> track_{};
};

// ---- Encoding (scripted peers and tests) ------------------------------------------------

/// A FLOAT message: DLC 8, value big-endian IEEE-754 single.
[[nodiscard]] CanFrame encode_float(std::uint16_t can_id, std::uint8_t node_id,
                                    std::uint8_t message_code, float value) noexcept;

/// A LONG message (signed 32-bit, big-endian).
[[nodiscard]] CanFrame encode_long(std::uint16_t can_id, std::uint8_t node_id,
                                   std::uint8_t message_code, std::int32_t value) noexcept;

/// A DOUBLEH + DOUBLEL pair carrying `value` as IEEE-754 double: first = high 32 bits with
/// `message_code`, second = low 32 bits with `message_code + 1` (mod 256).
[[nodiscard]] std::pair<CanFrame, CanFrame> encode_double(std::uint16_t can_id,
                                                          std::uint8_t node_id,
                                                          std::uint8_t message_code,
                                                          double value) noexcept;

}  // namespace radar_emu::io::canas
