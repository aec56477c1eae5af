#include "loop/bus_side.hpp"

#include <algorithm>
#include <stdexcept>

namespace radar_emu::loop {

BusSide::BusSide(const Scenario& s, bool replay_run, std::size_t list_frames)
    : ins(loopback.add_endpoint("ins", 1 << 16)),
      faulty(loopback.add_endpoint("faulty", 16)),
      replay(loopback.add_endpoint("replay", 16)),
      radar(loopback.add_endpoint("radar", 1 << 16)),
      avionics(loopback.add_endpoint("avionics", 1 << 16)),
      decoder_(s.input),
      out_frames_(list_frames) {
  link_ = std::make_unique<sim_bus::FaultyCanLink>(
      radar, replay_run ? sim_bus::FaultConfig{} : s.link_faults);
  if (s.babbling_node && !replay_run)
    babbler = &loopback.add_endpoint("babbler", 16);
  rx_ = link_.get();
  tx_ = &radar;
}

void BusSide::open_can(Scenario& s, const std::string& can, const std::string& nav_modbus,
                       bool realtime, bool replay_run, std::vector<std::string>& warnings) {
  can_spec_ = parse_can_spec(can);
  const bool hardware_can = can_spec_.kind != CanSpec::Kind::kSim;
  // ",fd" on the command line sends FD lists too (the frame buffers, sized for classic
  // lists, hold FD lists: those take fewer frames).
  if (can_spec_.fd)
    s.can_fd = true;
  const bool nav_external = !nav_modbus.empty() && nav_modbus != "sim";
  if ((hardware_can || nav_external) && !realtime) {
    throw std::runtime_error(
        std::string(hardware_can ? "--can " + can : "--nav-modbus " + nav_modbus) +
        ": a real bus runs on the wall clock: add --realtime");
  }
  if ((hardware_can || !nav_modbus.empty()) && replay_run)
    throw std::runtime_error("replay runs on the software bus only (no --can or --nav-modbus)");
  if (!hardware_can)
    return;
  // Bus time is Unix time (set when the run starts), as the kernel's CLOCK_REALTIME stamps.
  hw_can_ = loop::open_can(can_spec_, 0, warnings);
  rx_ = hw_can_.get();
  tx_ = hw_can_.get();
}

void BusSide::open_table_server(const std::string& spec, std::size_t max_detections) {
  table_config_.max_detections = std::max<std::size_t>(1, max_detections);
  table_regs_.resize(io::modbus::detection_table_registers(table_config_));
  io::modbus::ModbusServerConfig sc;
  sc.endpoint = modbus_server_endpoint(spec);
  sc.start_address = table_config_.base_address;
  sc.register_count = table_regs_.size();
  table_server_ = std::make_unique<io::modbus::ModbusServer>(sc);
}

void BusSide::receive(std::int64_t bus_now_ns, OutputStream* log, RunResult& r) noexcept {
  io::CanFrame f;
  link_->advance_to(bus_now_ns);
  while (rx_->receive(f)) {
    ++r.bus_frames_in;
    // Reception times are kept to the microsecond, the resolution of the candump log, so
    // that a replay of bus_in.log decodes exactly what this run decoded.
    f.timestamp_ns -= f.timestamp_ns % 1000;
    if (log != nullptr)
      log->bus_in(f);
    (void)decoder_.decode(f, f.timestamp_ns);
  }
}

io::icd::EncodeResult BusSide::send(const io::icd::Header& h,
                                    std::span<const io::icd::Detection> list, bool send_list,
                                    bool fd, std::int64_t bus_now_ns, OutputStream* log,
                                    RunResult& r) noexcept {
  io::icd::EncodeResult enc{};
  if (send_list)
    enc = fd ? io::icd::encode_fd(h, list, out_frames_) : io::icd::encode(h, list, out_frames_);
  else
    ++r.lists_suppressed;
  r.icd_dropped += enc.dropped;
  r.icd_truncated += enc.truncated;
  for (std::size_t i = 0; i < enc.frames; ++i) {
    io::CanFrame& f = out_frames_[i];
    f.timestamp_ns = bus_now_ns;
    if (tx_->send(f))
      ++r.bus_frames_out;
    if (log != nullptr)
      log->bus_out(f);
  }
  if (table_server_) {
    // The Modbus table is state, not a message: it is published every frame, stale or not.
    (void)io::modbus::encode_detection_table(h, list, table_regs_, table_config_);
    (void)table_server_->publish(table_regs_);
  }
  return enc;
}

std::uint64_t BusSide::rx_overflows() const noexcept {
  return radar.rx_overflows() + avionics.rx_overflows();
}

}  // namespace radar_emu::loop
