#pragma once
// Modbus register codecs and radar-emu's two register maps (docs/icd/modbus.md): the navigation
// feed in (aircraft state from an INS/GNSS with a Modbus interface) and the detection table out.
// Pure code: no libmodbus here (Debian 12's libmodbus 3.1.6 has broken modbus_set_float_*
// setters, fixed upstream in 3.1.11; we pack and unpack every value ourselves).
//
// Modbus registers are 16 bits, sent most significant byte first (Modbus application protocol
// v1.1b3, sec. 4.2: "big-endian representation ... for addresses and data items"). The protocol
// says nothing about values wider than one register; devices use one of two word orders, so it
// is a setting here (WordOrder). Addresses are protocol addresses (0-based); "4xxxx" numbers of
// device manuals are 40001 + address.

#include <array>
#include <cstddef>
#include <cstdint>
#include <limits>
#include <optional>
#include <span>

#include "io/canaerospace.hpp"
#include "io/detection_icd.hpp"

namespace radar_emu::io::modbus {

// ---- Value codecs ---------------------------------------------------------------------------

/// Order of the 16-bit registers of a value wider than one register. Bytes inside a register are
/// always big-endian (Modbus sec. 4.2). Naming after the bytes A (most significant) .. D.
enum class WordOrder : std::uint8_t {
  kABCD = 0,  ///< most significant register first ("big-endian"; the default)
  kCDAB,      ///< least significant register first ("word-swapped"; mbpoll's default for
              ///< 32-bit values); for 64-bit values the four registers are fully reversed
};

/// 32-bit value as two registers.
[[nodiscard]] std::array<std::uint16_t, 2> encode_u32(std::uint32_t value,
                                                      WordOrder order = WordOrder::kABCD) noexcept;
[[nodiscard]] std::uint32_t decode_u32(std::array<std::uint16_t, 2> regs,
                                       WordOrder order = WordOrder::kABCD) noexcept;
/// Two's-complement int32 as two registers.
[[nodiscard]] std::array<std::uint16_t, 2> encode_i32(std::int32_t value,
                                                      WordOrder order = WordOrder::kABCD) noexcept;
[[nodiscard]] std::int32_t decode_i32(std::array<std::uint16_t, 2> regs,
                                      WordOrder order = WordOrder::kABCD) noexcept;
/// IEEE-754 binary32 as two registers (bit pattern kept, NaN payloads included).
/// 123456.0f = 0x47F12000 -> ABCD {0x47F1, 0x2000}, CDAB {0x2000, 0x47F1}.
[[nodiscard]] std::array<std::uint16_t, 2> encode_f32(float value,
                                                      WordOrder order = WordOrder::kABCD) noexcept;
[[nodiscard]] float decode_f32(std::array<std::uint16_t, 2> regs,
                               WordOrder order = WordOrder::kABCD) noexcept;
/// IEEE-754 binary64 as four registers (ABCD: most significant first; CDAB: least first).
[[nodiscard]] std::array<std::uint16_t, 4> encode_f64(double value,
                                                      WordOrder order = WordOrder::kABCD) noexcept;
[[nodiscard]] double decode_f64(std::array<std::uint16_t, 4> regs,
                                WordOrder order = WordOrder::kABCD) noexcept;

/// Raw value that marks "no data" in a scaled int32 field (decodes as NaN).
inline constexpr std::int32_t kScaledI32NoData = std::numeric_limits<std::int32_t>::min();
/// Raw value that marks "no data" in a scaled int16 field (decodes as NaN).
inline constexpr std::int16_t kScaledI16NoData = std::numeric_limits<std::int16_t>::min();

/// Scaled integers: physical = raw * scale, raw = round(physical / scale) (half away from zero).
/// nullopt when `physical` is NaN/infinite, `scale` is not > 0, or the raw value does not fit
/// (the "no data" code is never produced for a value).
[[nodiscard]] std::optional<std::int32_t> to_scaled_i32(double physical, double scale) noexcept;
[[nodiscard]] std::optional<std::int16_t> to_scaled_i16(double physical, double scale) noexcept;
[[nodiscard]] std::optional<std::uint16_t> to_scaled_u16(double physical, double scale) noexcept;
/// raw * scale; NaN for the "no data" codes.
[[nodiscard]] double from_scaled_i32(std::int32_t raw, double scale) noexcept;
[[nodiscard]] double from_scaled_i16(std::int16_t raw, double scale) noexcept;
[[nodiscard]] double from_scaled_u16(std::uint16_t raw, double scale) noexcept;

// Bounded access into a register image: `offset` counts registers from the image's start.
// put_* return false (and write nothing) when the value does not fit inside `regs`; get_*
// return nullopt. All real-time safe.
[[nodiscard]] bool put_u16(std::span<std::uint16_t> regs, std::size_t offset,
                           std::uint16_t value) noexcept;
[[nodiscard]] bool put_u32(std::span<std::uint16_t> regs, std::size_t offset, std::uint32_t value,
                           WordOrder order) noexcept;
[[nodiscard]] bool put_i32(std::span<std::uint16_t> regs, std::size_t offset, std::int32_t value,
                           WordOrder order) noexcept;
[[nodiscard]] bool put_f32(std::span<std::uint16_t> regs, std::size_t offset, float value,
                           WordOrder order) noexcept;
[[nodiscard]] bool put_f64(std::span<std::uint16_t> regs, std::size_t offset, double value,
                           WordOrder order) noexcept;
[[nodiscard]] std::optional<std::uint16_t> get_u16(std::span<const std::uint16_t> regs,
                                                   std::size_t offset) noexcept;
[[nodiscard]] std::optional<std::uint32_t> get_u32(std::span<const std::uint16_t> regs,
                                                   std::size_t offset, WordOrder order) noexcept;
[[nodiscard]] std::optional<std::int32_t> get_i32(std::span<const std::uint16_t> regs,
                                                  std::size_t offset, WordOrder order) noexcept;
[[nodiscard]] std::optional<float> get_f32(std::span<const std::uint16_t> regs, std::size_t offset,
                                           WordOrder order) noexcept;
[[nodiscard]] std::optional<double> get_f64(std::span<const std::uint16_t> regs, std::size_t offset,
                                            WordOrder order) noexcept;

// ---- Navigation map (input) -----------------------------------------------------------------

struct NavMapConfig {
  /// kFloat32: latitude/longitude float64 deg (4 registers), the rest float32 (2 registers).
  /// kScaledInt: every value int32 (2 registers), scaled as in `nav_scale` below.
  enum class Encoding : std::uint8_t { kFloat32 = 0, kScaledInt };

  std::uint16_t base_address = 0;      ///< protocol address (0-based) of the update counter
  WordOrder order = WordOrder::kABCD;  ///< of every multi-register value (u32, int32, floats)
  Encoding encoding = Encoding::kFloat32;
};

/// Validity bits of the status word (a field whose group bit is clear is not updated).
namespace nav_status {
inline constexpr std::uint16_t kPositionValid = 0x0001;  ///< latitude, longitude, height
inline constexpr std::uint16_t kAttitudeValid = 0x0002;  ///< true heading, pitch, roll
inline constexpr std::uint16_t kVelocityValid = 0x0004;  ///< east, north, up velocity
inline constexpr std::uint16_t kAllValid = 0x0007;
}  // namespace nav_status

/// Scales of the kScaledInt encoding (physical = raw int32 * scale).
namespace nav_scale {
/// 1e-7 deg: 1.1 cm of latitude, rounding error <= 0.56 cm (the u-blox/MAVLink convention).
inline constexpr double kLatLon_deg = 1e-7;
inline constexpr double kHeight_m = 1e-3;
inline constexpr double kAngle_deg = 1e-6;  ///< heading, pitch, roll
inline constexpr double kVelocity_mps = 1e-4;
}  // namespace nav_scale

/// Register offsets (from base_address) of the navigation map.
struct NavLayout {
  std::size_t update_counter = 0;  ///< u16, +1 (wrapping) per new state from the sender
  std::size_t status = 1;          ///< u16, nav_status bits
  std::size_t time_ms = 2;         ///< u32, sender time stamp [ms], wraps after 2^32 ms
  std::size_t latitude = 4;        ///< WGS84 [deg]
  std::size_t longitude = 0;       ///< WGS84 [deg]
  std::size_t height = 0;          ///< above the WGS84 ellipsoid [m]
  std::size_t true_heading = 0;    ///< [deg], 0 = north, clockwise
  std::size_t pitch = 0;           ///< [deg], nose up positive
  std::size_t roll = 0;            ///< [deg], right wing down positive
  std::size_t vel_east = 0;        ///< [m/s]
  std::size_t vel_north = 0;       ///< [m/s]
  std::size_t vel_up = 0;          ///< [m/s]
  std::size_t count = 0;           ///< registers in the map (26 float, 22 scaled)
};
[[nodiscard]] NavLayout nav_layout(NavMapConfig::Encoding encoding) noexcept;
[[nodiscard]] std::size_t nav_register_count(const NavMapConfig& config) noexcept;

/// One navigation state in SI units (what a sender encodes).
struct NavState {
  double latitude_rad = 0.0;      ///< WGS84 geodetic
  double longitude_rad = 0.0;     ///< WGS84
  double height_m = 0.0;          ///< above the WGS84 ellipsoid
  double true_heading_rad = 0.0;  ///< 0 = north, clockwise
  double pitch_rad = 0.0;         ///< nose up positive
  double roll_rad = 0.0;          ///< right wing down positive
  double vel_east_mps = 0.0;
  double vel_north_mps = 0.0;
  double vel_up_mps = 0.0;
};

/// Outcome of decoding one register image of the navigation map.
enum class NavDecodeStatus : std::uint8_t {
  kAccepted = 0,  ///< new sample; every field flagged valid was stored
  kPartial,       ///< new sample; some fields rejected (NaN, range) or flagged invalid
  kRejected,      ///< new sample; no field stored
  kStale,         ///< update counter unchanged: nothing stored, fields keep their age
  kWrongSize,     ///< image size differs from nav_register_count(): nothing stored
};

struct NavDecoderCounters {
  std::uint64_t samples = 0;          ///< images offered
  std::uint64_t new_samples = 0;      ///< images with a changed update counter
  std::uint64_t fields_accepted = 0;  ///< field values stored
  std::uint64_t stale = 0;            ///< images with an unchanged update counter (not an error)
  std::uint64_t wrong_size = 0;       ///< images of the wrong size
  std::uint64_t not_a_number = 0;     ///< field values NaN/infinite (or the scaled "no data")
  std::uint64_t out_of_range = 0;     ///< field values outside their physical range
  std::uint64_t flagged_invalid = 0;  ///< field values skipped because their status bit is clear
  std::uint64_t counter_gaps = 0;     ///< update counter advanced by more than one
  [[nodiscard]] std::uint64_t rejected() const noexcept {
    return wrong_size + not_a_number + out_of_range;
  }
};

/// Decodes navigation-map images into the same OwnshipState the CANaerospace decoder fills
/// (radians, metres, m/s; heading wrapped to [0, 2 pi)), with the same physical limits
/// (docs/icd/canaerospace_input.md). Fields get `updated_ns = now_ns` only when the update
/// counter changed, so a frozen sender goes stale by the emulator's timeout. The first image
/// is always new. Real-time safe.
class NavDecoder {
 public:
  explicit NavDecoder(const NavMapConfig& config = {}) noexcept;
  /// `regs`: the nav_register_count() registers from base_address on.
  [[nodiscard]] NavDecodeStatus decode(std::span<const std::uint16_t> regs,
                                       std::int64_t now_ns) noexcept;
  [[nodiscard]] const canas::OwnshipState& state() const noexcept { return state_; }
  [[nodiscard]] const NavDecoderCounters& counters() const noexcept { return counters_; }
  [[nodiscard]] const NavMapConfig& config() const noexcept { return config_; }
  [[nodiscard]] std::size_t register_count() const noexcept { return layout_.count; }
  /// Header of the last new sample.
  [[nodiscard]] std::uint16_t last_update_counter() const noexcept { return last_counter_; }
  [[nodiscard]] std::uint16_t last_status() const noexcept { return last_status_; }
  [[nodiscard]] std::uint32_t last_sender_time_ms() const noexcept { return last_time_ms_; }

 private:
  NavMapConfig config_;
  NavLayout layout_;
  canas::OwnshipState state_{};
  NavDecoderCounters counters_{};
  bool seen_ = false;
  std::uint16_t last_counter_ = 0;
  std::uint16_t last_status_ = 0;
  std::uint32_t last_time_ms_ = 0;
};

/// Writes navigation-map images (the sender side: test servers, the scripted player). Values
/// that cannot be encoded (NaN, or outside int32 in the scaled encoding) go out as NaN or as
/// kScaledI32NoData. Real-time safe.
class NavEncoder {
 public:
  explicit NavEncoder(const NavMapConfig& config = {}) noexcept;
  /// Increments the update counter and writes a full image into `out` (nav_register_count()
  /// registers). Returns false, writing nothing and keeping the counter, if `out` is too small.
  [[nodiscard]] bool encode(const NavState& state, std::uint16_t status, std::uint32_t time_ms,
                            std::span<std::uint16_t> out) noexcept;
  [[nodiscard]] std::uint16_t update_counter() const noexcept { return counter_; }
  [[nodiscard]] const NavMapConfig& config() const noexcept { return config_; }
  [[nodiscard]] std::size_t register_count() const noexcept { return layout_.count; }

 private:
  NavMapConfig config_;
  NavLayout layout_;
  std::uint16_t counter_ = 0;
};

// ---- Detection table (output) ---------------------------------------------------------------

struct DetectionTableConfig {
  std::uint16_t base_address = 0;      ///< protocol address (0-based) of the table's first register
  WordOrder order = WordOrder::kABCD;  ///< of the time stamp and the float32 fields
  std::size_t max_detections = 64;     ///< records in the table, 1..icd::kMaxDetectionsPerFrame
};

inline constexpr std::uint16_t kDetectionTableVersion = 1;
inline constexpr std::size_t kDetectionHeaderRegisters = 8;
inline constexpr std::size_t kDetectionRecordRegisters = 22;  ///< ten float32, flags, spare

/// Header offsets (registers from base_address).
namespace table_offset {
inline constexpr std::size_t kFrameCounter = 0;     ///< u16, +1 per radar frame, wraps
inline constexpr std::size_t kDetectionCount = 1;   ///< u16, valid records
inline constexpr std::size_t kStatus = 2;           ///< u16, icd::status bits (low byte)
inline constexpr std::size_t kMaxDetections = 3;    ///< u16, records in the table
inline constexpr std::size_t kTimeMs = 4;           ///< u32, radar frame time [ms]
inline constexpr std::size_t kRecordRegisters = 6;  ///< u16, = kDetectionRecordRegisters
inline constexpr std::size_t kVersion = 7;          ///< u16, = kDetectionTableVersion
inline constexpr std::size_t kRecords = 8;          ///< first record
}  // namespace table_offset

/// Offsets inside a record (float32 unless noted).
namespace record_offset {
inline constexpr std::size_t kRange = 0;               ///< slant range [m]
inline constexpr std::size_t kAzimuth = 2;             ///< from boresight, positive right [deg]
inline constexpr std::size_t kElevation = 4;           ///< from boresight, positive up [deg]
inline constexpr std::size_t kRadialVelocity = 6;      ///< [m/s], positive receding
inline constexpr std::size_t kSnr = 8;                 ///< [dB]
inline constexpr std::size_t kRcs = 10;                ///< [dBsm]
inline constexpr std::size_t kRangeStd = 12;           ///< one sigma [m], 0 = not given
inline constexpr std::size_t kAzimuthStd = 14;         ///< one sigma [deg]
inline constexpr std::size_t kElevationStd = 16;       ///< one sigma [deg]
inline constexpr std::size_t kRadialVelocityStd = 18;  ///< one sigma [m/s]
inline constexpr std::size_t kFlags = 20;              ///< u16, record_flags bits
inline constexpr std::size_t kSpare = 21;              ///< u16, 0
}  // namespace record_offset

namespace record_flags {
inline constexpr std::uint16_t kRangeAmbiguous = 0x0001;     ///< the range may be folded
inline constexpr std::uint16_t kVelocityAmbiguous = 0x0002;  ///< the velocity may be folded
}  // namespace record_flags

/// Registers of the whole table: header + max_detections records + one trailer register (a
/// copy of the frame counter: a reader that needs several requests compares it with the
/// header's to detect a table updated between its reads).
[[nodiscard]] std::size_t detection_table_registers(const DetectionTableConfig& config) noexcept;

struct TableEncodeResult {
  bool ok = false;            ///< false: config invalid or `out` too small (nothing written)
  std::size_t encoded = 0;    ///< records written
  std::size_t dropped = 0;    ///< detections NaN/infinite, negative range or accuracy, or
                              ///< |angle| > 90 deg
  std::size_t truncated = 0;  ///< detections beyond max_detections
};

/// Writes the whole table (records beyond the count are zero). The header's status gets
/// icd::status::kDropped / kTruncated ORed in as on CAN; its detection_count is ignored (the
/// table carries what was encoded). Real-time safe.
[[nodiscard]] TableEncodeResult encode_detection_table(
    const icd::Header& header, std::span<const icd::Detection> detections,
    std::span<std::uint16_t> out, const DetectionTableConfig& config = {}) noexcept;

enum class TableDecodeStatus : std::uint8_t {
  kOk = 0,
  kWrongSize,  ///< regs.size() != detection_table_registers(config)
  kBadHeader,  ///< version, record size or max_detections differ from config, or count > max
  kTorn,       ///< trailer differs from the header's frame counter
};

/// Reads a table (the avionics side and tests). Real-time safe.
[[nodiscard]] TableDecodeStatus decode_detection_table(std::span<const std::uint16_t> regs,
                                                       const DetectionTableConfig& config,
                                                       icd::DetectionList& out) noexcept;

}  // namespace radar_emu::io::modbus
