#include "sim_bus/loopback_can.hpp"

#include <stdexcept>
#include <utility>

namespace radar_emu::sim_bus {

LoopbackEndpoint::LoopbackEndpoint(LoopbackCanBus& bus, std::string name,
                                   std::size_t queue_capacity)
    : bus_(&bus), name_(std::move(name)), ring_(queue_capacity) {}

bool LoopbackEndpoint::send(const io::CanFrame& frame) noexcept {
  ++sent_;
  bus_->deliver(*this, frame);
  return true;
}

bool LoopbackEndpoint::receive(io::CanFrame& out) noexcept {
  if (size_ == 0)
    return false;
  out = ring_[head_];
  head_ = (head_ + 1) % ring_.size();
  --size_;
  ++received_;
  return true;
}

bool LoopbackEndpoint::push(const io::CanFrame& frame) noexcept {
  if (size_ == ring_.size()) {
    ++rx_overflows_;
    return false;
  }
  ring_[(head_ + size_) % ring_.size()] = frame;
  ++size_;
  return true;
}

LoopbackEndpoint& LoopbackCanBus::add_endpoint(std::string name, std::size_t queue_capacity) {
  if (queue_capacity == 0) {
    throw std::invalid_argument("loopback endpoint '" + name + "': queue capacity must be > 0");
  }
  endpoints_.push_back(std::unique_ptr<LoopbackEndpoint>(
      new LoopbackEndpoint(*this, std::move(name), queue_capacity)));
  return *endpoints_.back();
}

void LoopbackCanBus::deliver(const LoopbackEndpoint& from, const io::CanFrame& frame) noexcept {
  ++frames_carried_;
  for (auto& ep : endpoints_) {
    if (ep.get() != &from)
      (void)ep->push(frame);
  }
}

}  // namespace radar_emu::sim_bus
