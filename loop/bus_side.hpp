#pragma once
// The radar's side of the buses, bound once at setup: the software CAN loopback with every
// simulated node on it, the radar's receiving link (with the scenario's faults) or a hardware CAN
// backend, the CANaerospace decoder, the detection-list frames, and the Modbus detection table.
// The frame path receives and sends through endpoints chosen here, never testing which.
//
// Units: times in ns of bus time (Unix time of the run's epoch). Setup throws with context; the
// frame-path calls are real-time safe (no allocation, no blocking, no exceptions).

#include <atomic>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <span>
#include <string>
#include <vector>

#include "io/can_frame.hpp"
#include "io/canaerospace.hpp"
#include "io/detection_icd.hpp"
#include "io/modbus.hpp"
#include "io/modbus_map.hpp"
#include "loop/bus_backends.hpp"
#include "loop/frame_record.hpp"
#include "loop/outputs/output_stream.hpp"
#include "loop/scenario.hpp"
#include "sim_bus/fault_injector.hpp"
#include "sim_bus/loopback_can.hpp"

namespace radar_emu::loop {

class BusSide {
 public:
  /// Setup: the software bus and its nodes (in the order they have always been attached: ins,
  /// faulty, replay, radar, avionics, then the babbling node when the scenario has one), the
  /// radar's receiving link with the scenario's faults (none in a replay: the log already holds
  /// what the recording run received after its faults), the decoder and the list frames (sized
  /// for `list_frames` frames). Receives and sends on the software bus until open_can().
  BusSide(const Scenario& scenario, bool replay, std::size_t list_frames);
  BusSide(const BusSide&) = delete;
  BusSide& operator=(const BusSide&) = delete;

  /// Setup: the `--can` backend ("sim" keeps the software bus). ",fd" sets scenario.can_fd.
  /// Refuses a real bus (or `nav_modbus` other than "sim") without `realtime`, and any of them in
  /// a replay. Appends the backend's warnings. Throws std::runtime_error / invalid_argument.
  void open_can(Scenario& scenario, const std::string& can, const std::string& nav_modbus,
                bool realtime, bool replay, std::vector<std::string>& warnings);
  /// Setup: serves the detection table (`--modbus-server` spec, loop/bus_backends.hpp) for
  /// lists of up to `max_detections`. Throws with the address on failure.
  void open_table_server(const std::string& spec, std::size_t max_detections);

  /// Frame path: takes every frame received by bus time `bus_now_ns` [ns], logs it (`log` may be
  /// null), decodes it into decoder(); counts into `r`. Real-time safe.
  void receive(std::int64_t bus_now_ns, OutputStream* log, RunResult& r) noexcept;
  /// Frame path: encodes the list (`send_list` false: nothing goes on the bus, counted), sends
  /// it stamped `bus_now_ns` and logs it; publishes the Modbus table (state: every frame).
  /// Returns the encoding's result. Real-time safe.
  io::icd::EncodeResult send(const io::icd::Header& header,
                             std::span<const io::icd::Detection> list, bool send_list, bool fd,
                             std::int64_t bus_now_ns, OutputStream* log, RunResult& r) noexcept;

  [[nodiscard]] const io::canas::Decoder& decoder() const noexcept { return decoder_; }
  /// Whether bus time must be Unix time on the wall clock (a hardware CAN backend).
  [[nodiscard]] bool hardware() const noexcept { return hw_can_ != nullptr; }
  [[nodiscard]] const CanSpec& can_spec() const noexcept { return can_spec_; }
  [[nodiscard]] const io::CanEndpoint* hardware_can() const noexcept { return hw_can_.get(); }
  [[nodiscard]] const io::modbus::ModbusServer* table_server() const noexcept {
    return table_server_.get();
  }
  [[nodiscard]] const sim_bus::FaultyCanLink& link() const noexcept { return *link_; }
  /// Frames lost to full receive queues (the radar's and the avionics').
  [[nodiscard]] std::uint64_t rx_overflows() const noexcept;

  /// Bus time minus CLOCK_MONOTONIC [ns], set when a run on a real bus begins.
  std::atomic<std::int64_t> bus_from_monotonic_ns{0};

  // The software bus and its simulated nodes (the peers send and receive here).
  sim_bus::LoopbackCanBus loopback;
  sim_bus::LoopbackEndpoint& ins;
  sim_bus::LoopbackEndpoint& faulty;
  sim_bus::LoopbackEndpoint& replay;
  sim_bus::LoopbackEndpoint& radar;
  sim_bus::LoopbackEndpoint& avionics;
  sim_bus::LoopbackEndpoint* babbler = nullptr;  ///< null without a babbling node

 private:
  std::unique_ptr<sim_bus::FaultyCanLink> link_;  ///< what the radar receives through
  CanSpec can_spec_;
  std::unique_ptr<io::CanEndpoint> hw_can_;  ///< null: the software bus
  io::CanEndpoint* rx_ = nullptr;            ///< bound at setup: the link or the hardware
  io::CanEndpoint* tx_ = nullptr;            ///< bound at setup: `radar` or the hardware
  io::canas::Decoder decoder_;
  std::vector<io::CanFrame> out_frames_;  ///< one detection list
  io::modbus::DetectionTableConfig table_config_{};
  std::vector<std::uint16_t> table_regs_;
  std::unique_ptr<io::modbus::ModbusServer> table_server_;  ///< null: not serving
};

}  // namespace radar_emu::loop
