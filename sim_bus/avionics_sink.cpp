#include "sim_bus/avionics_sink.hpp"

namespace radar_emu::sim_bus {

AvionicsSink::AvionicsSink(std::size_t max_lists) : max_lists_(max_lists) {
  lists_.reserve(max_lists);
}

std::size_t AvionicsSink::poll(io::CanEndpoint& bus) noexcept {
  std::size_t completed_now = 0;
  io::CanFrame frame;
  while (bus.receive(frame)) {
    ++frames_;
    switch (decoder_.feed(frame)) {
      case io::icd::FeedStatus::kComplete:
        ++completed_;
        ++completed_now;
        if (lists_.size() < max_lists_) {
          lists_.push_back(decoder_.list());  // capacity reserved: no allocation
        } else {
          ++not_stored_;
        }
        break;
      case io::icd::FeedStatus::kIgnored:
        ++ignored_;
        break;
      case io::icd::FeedStatus::kConsumed:
      case io::icd::FeedStatus::kMalformed:
      case io::icd::FeedStatus::kOrphan:
        break;  // counted by the decoder
    }
  }
  return completed_now;
}

}  // namespace radar_emu::sim_bus
