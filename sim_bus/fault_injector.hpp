#pragma once
// Seeded, deterministic fault injection for the software buses (issue 6): a faulty CAN link on
// the receiving side (drop, delay with jitter, corruption, reordering, duplication), a stale
// sender (silent or frozen in a time window), a babbling node and a faulty register bank.
//
// Determinism: every random decision comes from a std::mt19937_64 owned by the injector and
// seeded from its config's `seed` (the engine's sequence is fixed by the C++ standard,
// [rand.eng.mers]; the conversions below use only its raw 64-bit output), so the same seed, the
// same input frames and the same advance_to() calls give the same faults on every machine.
// No global state. Print the seed: it is all one needs to reproduce a run.

#include <array>
#include <cstddef>
#include <cstdint>
#include <limits>
#include <random>
#include <span>
#include <vector>

#include "io/can_frame.hpp"
#include "io/register_bank.hpp"

namespace radar_emu::sim_bus {

/// Most bits one corruption flips.
inline constexpr std::uint32_t kMaxCorruptBits = 16;

/// Random decisions for the injectors: a std::mt19937_64 and portable conversions of its
/// output (the standard's distributions are implementation-defined; these are not).
class FaultRandom {
 public:
  explicit FaultRandom(std::uint64_t seed) noexcept : engine_(seed) {}
  /// Uniform in [0, 1), 53 random bits. Real-time safe.
  [[nodiscard]] double uniform() noexcept {
    return static_cast<double>(engine_() >> 11) * 0x1.0p-53;
  }
  /// True with probability `p` (no draw when p <= 0). Real-time safe.
  [[nodiscard]] bool chance(double p) noexcept { return p > 0.0 && uniform() < p; }
  /// Uniform integer in [0, n), n > 0 (modulo bias below n / 2^64). Real-time safe.
  [[nodiscard]] std::uint64_t below(std::uint64_t n) noexcept { return engine_() % n; }

 private:
  std::mt19937_64 engine_;
};

/// Flips `bits` (1..kMaxCorruptBits) distinct bits drawn uniformly among the frame's identifier
/// bits (11 or 29), its 4 DLC bits (only when `len` is a valid length for the frame's kind) and
/// its payload bits. The IDE/FDF/BRS flags are left alone. A DLC flip changes `len` through the
/// DLC coding of ISO 11898-1:2015 (classic: codes 9..15 mean 8 bytes; FD: 9..15 mean 12, 16,
/// 20, 24, 32, 48, 64 bytes); bytes past the new length are zero. The result always differs
/// from the input (a draw whose flips change nothing, possible only through the classic DLC's
/// 9..15 = 8 aliasing, is redrawn). Returns the number of bits flipped. Real-time safe.
///
/// On a real bus the CRC catches practically all such errors and the frame is retransmitted:
/// classic CAN's 15-bit CRC has Hamming distance 6 (any 5 random bit errors, any odd number,
/// bursts up to 15 bits; Bosch CAN Specification 2.0, 1991), CAN FD uses 17 or 21 bits. The
/// injector delivers them anyway: they stand for errors the CRC cannot see (a faulty gateway,
/// controller or sender software) and exercise the decoders' range and consistency checks.
std::uint32_t corrupt_frame(io::CanFrame& frame, std::uint32_t bits, FaultRandom& random) noexcept;

// ---- FaultyCanLink -----------------------------------------------------------------------

/// Faults on the receiving side of a CAN link. Plain value type; SI units. Field names are the
/// scenario's `[faults]` keys.
struct FaultConfig {
  double drop_probability = 0.0;  ///< probability that a frame is lost [0, 1]
  /// Added latency [s], >= 0: a frame stamped t (its transmission time) is received at
  /// t + delay_s + u, u uniform in [-jitter_s, +jitter_s] (uniform, not Gaussian: the bound is
  /// hard). Released by advance_to() once due, in due order.
  double delay_s = 0.0;
  double jitter_s = 0.0;               ///< half-width of the uniform jitter [s], 0 .. delay_s
  double corrupt_probability = 0.0;    ///< probability that a frame is corrupted [0, 1]
  std::uint32_t corrupt_max_bits = 1;  ///< a corruption flips 1..this bits, uniform [1, 16]
  double reorder_probability = 0.0;    ///< probability that a frame swaps with the next one [0, 1]
  double duplicate_probability = 0.0;  ///< probability that a frame is received twice [0, 1]
  std::uint64_t seed = 1;              ///< generator seed
  std::size_t max_held_frames = 4096;  ///< capacity of the delay queue [frames], >= 1
};

/// Throws std::invalid_argument("faults.FIELD: expected ..., got ...") for a bad field (setup).
void validate(const FaultConfig& config);

/// True when `config` injects nothing (the link is then a bit-identical pass-through).
[[nodiscard]] bool no_faults(const FaultConfig& config) noexcept;

/// What a FaultyCanLink did. Conservation: frames_in - dropped + duplicated - held_overflow ==
/// frames_out + FaultyCanLink::held().
struct FaultCounters {
  std::uint64_t frames_in = 0;      ///< frames taken from the inner endpoint
  std::uint64_t frames_out = 0;     ///< frames handed to the caller
  std::uint64_t dropped = 0;        ///< frames lost on purpose
  std::uint64_t delayed = 0;        ///< frames (copies included) that went through the delay queue
  std::uint64_t corrupted = 0;      ///< frames with bits flipped
  std::uint64_t reordered = 0;      ///< swaps made: a frame delivered after its successor
  std::uint64_t duplicated = 0;     ///< extra copies delivered
  std::uint64_t held_overflow = 0;  ///< frames lost because the delay queue was full
};

/// A CanEndpoint decorator that applies FaultConfig to everything `inner` receives. Stages, in
/// this order, for each frame taken from `inner`: drop; corrupt; reorder (the frame is held
/// until the next frame has passed, or until the second advance_to() after it was held if none
/// comes, so a quiet bus never keeps it forever); duplicate (the copy follows at once); delay.
/// With delay_s == 0 frames are delivered as soon as they pass, and with no_faults() the link
/// is a bit-identical pass-through. With delay_s > 0 every frame goes through a bounded priority
/// queue keyed by due time (ties in arrival order), is released when advance_to() has passed
/// its due time, and is delivered stamped with that due time (its reception time). Release
/// granularity is therefore the caller's advance_to() cadence (the loop's frame period).
/// send() is forwarded unchanged: faults act on the receiving side only.
/// Resource (non-copyable); everything is allocated in the constructor.
class FaultyCanLink final : public io::CanEndpoint {
 public:
  /// Validates `config` (throws std::invalid_argument, see validate()) and preallocates.
  /// `inner` must outlive the link.
  FaultyCanLink(io::CanEndpoint& inner, const FaultConfig& config);
  FaultyCanLink(const FaultyCanLink&) = delete;
  FaultyCanLink& operator=(const FaultyCanLink&) = delete;

  /// Sets the link's clock to `now_ns` (bus time [ns]; calls going backwards are ignored):
  /// delayed frames due at or before it become receivable. Call once per loop frame, before
  /// draining. Real-time safe.
  void advance_to(std::int64_t now_ns) noexcept;

  /// Forwards to inner.send(). Real-time safe.
  [[nodiscard]] bool send(const io::CanFrame& frame) noexcept override;
  /// Next frame after the faults, or false when none is due. Real-time safe.
  [[nodiscard]] bool receive(io::CanFrame& out) noexcept override;

  [[nodiscard]] const FaultCounters& counters() const noexcept { return counters_; }
  /// Frames inside the link: delay queue, ready queue and the one held for a swap.
  [[nodiscard]] std::size_t held() const noexcept {
    return heap_size_ + ready_size_ + (swap_held_ ? 1u : 0u);
  }
  [[nodiscard]] const FaultConfig& config() const noexcept { return config_; }
  [[nodiscard]] std::int64_t now_ns() const noexcept { return now_ns_; }

 private:
  struct Due {
    std::int64_t due_ns;
    std::uint64_t sequence;  // arrival order, breaks ties
    std::uint32_t slot;      // index into pool_
  };
  void process(const io::CanFrame& frame) noexcept;
  // Passes `frame` to the duplicate and delay stages; returns the due time given to it.
  std::int64_t emit(const io::CanFrame& frame, std::int64_t not_before_ns) noexcept;
  std::int64_t enqueue(const io::CanFrame& frame, std::int64_t not_before_ns) noexcept;
  bool push_ready(const io::CanFrame& frame) noexcept;
  bool push_due(const io::CanFrame& frame, std::int64_t due_ns) noexcept;
  static bool earlier(const Due& a, const Due& b) noexcept {
    return a.due_ns < b.due_ns || (a.due_ns == b.due_ns && a.sequence < b.sequence);
  }

  io::CanEndpoint* inner_;
  FaultConfig config_;
  FaultRandom random_;
  bool delay_enabled_;
  std::int64_t now_ns_ = std::numeric_limits<std::int64_t>::min();
  std::uint64_t advances_ = 0;
  std::uint64_t sequence_ = 0;
  // Delay queue: binary min-heap of Due over a frame pool with a free-slot stack.
  std::vector<io::CanFrame> pool_;
  std::vector<std::uint32_t> free_;
  std::size_t free_size_ = 0;
  std::vector<Due> heap_;
  std::size_t heap_size_ = 0;
  // Frames ready now (no delay configured): a small ring (one input yields at most 3).
  std::array<io::CanFrame, 8> ready_{};
  std::size_t ready_head_ = 0;
  std::size_t ready_size_ = 0;
  // Reorder stage.
  io::CanFrame swap_frame_{};
  bool swap_held_ = false;
  std::uint64_t swap_advance_ = 0;
  FaultCounters counters_{};
};

// ---- StaleSender -------------------------------------------------------------------------

enum class StaleMode : std::uint8_t {
  kSilent = 0,   ///< the node sends nothing in the window
  kFrozen,       ///< replays its last frame per key unchanged: value and message code frozen
  kFrozenValue,  ///< replays its last payload per key with the live message code (byte 3)
};

/// A stale sender's window. Plain value type.
struct StaleConfig {
  StaleMode mode = StaleMode::kSilent;
  double start_s = 0.0;       ///< window start, scenario time [s] (inclusive)
  double end_s = 0.0;         ///< window end, scenario time [s] (exclusive), >= start_s
  std::int64_t epoch_ns = 0;  ///< bus time stamp of scenario time 0 [ns]
  std::size_t max_keys = 64;  ///< distinct keys remembered for replay, >= 1
};

struct StaleCounters {
  std::uint64_t passed = 0;      ///< frames forwarded unchanged (outside the window)
  std::uint64_t suppressed = 0;  ///< frames not sent (silent window, or frozen with no last frame)
  std::uint64_t replayed = 0;    ///< frames replaced by the key's last frame (frozen window)
  std::uint64_t keys_overflow = 0;  ///< frames whose key did not fit in max_keys (not stored)
};

/// A CanEndpoint decorator for the sending side (wrap the INS player's endpoint): outside
/// [start_s, end_s) it forwards every frame; inside, by the frame's own timestamp_ns, it sends
/// nothing (kSilent) or, for each frame, the last frame sent before with the same key
/// (identifier, IDE flag, and byte 1 when len >= 2 — CANaerospace's data-type byte, v1.7 sec.
/// 4.1, so that a DOUBLEH and a DOUBLEL on one identifier each replay their own half), stamped
/// with the new frame's time. kFrozenValue copies the new frame's byte 3 (the CANaerospace
/// message code, sec. 4.1.4) into the replay: the node's bus interface is alive but its data
/// stuck, which the message-code check cannot see; kFrozen repeats the code too (counted as
/// message-code gaps by the decoder). A key never sent before the window is suppressed.
/// Suppressed frames still return true from send(): the node believes it sent them.
/// receive() is forwarded unchanged. Resource (non-copyable).
class StaleSender final : public io::CanEndpoint {
 public:
  /// Throws std::invalid_argument("stale.FIELD: ...") for a bad config. `inner` must outlive it.
  StaleSender(io::CanEndpoint& inner, const StaleConfig& config);
  StaleSender(const StaleSender&) = delete;
  StaleSender& operator=(const StaleSender&) = delete;

  /// Real-time safe.
  [[nodiscard]] bool send(const io::CanFrame& frame) noexcept override;
  /// Forwards to inner.receive(). Real-time safe.
  [[nodiscard]] bool receive(io::CanFrame& out) noexcept override;

  [[nodiscard]] const StaleCounters& counters() const noexcept { return counters_; }
  [[nodiscard]] const StaleConfig& config() const noexcept { return config_; }
  /// True when a frame stamped `timestamp_ns` falls in the window.
  [[nodiscard]] bool in_window(std::int64_t timestamp_ns) const noexcept {
    return timestamp_ns >= start_ns_ && timestamp_ns < end_ns_;
  }

 private:
  struct Key {
    std::uint32_t id;
    bool extended;
    std::int32_t type;  // byte 1, or -1 when len < 2
  };
  static Key key_of(const io::CanFrame& frame) noexcept;
  io::CanEndpoint* inner_;
  StaleConfig config_;
  std::int64_t start_ns_;
  std::int64_t end_ns_;
  std::vector<Key> keys_;
  std::vector<io::CanFrame> last_;
  std::size_t key_count_ = 0;
  StaleCounters counters_{};
};

// ---- BabblingNode ------------------------------------------------------------------------

/// A node that floods the bus. Plain value type.
struct BabbleConfig {
  std::uint32_t id =
      0;  ///< identifier; low = high priority (CANaerospace emergency events: 0..127)
  bool extended = false;  ///< 29-bit identifier
  std::uint8_t len = 8;   ///< payload bytes, 0..8 (bytes 0..3: a big-endian frame counter)
  /// Frames per second while babbling, > 0. For scale: a 1 Mbit/s classic bus carries at most
  /// about 1e6 / 111 = 9000 frames/s of 8 bytes (111 bits unstuffed, docs/icd/detections.md);
  /// the loopback bus has no bit-rate limit, only its bounded queues.
  double rate_hz = 10'000.0;
  double start_s = 0.0;                                    ///< scenario time [s] (inclusive)
  double end_s = std::numeric_limits<double>::infinity();  ///< scenario time [s] (exclusive)
  std::int64_t epoch_ns = 0;                  ///< bus time stamp of scenario time 0 [ns]
  std::size_t max_frames_per_call = 100'000;  ///< work bound per call; excess skipped (counted)
};

struct BabbleCounters {
  std::uint64_t sent = 0;           ///< frames the bus took
  std::uint64_t send_failures = 0;  ///< frames the bus refused
  std::uint64_t skipped = 0;        ///< frames due but over max_frames_per_call (never sent)
};

class BabblingNode {
 public:
  /// Throws std::invalid_argument("babble.FIELD: ...") for a bad config.
  explicit BabblingNode(const BabbleConfig& config);

  /// Sends every frame due at scenario times <= `time_s` inside the window, each stamped with
  /// its due time; at most max_frames_per_call, the rest are skipped (no catch-up burst).
  /// Returns frames sent. Real-time safe.
  std::size_t publish_until(double time_s, io::CanEndpoint& bus) noexcept;
  /// Sends `frames` frames at once, stamped `timestamp_ns` (ignores the window and rate).
  /// Returns frames sent. Real-time safe.
  std::size_t send_burst(io::CanEndpoint& bus, std::int64_t timestamp_ns,
                         std::size_t frames) noexcept;

  [[nodiscard]] const BabbleCounters& counters() const noexcept { return counters_; }

 private:
  bool send_one(io::CanEndpoint& bus, std::int64_t timestamp_ns) noexcept;
  BabbleConfig config_;
  std::uint64_t next_index_ = 0;  // next frame of the schedule, counted from start_s
  std::uint32_t counter_ = 0;     // payload counter
  BabbleCounters counters_{};
};

// ---- FaultyRegisterBank ------------------------------------------------------------------

/// Faults on a register transport. Plain value type; field names are the scenario's keys.
struct RegisterFaultConfig {
  double timeout_probability = 0.0;    ///< a transaction is lost: kTimeout, inner not called [0, 1]
  double corrupt_probability = 0.0;    ///< a successful read returns flipped bits [0, 1]
  std::uint32_t corrupt_max_bits = 1;  ///< bits flipped per corrupted read, uniform [1, 16]
  double frozen_start_s = 0.0;         ///< reads in [frozen_start_s, frozen_end_s) return the last
  double frozen_end_s = 0.0;           ///< image read before (scenario time [s]); empty by default
  std::int64_t epoch_ns = 0;           ///< bus time of scenario time 0 [ns]
  std::uint64_t seed = 1;              ///< generator seed
};

struct RegisterFaultCounters {
  std::uint64_t reads = 0;           ///< read_holding calls
  std::uint64_t writes = 0;          ///< write_holding calls
  std::uint64_t timeouts = 0;        ///< transactions answered kTimeout by the injector
  std::uint64_t corrupted = 0;       ///< reads returned with flipped bits
  std::uint64_t frozen_reads = 0;    ///< reads answered from the last image
  std::uint64_t frozen_unknown = 0;  ///< frozen reads of never-read registers (kTimeout)
};

/// A RegisterBank decorator. Per transaction, in order: timeout (drop); in the frozen window a
/// read returns the last image of those registers (the device stalls; writes still pass) and
/// kTimeout if some were never read; otherwise the call goes to `inner`, and a successful read
/// is recorded as the image and then corrupted with corrupt_probability. It blocks exactly when
/// `inner` does. Resource (non-copyable); allocates its 64 Ki-register image up front.
class FaultyRegisterBank final : public io::RegisterBank {
 public:
  /// Throws std::invalid_argument("register_faults.FIELD: ...") for a bad config.
  FaultyRegisterBank(io::RegisterBank& inner, const RegisterFaultConfig& config);
  FaultyRegisterBank(const FaultyRegisterBank&) = delete;
  FaultyRegisterBank& operator=(const FaultyRegisterBank&) = delete;

  /// Sets the injector's clock (bus time [ns]) for the frozen window. Real-time safe.
  void advance_to(std::int64_t now_ns) noexcept { now_ns_ = now_ns; }

  [[nodiscard]] io::RegisterStatus read_holding(std::uint16_t address,
                                                std::span<std::uint16_t> out) noexcept override;
  [[nodiscard]] io::RegisterStatus write_holding(
      std::uint16_t address, std::span<const std::uint16_t> values) noexcept override;

  [[nodiscard]] const RegisterFaultCounters& counters() const noexcept { return counters_; }
  [[nodiscard]] bool frozen() const noexcept {
    return now_ns_ >= frozen_start_ns_ && now_ns_ < frozen_end_ns_;
  }

 private:
  io::RegisterBank* inner_;
  RegisterFaultConfig config_;
  FaultRandom random_;
  std::int64_t frozen_start_ns_;
  std::int64_t frozen_end_ns_;
  std::int64_t now_ns_ = 0;
  std::vector<std::uint16_t> image_;  // last value read per address
  std::vector<std::uint8_t> known_;   // 1 where image_ holds a value
  RegisterFaultCounters counters_{};
};

}  // namespace radar_emu::sim_bus
