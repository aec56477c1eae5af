#pragma once
// Where the loop's ownship state comes from, chosen once at setup (RunOptions::nav_modbus):
// CANaerospace on the CAN bus, the Modbus navigation register map played on the loopback
// register bank, or an external Modbus server polled by a background thread. The frame reads
// it with one call, OwnshipSource::read(), whatever the source.
//
// A std::variant, not a virtual base: the set is closed (the three sources the CLI names), each
// reports different counters (report.json "nav_modbus") so the report must know which one ran,
// and the sources live in place in the loop, with no heap indirection on the frame path.

#include <atomic>
#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <utility>
#include <variant>
#include <vector>

#include "io/canaerospace.hpp"
#include "io/modbus.hpp"
#include "io/modbus_map.hpp"
#include "loop/outputs/report.hpp"
#include "sim_bus/fault_injector.hpp"
#include "sim_bus/loopback_registers.hpp"

namespace radar_emu::loop {

/// CANaerospace on the CAN bus: the state the bus's decoder holds (the bus is read and decoded
/// every frame whatever the source).
class CanAerospaceSource {
 public:
  explicit CanAerospaceSource(const io::canas::Decoder& decoder) noexcept : decoder_(&decoder) {}
  /// Real-time safe.
  [[nodiscard]] const io::canas::OwnshipState& read(std::int64_t /*bus_now_ns*/) noexcept {
    return decoder_->state();
  }

 private:
  const io::canas::Decoder* decoder_;
};

/// The navigation register map on the loopback register bank ("--nav-modbus sim"), read once a
/// frame through the scenario's faults (a lost frame is a lost transaction, a stale INS a frozen
/// register image: sim_bus/fault_injector.hpp). The simulated INS writes into bank().
class RegisterBankSource {
 public:
  /// Setup: allocates the bank and the register buffer.
  RegisterBankSource(const io::modbus::NavMapConfig& map,
                     const sim_bus::RegisterFaultConfig& faults);
  /// Reads the bank at bus time `bus_now_ns` [ns] and decodes it; a failed read keeps the last
  /// state (counted). Real-time safe.
  [[nodiscard]] const io::canas::OwnshipState& read(std::int64_t bus_now_ns) noexcept;
  [[nodiscard]] sim_bus::LoopbackRegisterBank& bank() noexcept { return *bank_; }
  [[nodiscard]] NavSourceReport report() const;

 private:
  io::modbus::NavMapConfig map_;
  std::vector<std::uint16_t> regs_;  ///< the map's registers, read every frame
  std::unique_ptr<sim_bus::LoopbackRegisterBank> bank_;
  std::unique_ptr<sim_bus::FaultyRegisterBank> faulty_;  ///< the radar's side of the bank
  io::modbus::NavDecoder decoder_{};
  std::uint64_t read_failures_ = 0;
};

/// An external Modbus TCP/RTU navigation server ("--nav-modbus tcp:HOST:PORT" or "rtu:DEV:BAUD"),
/// polled by a background thread; the frame takes its latest state. The source's state changes
/// are printed on stderr from the poller's thread.
class PollerSource {
 public:
  /// Setup: connects (in the background) and starts the poller. `bus_from_monotonic_ns`: bus
  /// time minus CLOCK_MONOTONIC [ns], set when the run begins; must outlive this source.
  PollerSource(const std::string& endpoint, const io::modbus::NavMapConfig& map,
               const std::atomic<std::int64_t>& bus_from_monotonic_ns);
  /// The latest decoded state; counts the frames run while the source is not answering.
  /// Real-time safe (wait-free).
  [[nodiscard]] const io::canas::OwnshipState& read(std::int64_t bus_now_ns) noexcept;
  [[nodiscard]] NavSourceReport report() const;
  /// "" unless the source never answered during the run (ClosedLoop::nav_source_failure()).
  [[nodiscard]] std::string failure() const;

 private:
  std::string endpoint_;
  std::unique_ptr<io::modbus::ModbusClient> client_;
  std::unique_ptr<io::modbus::NavPoller> poller_;
  double retry_max_s_ = 0.0;              ///< the client's back-off ceiling (retry period) [s]
  std::uint64_t frames_source_down_ = 0;  ///< frames run while the source did not answer
  io::canas::OwnshipState state_{};       ///< last state from the poller
};

/// The ownship source of a run, one of the three, chosen at setup.
class OwnshipSource {
 public:
  using Source = std::variant<CanAerospaceSource, RegisterBankSource, PollerSource>;
  /// CANaerospace from `decoder`.
  explicit OwnshipSource(const io::canas::Decoder& decoder)
      : source_(std::in_place_type<CanAerospaceSource>, decoder) {}
  /// Replaces the source (setup only).
  template <class S, class... Args>
  S& emplace(Args&&... args) {
    return source_.emplace<S>(std::forward<Args>(args)...);
  }
  /// The ownship state at bus time `bus_now_ns` [ns]. Real-time safe.
  [[nodiscard]] const io::canas::OwnshipState& read(std::int64_t bus_now_ns) noexcept {
    return std::visit(
        [bus_now_ns](auto& s) -> const io::canas::OwnshipState& { return s.read(bus_now_ns); },
        source_);
  }
  /// Whether the state comes from a bus only a wall clock can drive (the poller).
  [[nodiscard]] bool external() const noexcept {
    return std::holds_alternative<PollerSource>(source_);
  }
  /// report.json "nav_modbus" (nullopt for CANaerospace).
  [[nodiscard]] std::optional<NavSourceReport> report() const;
  /// See PollerSource::failure() ("" for the other sources).
  [[nodiscard]] std::string failure() const;

 private:
  Source source_;
};

}  // namespace radar_emu::loop
