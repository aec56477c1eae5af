#include "loop/ownship_source.hpp"

#include <time.h>

#include <cstdio>

#include "loop/bus_backends.hpp"

namespace radar_emu::loop {

RegisterBankSource::RegisterBankSource(const io::modbus::NavMapConfig& map,
                                       const sim_bus::RegisterFaultConfig& faults)
    : map_(map), regs_(io::modbus::nav_register_count(map)) {
  bank_ = std::make_unique<sim_bus::LoopbackRegisterBank>(map_.base_address, regs_.size());
  faulty_ = std::make_unique<sim_bus::FaultyRegisterBank>(*bank_, faults);
}

const io::canas::OwnshipState& RegisterBankSource::read(std::int64_t bus_now_ns) noexcept {
  faulty_->advance_to(bus_now_ns);
  if (faulty_->read_holding(map_.base_address, regs_) == io::RegisterStatus::kOk)
    (void)decoder_.decode(regs_, bus_now_ns);
  else
    ++read_failures_;
  return decoder_.state();
}

NavSourceReport RegisterBankSource::report() const {
  NavSourceReport r;
  r.register_bank = true;
  r.decoder = decoder_.counters();
  r.read_failures = read_failures_;
  r.faults = faulty_->counters();
  return r;
}

PollerSource::PollerSource(const std::string& endpoint, const io::modbus::NavMapConfig& map,
                           const std::atomic<std::int64_t>& bus_from_monotonic_ns)
    : endpoint_(endpoint) {
  io::modbus::ModbusClientConfig cc;
  cc.endpoint = endpoint;
  client_ = std::make_unique<io::modbus::ModbusClient>(cc);
  retry_max_s_ = cc.reconnect_max_interval_s;
  io::modbus::NavPollerConfig pc;
  pc.map = map;
  const std::atomic<std::int64_t>* offset = &bus_from_monotonic_ns;
  pc.clock_ns = [offset] {
    timespec ts{};
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return offset->load(std::memory_order_relaxed) +
           static_cast<std::int64_t>(ts.tv_sec) * 1'000'000'000LL + ts.tv_nsec;
  };
  // The source's state on stderr as it changes (from the poller's thread, never the loop).
  pc.on_link = [client = client_.get(), endpoint,
                retry = cc.reconnect_max_interval_s](const io::modbus::NavLinkEvent& e) {
    const std::string line = nav_link_message(endpoint, e, client->last_error_text(), retry);
    std::fprintf(stderr, "%s\n", line.c_str());
    std::fflush(stderr);
  };
  poller_ = std::make_unique<io::modbus::NavPoller>(*client_, pc);
}

const io::canas::OwnshipState& PollerSource::read(std::int64_t /*bus_now_ns*/) noexcept {
  (void)poller_->latest(state_);
  if (poller_->link_state() != io::modbus::NavLinkState::kUp)
    ++frames_source_down_;  // reported with the link (report.json nav_modbus.link)
  return state_;
}

NavSourceReport PollerSource::report() const {
  NavSourceReport r;
  r.register_bank = false;
  r.decoder = poller_->counters().decoder;
  r.poller = poller_->counters();
  r.link_json = nav_link_report_json(r.poller, poller_->link_state(), client_->counters(),
                                     client_->last_error_text(), retry_max_s_, frames_source_down_);
  return r;
}

std::string PollerSource::failure() const {
  if (poller_->counters().ever_up)
    return {};
  const std::string error = client_->last_error_text();
  return "navigation source " + endpoint_ + " never answered" +
         (error.empty() ? "" : " (" + error + ")") +
         ": no frame had a valid ownship state (report.json nav_modbus.link)";
}

std::optional<NavSourceReport> OwnshipSource::report() const {
  if (const auto* bank = std::get_if<RegisterBankSource>(&source_))
    return bank->report();
  if (const auto* poller = std::get_if<PollerSource>(&source_))
    return poller->report();
  return std::nullopt;
}

std::string OwnshipSource::failure() const {
  const auto* poller = std::get_if<PollerSource>(&source_);
  return poller != nullptr ? poller->failure() : std::string();
}

}  // namespace radar_emu::loop
