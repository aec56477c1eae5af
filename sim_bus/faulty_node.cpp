#include "sim_bus/faulty_node.hpp"

#include <limits>

#include "io/canaerospace.hpp"

namespace radar_emu::sim_bus {

void FaultyNode::send_next(io::CanEndpoint& bus, std::int64_t timestamp_ns) noexcept {
  namespace canas = io::canas;
  const auto kind = static_cast<MalformedKind>(next_);
  io::CanFrame f;
  switch (kind) {
    case MalformedKind::kShortDlc:
      f = canas::encode_float(canas::id::kPitchAngle, node_id_, message_code_, 1.0f);
      f.len = 3;
      break;
    case MalformedKind::kUnknownDataType:
      f = canas::encode_float(canas::id::kRollAngle, node_id_, message_code_, 1.0f);
      f.data[1] = 77;
      break;
    case MalformedKind::kNotANumber:
      f = canas::encode_float(canas::id::kPitchAngle, node_id_, message_code_,
                              std::numeric_limits<float>::quiet_NaN());
      break;
    case MalformedKind::kOutOfRange:
      f = canas::encode_float(canas::id::kGpsLatitude, node_id_, message_code_, 123.0f);
      break;
    case MalformedKind::kCount:
      return;
  }
  f.timestamp_ns = timestamp_ns;
  if (bus.send(f))
    ++sent_[next_];
  ++message_code_;
  next_ = (next_ + 1) % kMalformedKindCount;
}

}  // namespace radar_emu::sim_bus
