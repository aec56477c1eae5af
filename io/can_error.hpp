#pragma once
// CAN error frames as Linux defines them (include/uapi/linux/can/error.h): a classic frame whose
// can_id carries CAN_ERR_FLAG and a class mask (CAN_ERR_BUSOFF, CAN_ERR_CRTL, ...), with details
// in data[0..7]. SocketCAN delivers them to sockets that set CAN_RAW_ERR_FILTER; gs_usb devices
// send the same encoding over USB (drivers/net/can/usb/gs_usb.c: "The GS USB devices make use of
// the same flags and masks as in linux/can.h and linux/can/error.h"). Both backends decode them
// here into counters and a bus state; error frames never reach CanEndpoint::receive().

#include <array>
#include <cstdint>
#include <span>
#include <string_view>

namespace radar_emu::io {

/// Fault-confinement state of the local controller (ISO 11898-1: error active, error passive,
/// bus off; Linux adds "warning" at an error counter of 96, CAN_ERROR_WARNING_THRESHOLD).
enum class CanBusState : std::uint8_t {
  kUnknown = 0,   ///< nothing reported yet (e.g. a virtual interface)
  kErrorActive,   ///< normal operation
  kErrorWarning,  ///< an error counter reached 96
  kErrorPassive,  ///< an error counter exceeded 127
  kBusOff,        ///< transmit error counter exceeded 255: the node is off the bus
  kStopped,       ///< the controller is stopped (interface down, device reset)
};

[[nodiscard]] std::string_view to_string(CanBusState state) noexcept;

/// Counts of what error frames reported. Each field counts error frames carrying that report
/// (the kernel emits state reports only on a change of state).
struct CanErrorCounters {
  std::uint64_t error_frames = 0;           ///< error frames seen, of any class
  std::uint64_t tx_timeouts = 0;            ///< CAN_ERR_TX_TIMEOUT
  std::uint64_t lost_arbitration = 0;       ///< CAN_ERR_LOSTARB
  std::uint64_t controller = 0;             ///< CAN_ERR_CRTL, any detail
  std::uint64_t rx_overflows = 0;           ///< CAN_ERR_CRTL_RX_OVERFLOW (+ gs_usb overflow flag)
  std::uint64_t tx_overflows = 0;           ///< CAN_ERR_CRTL_TX_OVERFLOW
  std::uint64_t error_warning = 0;          ///< CAN_ERR_CRTL_{RX,TX}_WARNING
  std::uint64_t error_passive = 0;          ///< CAN_ERR_CRTL_{RX,TX}_PASSIVE
  std::uint64_t back_to_active = 0;         ///< CAN_ERR_CRTL_ACTIVE (recovered to error active)
  std::uint64_t protocol_errors = 0;        ///< CAN_ERR_PROT (bit, form, stuff, ... errors)
  std::uint64_t transceiver_errors = 0;     ///< CAN_ERR_TRX
  std::uint64_t no_ack = 0;                 ///< CAN_ERR_ACK (no node acknowledged our frame)
  std::uint64_t bus_off = 0;                ///< CAN_ERR_BUSOFF
  std::uint64_t bus_errors = 0;             ///< CAN_ERR_BUSERROR
  std::uint64_t restarted = 0;              ///< CAN_ERR_RESTARTED (controller restarted)
  std::uint8_t last_lostarb_bit = 0;        ///< data[0] of the last CAN_ERR_LOSTARB (0 unspecified)
  std::uint8_t last_protocol_type = 0;      ///< data[2] of the last CAN_ERR_PROT (CAN_ERR_PROT_*)
  std::uint8_t last_protocol_location = 0;  ///< data[3] of the last CAN_ERR_PROT (..._LOC_*)
  std::uint8_t last_transceiver = 0;        ///< data[4] of the last CAN_ERR_TRX
  std::uint8_t tx_error_counter = 0;        ///< data[6] of the last frame with CAN_ERR_CNT (TEC)
  std::uint8_t rx_error_counter = 0;        ///< data[7] of the last frame with CAN_ERR_CNT (REC)
};

/// Decodes error frames into counters and a bus state. Single-threaded; all calls real-time safe.
class CanErrorTracker {
 public:
  explicit CanErrorTracker(CanBusState initial = CanBusState::kUnknown) noexcept
      : state_(initial) {}

  /// Decodes one error frame: `can_id` is the raw Linux can_id (CAN_ERR_FLAG set, class bits in
  /// CAN_ERR_MASK), `data` its 8 data bytes (CAN_ERR_DLC). A frame without CAN_ERR_FLAG is
  /// ignored and false returned. Real-time safe.
  bool on_error_frame(std::uint32_t can_id, std::span<const std::uint8_t, 8> data) noexcept;
  /// A receive overflow reported outside an error frame (gs_usb GS_CAN_FLAG_OVERFLOW).
  void on_rx_overflow() noexcept { ++counters_.rx_overflows; }
  /// Sets the state from an out-of-band source (setup: libsocketcan's can_get_state, a gs_usb
  /// MODE start or reset).
  void set_state(CanBusState state) noexcept { state_ = state; }

  [[nodiscard]] CanBusState state() const noexcept { return state_; }
  [[nodiscard]] const CanErrorCounters& counters() const noexcept { return counters_; }

 private:
  CanBusState state_;
  CanErrorCounters counters_;
};

}  // namespace radar_emu::io
