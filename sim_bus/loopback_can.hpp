#pragma once
// An in-process CAN bus: every frame one endpoint sends is delivered, in send order, to every
// other endpoint (as on a real bus, a node does not receive its own frames). Single-threaded
// and deterministic: the same sends in the same order give the same receptions.

#include <cstddef>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "io/can_frame.hpp"

namespace radar_emu::sim_bus {

class LoopbackCanBus;

/// One node's connection to the loopback bus, with a bounded receive queue.
class LoopbackEndpoint final : public io::CanEndpoint {
 public:
  [[nodiscard]] bool send(const io::CanFrame& frame) noexcept override;
  [[nodiscard]] bool receive(io::CanFrame& out) noexcept override;

  [[nodiscard]] const std::string& name() const noexcept { return name_; }
  [[nodiscard]] std::size_t pending() const noexcept { return size_; }
  /// Frames lost because this endpoint's receive queue was full.
  [[nodiscard]] std::uint64_t rx_overflows() const noexcept { return rx_overflows_; }
  [[nodiscard]] std::uint64_t sent() const noexcept { return sent_; }
  [[nodiscard]] std::uint64_t received() const noexcept { return received_; }

 private:
  friend class LoopbackCanBus;
  LoopbackEndpoint(LoopbackCanBus& bus, std::string name, std::size_t queue_capacity);
  bool push(const io::CanFrame& frame) noexcept;

  LoopbackCanBus* bus_;
  std::string name_;
  std::vector<io::CanFrame> ring_;
  std::size_t head_ = 0;
  std::size_t size_ = 0;
  std::uint64_t rx_overflows_ = 0;
  std::uint64_t sent_ = 0;
  std::uint64_t received_ = 0;
};

class LoopbackCanBus {
 public:
  LoopbackCanBus() = default;
  LoopbackCanBus(const LoopbackCanBus&) = delete;
  LoopbackCanBus& operator=(const LoopbackCanBus&) = delete;

  /// Adds a node (setup). The reference stays valid for the bus's lifetime.
  LoopbackEndpoint& add_endpoint(std::string name, std::size_t queue_capacity = 4096);

  /// Frames carried since the start.
  [[nodiscard]] std::uint64_t frames_carried() const noexcept { return frames_carried_; }

 private:
  friend class LoopbackEndpoint;
  void deliver(const LoopbackEndpoint& from, const io::CanFrame& frame) noexcept;

  std::vector<std::unique_ptr<LoopbackEndpoint>> endpoints_;
  std::uint64_t frames_carried_ = 0;
};

}  // namespace radar_emu::sim_bus
