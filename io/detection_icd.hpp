#pragma once
// The radar-emu detection ICD, version 1, on classic CAN (docs/icd/detections.md, DBC file
// docs/icd/radar_emu_detections.dbc). Per radar frame: one header frame, then two frames per
// detection (A: range, radial velocity, SNR; B: azimuth, elevation, RCS). All signals are
// little-endian (Intel, DBC "@1"). Identifiers are in CANaerospace's user-defined low-priority
// range (1800-1899) so they cannot collide with normal-operation data on a shared bus.
//
// The same lists also travel packed on CAN FD (docs/icd/detections.md, "CAN FD"): one 48-byte
// header frame 0x70B carrying the header and detections 0-1, then 64-byte continuation frames
// 0x70C with three detections each. Each detection is a 20-byte slot with the classic ICD's
// signals and scalings plus what the classic ICD lacks: the one-sigma accuracies and the range
// and velocity ambiguity flags.

#include <array>
#include <cstddef>
#include <cstdint>
#include <span>

#include "io/can_frame.hpp"

namespace radar_emu::io::icd {

inline constexpr std::uint32_t kHeaderId = 0x708;      ///< 1800
inline constexpr std::uint32_t kDetectionAId = 0x709;  ///< 1801
inline constexpr std::uint32_t kDetectionBId = 0x70A;  ///< 1802
inline constexpr std::size_t kMaxDetectionsPerFrame = 255;

// CAN FD identifiers and frame geometry (docs/icd/detections.md, "CAN FD"). Both are sent with
// bit-rate switching (BRS); lengths are CAN FD payload lengths (ISO 11898-1:2015, DLC 14 = 48
// bytes, DLC 15 = 64 bytes).
inline constexpr std::uint32_t kFdHeaderId = 0x70B;          ///< 1803: header + detections 0, 1
inline constexpr std::uint32_t kFdContinuationId = 0x70C;    ///< 1804: three detections each
inline constexpr std::uint8_t kFdHeaderBytes = 48;           ///< payload length of 0x70B
inline constexpr std::uint8_t kFdContinuationBytes = 64;     ///< payload length of 0x70C
inline constexpr std::size_t kFdSlotBytes = 20;              ///< one packed detection
inline constexpr std::size_t kFdHeaderSlots = 2;             ///< detections in 0x70B
inline constexpr std::size_t kFdContinuationSlots = 3;       ///< detections in each 0x70C
inline constexpr std::size_t kFdHeaderSlotOffset = 8;        ///< byte of slot 0 in 0x70B
inline constexpr std::size_t kFdContinuationSlotOffset = 4;  ///< byte of slot 0 in 0x70C

// Scaling of each signal: physical = raw * kScale (+ offset 0 for all signals).
inline constexpr double kRangeScale_m = 0.01;             ///< u24: 0 .. 167772.15 m
inline constexpr double kRadialVelocityScale_mps = 0.02;  ///< s16: -655.36 .. 655.34 m/s
inline constexpr double kSnrScale_db = 0.5;               ///< u8: 0 .. 127.5 dB
inline constexpr double kAngleScale_deg = 0.01;           ///< s16: azimuth/elevation
inline constexpr double kRcsScale_dbsm = 0.01;            ///< s16: -327.68 .. 327.67 dBsm
inline constexpr double kMaxRange_m = 16777215 * kRangeScale_m;
inline constexpr double kMaxAbsAngle_deg = 90.0;  ///< ICD-valid angles: [-90, +90] deg
inline constexpr double kMaxAbsRadialVelocity_mps = 655.34;

// CAN FD only: one-sigma accuracies, unsigned, saturated at the field's maximum ("this or
// worse"); 0 means "below half a step" or "not given".
inline constexpr double kRangeStdScale_m = 0.01;             ///< u16: 0 .. 655.35 m
inline constexpr double kRadialVelocityStdScale_mps = 0.01;  ///< u12: 0 .. 40.95 m/s
inline constexpr double kAngleStdScale_deg = 0.002;          ///< u14: 0 .. 32.766 deg
inline constexpr std::uint32_t kRangeStdMaxRaw = 0xFFFF;
inline constexpr std::uint32_t kRadialVelocityStdMaxRaw = 0xFFF;
inline constexpr std::uint32_t kAngleStdMaxRaw = 0x3FFF;

/// Header status bits.
namespace status {
inline constexpr std::uint8_t kOwnshipInvalid = 0x01;  ///< ownship state stale or missing
inline constexpr std::uint8_t kOverrun = 0x02;         ///< the previous frame missed its deadline
inline constexpr std::uint8_t kTruncated = 0x04;       ///< more detections than the list carries
inline constexpr std::uint8_t kDropped = 0x08;  ///< some detections were outside the ICD ranges
/// The fidelity governor computed the frame below the scenario's fidelity to hold its deadline.
inline constexpr std::uint8_t kDegraded = 0x10;
}  // namespace status

/// One detection in ICD units (the edge of the system: degrees and dB live here).
struct Detection {
  double range_m = 0.0;              ///< slant range [m], 0 .. kMaxRange_m
  double azimuth_deg = 0.0;          ///< from antenna boresight, positive right [deg]
  double elevation_deg = 0.0;        ///< from antenna boresight, positive up [deg]
  double radial_velocity_mps = 0.0;  ///< range rate, positive receding [m/s]
  double snr_db = 0.0;               ///< measured signal-to-noise ratio [dB]
  double rcs_dbsm = 0.0;             ///< RCS estimate [dBsm]
  // Carried on CAN FD only (the classic encoder ignores them; the classic decoder leaves them 0).
  double range_std_m = 0.0;              ///< one-sigma range accuracy [m], >= 0
  double azimuth_std_deg = 0.0;          ///< one-sigma azimuth accuracy [deg], >= 0
  double elevation_std_deg = 0.0;        ///< one-sigma elevation accuracy [deg], >= 0
  double radial_velocity_std_mps = 0.0;  ///< one-sigma radial velocity accuracy [m/s], >= 0
  bool range_ambiguous = false;          ///< the waveform may have folded this range
  bool velocity_ambiguous = false;  ///< the radial velocity may be folded (|v| > v_unambiguous)
};

struct Header {
  std::uint16_t frame_counter = 0;   ///< increments by one per radar frame, wraps
  std::uint8_t detection_count = 0;  ///< detections that follow in this list
  std::uint8_t status = 0;           ///< status:: bits
  std::uint32_t time_ms = 0;         ///< radar frame time since the start of the run [ms]
};

/// Result of encoding one detection list.
struct EncodeResult {
  std::size_t frames = 0;     ///< frames written to the output span
  std::size_t encoded = 0;    ///< detections encoded
  std::size_t dropped = 0;    ///< detections rejected (NaN or outside ICD ranges)
  std::size_t truncated = 0;  ///< detections not sent for lack of space (list or span)
};

/// Encodes a header and the detections into `out` (real-time safe; no allocation). Detections
/// that are NaN or outside the ICD's ranges are dropped and flagged (status::kDropped); if more
/// than kMaxDetectionsPerFrame remain or `out` is too small, the rest are truncated
/// (status::kTruncated). The header's detection_count is what was actually encoded.
[[nodiscard]] EncodeResult encode(Header header, std::span<const Detection> detections,
                                  std::span<CanFrame> out) noexcept;

/// Frames needed for `n` detections: 1 + 2 n.
[[nodiscard]] constexpr std::size_t frames_for(std::size_t n) noexcept {
  return 1 + 2 * n;
}

/// Encodes the same list as encode() on CAN FD (48-byte header frame 0x70B with detections 0-1,
/// then 64-byte frames 0x70C with three detections each; all FD with BRS). Carries the
/// accuracies and ambiguity flags too. Real-time safe (no allocation). Drops what encode()
/// drops, plus detections whose accuracies are NaN or negative (status::kDropped); accuracies
/// above their field saturate. Truncates past kMaxDetectionsPerFrame or what `out` holds
/// (status::kTruncated). Unused slots of the last frame are zero.
[[nodiscard]] EncodeResult encode_fd(Header header, std::span<const Detection> detections,
                                     std::span<CanFrame> out) noexcept;

/// CAN FD frames needed for `n` detections: 1 + ceil(max(n - 2, 0) / 3).
[[nodiscard]] constexpr std::size_t frames_for_fd(std::size_t n) noexcept {
  return n <= kFdHeaderSlots
             ? 1
             : 1 + (n - kFdHeaderSlots + kFdContinuationSlots - 1) / kFdContinuationSlots;
}

/// A received detection list.
struct DetectionList {
  Header header{};
  std::array<Detection, kMaxDetectionsPerFrame> detections{};
  std::size_t count = 0;  ///< equals header.detection_count when complete
  bool fd = false;        ///< received on CAN FD: accuracies and ambiguity flags are valid
};

enum class FeedStatus : std::uint8_t {
  kIgnored = 0,  ///< not an ICD identifier
  kConsumed,     ///< part of a list still being assembled
  kComplete,     ///< a list is complete: read it with list()
  kMalformed,    ///< wrong length or kind, bad index/slot count, counter mismatch (counted)
  kOrphan,       ///< detection frame without a header of its kind (counted)
};

/// Reassembles detection lists from frames (the avionics side), classic and CAN FD alike: a
/// header of either kind starts a list; a detection frame of the other kind than the list in
/// progress is an orphan. Real-time safe.
class ListDecoder {
 public:
  [[nodiscard]] FeedStatus feed(const CanFrame& frame) noexcept;
  [[nodiscard]] const DetectionList& list() const noexcept { return list_; }
  [[nodiscard]] std::uint64_t malformed() const noexcept { return malformed_; }
  [[nodiscard]] std::uint64_t orphans() const noexcept { return orphans_; }
  [[nodiscard]] std::uint64_t incomplete_lists() const noexcept { return incomplete_; }

 private:
  [[nodiscard]] FeedStatus feed_classic(const CanFrame& frame) noexcept;
  [[nodiscard]] FeedStatus feed_fd(const CanFrame& frame) noexcept;

  DetectionList list_{};
  bool in_list_ = false;
  // Classic: per detection, bit 0 A seen, bit 1 B seen. FD: per continuation frame, bit 0 seen.
  std::array<std::uint8_t, kMaxDetectionsPerFrame> have_{};
  std::size_t parts_seen_ = 0;
  std::size_t parts_expected_ = 0;
  std::uint64_t malformed_ = 0;
  std::uint64_t orphans_ = 0;
  std::uint64_t incomplete_ = 0;
};

}  // namespace radar_emu::io::icd
