#include "io/can_error.hpp"

#include <linux/can.h>
#include <linux/can/error.h>

namespace radar_emu::io {

std::string_view to_string(CanBusState state) noexcept {
  switch (state) {
    case CanBusState::kUnknown:
      return "unknown";
    case CanBusState::kErrorActive:
      return "error-active";
    case CanBusState::kErrorWarning:
      return "error-warning";
    case CanBusState::kErrorPassive:
      return "error-passive";
    case CanBusState::kBusOff:
      return "bus-off";
    case CanBusState::kStopped:
      return "stopped";
  }
  return "unknown";
}

bool CanErrorTracker::on_error_frame(std::uint32_t can_id,
                                     std::span<const std::uint8_t, 8> data) noexcept {
  if ((can_id & CAN_ERR_FLAG) == 0)
    return false;
  ++counters_.error_frames;
  const std::uint32_t cls = can_id & CAN_ERR_MASK;

  // Classes and their data bytes: linux/can/error.h (the comment beside each CAN_ERR_* class).
  if (cls & CAN_ERR_TX_TIMEOUT)
    ++counters_.tx_timeouts;
  if (cls & CAN_ERR_LOSTARB) {
    ++counters_.lost_arbitration;
    counters_.last_lostarb_bit = data[0];
  }
  if (cls & CAN_ERR_CRTL) {
    ++counters_.controller;
    const std::uint8_t c = data[1];
    if (c & CAN_ERR_CRTL_RX_OVERFLOW)
      ++counters_.rx_overflows;
    if (c & CAN_ERR_CRTL_TX_OVERFLOW)
      ++counters_.tx_overflows;
    // The kernel (drivers/net/can/dev/dev.c, can_change_state) sets the bits of the more severe
    // of the TX and RX states, so the most severe bit present is the new state.
    if (c & (CAN_ERR_CRTL_RX_PASSIVE | CAN_ERR_CRTL_TX_PASSIVE)) {
      ++counters_.error_passive;
      state_ = CanBusState::kErrorPassive;
    } else if (c & (CAN_ERR_CRTL_RX_WARNING | CAN_ERR_CRTL_TX_WARNING)) {
      ++counters_.error_warning;
      state_ = CanBusState::kErrorWarning;
    } else if (c & CAN_ERR_CRTL_ACTIVE) {
      ++counters_.back_to_active;
      state_ = CanBusState::kErrorActive;
    }
  }
  if (cls & CAN_ERR_PROT) {
    ++counters_.protocol_errors;
    counters_.last_protocol_type = data[2];
    counters_.last_protocol_location = data[3];
  }
  if (cls & CAN_ERR_TRX) {
    ++counters_.transceiver_errors;
    counters_.last_transceiver = data[4];
  }
  if (cls & CAN_ERR_ACK)
    ++counters_.no_ack;
  if (cls & CAN_ERR_BUSERROR)
    ++counters_.bus_errors;
  if (cls & CAN_ERR_BUSOFF) {
    ++counters_.bus_off;
    state_ = CanBusState::kBusOff;
  }
  if (cls & CAN_ERR_RESTARTED) {  // after bus-off: back to error active (can_restart in dev.c)
    ++counters_.restarted;
    state_ = CanBusState::kErrorActive;
  }
#ifdef CAN_ERR_CNT
  if (cls & CAN_ERR_CNT) {
    counters_.tx_error_counter = data[6];
    counters_.rx_error_counter = data[7];
  }
#endif
  return true;
}

}  // namespace radar_emu::io
