#include "io/modbus.hpp"

#include <arpa/inet.h>
#include <errno.h>
#include <fcntl.h>
#include <modbus.h>
#include <netinet/in.h>
#include <netinet/tcp.h>
#include <poll.h>
#include <sys/eventfd.h>
#include <sys/socket.h>
#include <time.h>
#include <unistd.h>

#include <algorithm>
#include <charconv>
#include <chrono>
#include <cmath>
#include <cstring>
#include <stdexcept>
#include <utility>

namespace radar_emu::io::modbus {

namespace {

std::int64_t monotonic_ns() noexcept {
  timespec ts{};
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return static_cast<std::int64_t>(ts.tv_sec) * 1'000'000'000 + ts.tv_nsec;
}

bool parse_int(std::string_view text, long long lo, long long hi, long long& out) noexcept {
  if (text.empty())
    return false;
  long long v = 0;
  const auto [end, ec] = std::from_chars(text.data(), text.data() + text.size(), v);
  if (ec != std::errc() || end != text.data() + text.size() || v < lo || v > hi)
    return false;
  out = v;
  return true;
}

bool is_ipv4_literal(const std::string& host) noexcept {
  in_addr a{};
  return inet_pton(AF_INET, host.c_str(), &a) == 1;
}

std::string host_port(const std::string& host, std::uint16_t port) {
  const bool v6 = host.find(':') != std::string::npos;
  return (v6 ? "[" + host + "]" : host) + ":" + std::to_string(port);
}

// Splits a timeout [s] into libmodbus's (seconds, microseconds < 1e6).
std::pair<std::uint32_t, std::uint32_t> split_timeout(double timeout_s) noexcept {
  const auto total_us = static_cast<std::uint64_t>(std::llround(timeout_s * 1e6));
  return {static_cast<std::uint32_t>(total_us / 1'000'000),
          static_cast<std::uint32_t>(total_us % 1'000'000)};
}

// Creates a libmodbus context for an endpoint (nullptr with errno set on failure).
modbus_t* new_context(const ModbusEndpoint& e) noexcept {
  if (e.kind == ModbusEndpoint::Kind::kRtu) {
    return modbus_new_rtu(e.device.c_str(), e.baud, e.parity, e.data_bits, e.stop_bits);
  }
  // modbus_new_tcp takes dotted IPv4 only (libmodbus 3.1.6 uses inet_addr); the "_pi" variant
  // resolves host names and IPv6 with getaddrinfo.
  if (is_ipv4_literal(e.host))
    return modbus_new_tcp(e.host.c_str(), e.port);
  return modbus_new_tcp_pi(e.host.c_str(), std::to_string(e.port).c_str());
}

bool is_write_function(std::uint8_t fc) noexcept {
  switch (fc) {
    case MODBUS_FC_WRITE_SINGLE_COIL:
    case MODBUS_FC_WRITE_SINGLE_REGISTER:
    case MODBUS_FC_WRITE_MULTIPLE_COILS:
    case MODBUS_FC_WRITE_MULTIPLE_REGISTERS:
    case MODBUS_FC_MASK_WRITE_REGISTER:
    case MODBUS_FC_WRITE_AND_READ_REGISTERS:
      return true;
    default:
      return false;
  }
}

}  // namespace

// ---- Endpoints ------------------------------------------------------------------------------

ModbusEndpoint parse_modbus_endpoint(std::string_view spec) {
  const std::string quoted = "modbus endpoint '" + std::string(spec) + "': ";
  const auto fail = [&](const std::string& what) { throw std::invalid_argument(quoted + what); };
  ModbusEndpoint e;
  if (spec.starts_with("rtu:")) {
    e.kind = ModbusEndpoint::Kind::kRtu;
    std::string_view rest = spec.substr(4);
    const std::size_t c1 = rest.find(':');
    if (c1 == std::string_view::npos || c1 == 0)
      fail("expected rtu:DEVICE:BAUD[:8N1]");
    e.device = std::string(rest.substr(0, c1));
    rest = rest.substr(c1 + 1);
    const std::size_t c2 = rest.find(':');
    const std::string_view baud = rest.substr(0, c2);
    long long v = 0;
    if (!parse_int(baud, 50, 4'000'000, v))
      fail("baud rate '" + std::string(baud) + "' is not an integer in 50..4000000");
    e.baud = static_cast<int>(v);
    if (c2 != std::string_view::npos) {
      const std::string_view fmt = rest.substr(c2 + 1);
      if (fmt.size() != 3 || (fmt[0] != '7' && fmt[0] != '8') ||
          (fmt[1] != 'N' && fmt[1] != 'E' && fmt[1] != 'O') || (fmt[2] != '1' && fmt[2] != '2')) {
        fail("frame format '" + std::string(fmt) +
             "' is not DATABITS(7|8) PARITY(N|E|O) STOPBITS(1|2), e.g. 8N1");
      }
      e.data_bits = fmt[0] - '0';
      e.parity = fmt[1];
      e.stop_bits = fmt[2] - '0';
    }
    return e;
  }
  std::string_view rest = spec.starts_with("tcp:") ? spec.substr(4) : spec;
  std::string_view host;
  std::string_view port;
  if (rest.starts_with('[')) {
    const std::size_t close = rest.find(']');
    if (close == std::string_view::npos || close + 1 >= rest.size() || rest[close + 1] != ':')
      fail("expected tcp:[IPV6]:PORT");
    host = rest.substr(1, close - 1);
    port = rest.substr(close + 2);
  } else {
    const std::size_t colon = rest.rfind(':');
    if (colon == std::string_view::npos)
      fail("expected tcp:HOST:PORT, HOST:PORT or rtu:DEVICE:BAUD[:8N1]");
    host = rest.substr(0, colon);
    port = rest.substr(colon + 1);
    if (host.find(':') != std::string_view::npos)
      fail("an IPv6 address must be written in brackets: tcp:[ADDRESS]:PORT");
  }
  if (host.empty())
    fail("empty host");
  long long v = 0;
  if (!parse_int(port, 0, 65535, v))
    fail("port '" + std::string(port) + "' is not an integer in 0..65535");
  e.host = std::string(host);
  e.port = static_cast<std::uint16_t>(v);
  return e;
}

std::string to_string(const ModbusEndpoint& e) {
  if (e.kind == ModbusEndpoint::Kind::kRtu) {
    return "rtu:" + e.device + ":" + std::to_string(e.baud) + ":" + std::to_string(e.data_bits) +
           e.parity + std::to_string(e.stop_bits);
  }
  return "tcp:" + host_port(e.host, e.port);
}

// ---- Client ---------------------------------------------------------------------------------

struct ModbusClient::Impl {
  modbus_t* ctx = nullptr;
};

ModbusClient::ModbusClient(const ModbusClientConfig& config)
    : endpoint_(parse_modbus_endpoint(config.endpoint)),
      config_(config),
      impl_(std::make_unique<Impl>()) {
  const std::string where = "modbus client " + to_string(endpoint_) + ": ";
  if (!(config.response_timeout_s > 0.0 && config.response_timeout_s <= 60.0))
    throw std::invalid_argument(where + "response_timeout_s must be in (0, 60] s");
  if (!(config.reconnect_interval_s >= 0.0 && config.reconnect_interval_s <= 3600.0))
    throw std::invalid_argument(where + "reconnect_interval_s must be in [0, 3600] s");
  if (config.timeouts_before_reconnect < 1)
    throw std::invalid_argument(where + "timeouts_before_reconnect must be >= 1");
  const bool rtu = endpoint_.kind == ModbusEndpoint::Kind::kRtu;
  if (config.unit_id < (rtu ? 1 : 0) || config.unit_id > (rtu ? 247 : 255)) {
    throw std::invalid_argument(where + "unit_id " + std::to_string(config.unit_id) +
                                (rtu ? " is not a slave address 1..247" : " is not 0..255"));
  }
  if (endpoint_.kind == ModbusEndpoint::Kind::kTcp && endpoint_.port == 0)
    throw std::invalid_argument(where + "port 0 is only for servers");
  impl_->ctx = new_context(endpoint_);
  if (impl_->ctx == nullptr)
    throw std::runtime_error(where + "libmodbus refused the settings: " + std::strerror(errno));
  const auto [sec, usec] = split_timeout(config.response_timeout_s);
  if (modbus_set_slave(impl_->ctx, config.unit_id) == -1 ||
      modbus_set_response_timeout(impl_->ctx, sec, usec) == -1 ||
      modbus_set_byte_timeout(impl_->ctx, sec, usec) == -1) {
    const std::string reason = modbus_strerror(errno);
    modbus_free(impl_->ctx);
    throw std::runtime_error(where + "libmodbus refused the settings: " + reason);
  }
  (void)ensure_connected();
}

ModbusClient::~ModbusClient() {
  if (impl_->ctx != nullptr) {
    modbus_close(impl_->ctx);
    modbus_free(impl_->ctx);
  }
}

bool ModbusClient::ensure_connected() noexcept {
  if (connected_.load())
    return true;
  const std::int64_t now = monotonic_ns();
  if (now < next_connect_ns_)
    return false;
  next_connect_ns_ = now + std::llround(config_.reconnect_interval_s * 1e9);
  if (modbus_connect(impl_->ctx) == -1) {
    counters_.connect_failures.fetch_add(1, std::memory_order_relaxed);
    return false;
  }
  if (ever_connected_)
    counters_.reconnects.fetch_add(1, std::memory_order_relaxed);
  ever_connected_ = true;
  consecutive_timeouts_ = 0;
  connected_.store(true);
  return true;
}

void ModbusClient::drop_link() noexcept {
  modbus_close(impl_->ctx);
  connected_.store(false);
  next_connect_ns_ = 0;  // the next call tries at once (a restarted server is back quickly)
}

RegisterStatus ModbusClient::classify_failure(int error) noexcept {
  if (error == ETIMEDOUT) {
    counters_.timeouts.fetch_add(1, std::memory_order_relaxed);
    ++consecutive_timeouts_;
    if (endpoint_.kind == ModbusEndpoint::Kind::kTcp &&
        consecutive_timeouts_ >= config_.timeouts_before_reconnect) {
      drop_link();
    } else {
      modbus_flush(impl_->ctx);  // a late answer must not be taken for the next one
    }
    return RegisterStatus::kTimeout;
  }
  consecutive_timeouts_ = 0;
  if (error == EMBXILADD) {
    counters_.exceptions.fetch_add(1, std::memory_order_relaxed);
    return RegisterStatus::kIllegalAddress;
  }
  if (error >= EMBXILFUN && error <= EMBXGTAR) {
    counters_.exceptions.fetch_add(1, std::memory_order_relaxed);
    return RegisterStatus::kError;
  }
  if (error >= EMBBADCRC && error <= EMBBADSLAVE) {
    counters_.errors.fetch_add(1, std::memory_order_relaxed);
    modbus_flush(impl_->ctx);
    return RegisterStatus::kError;
  }
  // Transport failure (ECONNRESET, EPIPE, EBADF, EIO, ...): drop the link, reconnect later.
  counters_.disconnected.fetch_add(1, std::memory_order_relaxed);
  drop_link();
  return RegisterStatus::kDisconnected;
}

template <class Call>
RegisterStatus ModbusClient::transact(std::uint16_t address, std::size_t count, std::size_t max,
                                      Call call) noexcept {
  counters_.requests.fetch_add(1, std::memory_order_relaxed);
  if (count == 0 || count > max || static_cast<std::size_t>(address) + count > 65536) {
    counters_.errors.fetch_add(1, std::memory_order_relaxed);
    return RegisterStatus::kError;
  }
  if (!ensure_connected()) {
    counters_.disconnected.fetch_add(1, std::memory_order_relaxed);
    return RegisterStatus::kDisconnected;
  }
  const int n = static_cast<int>(count);
  const int rc = call(n);
  if (rc == n) {
    consecutive_timeouts_ = 0;
    counters_.ok.fetch_add(1, std::memory_order_relaxed);
    return RegisterStatus::kOk;
  }
  if (rc >= 0) {
    counters_.errors.fetch_add(1, std::memory_order_relaxed);
    return RegisterStatus::kError;
  }
  return classify_failure(errno);
}

RegisterStatus ModbusClient::read_holding(std::uint16_t address,
                                          std::span<std::uint16_t> out) noexcept {
  return transact(address, out.size(), kModbusMaxReadRegisters,
                  [&](int n) { return modbus_read_registers(impl_->ctx, address, n, out.data()); });
}

RegisterStatus ModbusClient::write_holding(std::uint16_t address,
                                           std::span<const std::uint16_t> values) noexcept {
  return transact(address, values.size(), kModbusMaxWriteRegisters, [&](int n) {
    return modbus_write_registers(impl_->ctx, address, n, values.data());
  });
}

ModbusClientCounters ModbusClient::counters() const noexcept {
  ModbusClientCounters c;
  c.requests = counters_.requests.load(std::memory_order_relaxed);
  c.ok = counters_.ok.load(std::memory_order_relaxed);
  c.timeouts = counters_.timeouts.load(std::memory_order_relaxed);
  c.disconnected = counters_.disconnected.load(std::memory_order_relaxed);
  c.exceptions = counters_.exceptions.load(std::memory_order_relaxed);
  c.errors = counters_.errors.load(std::memory_order_relaxed);
  c.connect_failures = counters_.connect_failures.load(std::memory_order_relaxed);
  c.reconnects = counters_.reconnects.load(std::memory_order_relaxed);
  return c;
}

// ---- Navigation poller ----------------------------------------------------------------------

NavPoller::NavPoller(RegisterBank& bank, NavPollerConfig config)
    : bank_(bank), config_(std::move(config)), decoder_(config_.map) {
  if (!(config_.period_s > 0.0 && config_.period_s <= 60.0))
    throw std::invalid_argument("nav poller: period_s must be in (0, 60] s");
  if (decoder_.register_count() > kModbusMaxReadRegisters)
    throw std::invalid_argument("nav poller: the navigation map exceeds one read");
  if (static_cast<std::size_t>(config_.map.base_address) + decoder_.register_count() > 65536)
    throw std::invalid_argument("nav poller: base_address + map length exceeds 65536");
  if (!config_.clock_ns)
    config_.clock_ns = [] { return monotonic_ns(); };
  thread_ = std::thread([this] { run(); });
}

NavPoller::~NavPoller() {
  stop();
}

void NavPoller::stop() noexcept {
  {
    std::lock_guard<std::mutex> lock(wake_mutex_);
    stop_.store(true);
  }
  wake_.notify_all();
  if (thread_.joinable())
    thread_.join();
}

bool NavPoller::latest(canas::OwnshipState& out) noexcept {
  const bool fresh = states_.update();
  out = states_.read_slot();
  return fresh;
}

void NavPoller::run() noexcept {
  std::array<std::uint16_t, kModbusMaxReadRegisters> regs{};
  const std::span<std::uint16_t> image(regs.data(), decoder_.register_count());
  const auto period = std::chrono::nanoseconds(std::llround(config_.period_s * 1e9));
  auto next = std::chrono::steady_clock::now();
  bool failing = false;
  auto& c = counters_;
  constexpr auto kRelaxed = std::memory_order_relaxed;
  while (!stop_.load()) {
    c.polls.fetch_add(1, kRelaxed);
    const RegisterStatus status = bank_.read_holding(config_.map.base_address, image);
    if (status == RegisterStatus::kOk) {
      c.reads_ok.fetch_add(1, kRelaxed);
      if (failing)
        c.recoveries.fetch_add(1, kRelaxed);
      failing = false;
      const NavDecodeStatus st = decoder_.decode(image, config_.clock_ns());
      const NavDecoderCounters& d = decoder_.counters();
      c.samples.store(d.samples, kRelaxed);
      c.new_samples.store(d.new_samples, kRelaxed);
      c.fields_accepted.store(d.fields_accepted, kRelaxed);
      c.stale.store(d.stale, kRelaxed);
      c.wrong_size.store(d.wrong_size, kRelaxed);
      c.not_a_number.store(d.not_a_number, kRelaxed);
      c.out_of_range.store(d.out_of_range, kRelaxed);
      c.flagged_invalid.store(d.flagged_invalid, kRelaxed);
      c.counter_gaps.store(d.counter_gaps, kRelaxed);
      if (st == NavDecodeStatus::kAccepted || st == NavDecodeStatus::kPartial) {
        states_.write_slot() = decoder_.state();
        states_.publish();
        c.published.fetch_add(1, kRelaxed);
      }
    } else {
      failing = true;
      if (status == RegisterStatus::kTimeout)
        c.timeouts.fetch_add(1, kRelaxed);
      else if (status == RegisterStatus::kDisconnected)
        c.disconnected.fetch_add(1, kRelaxed);
      else
        c.read_errors.fetch_add(1, kRelaxed);
    }
    // Absolute deadlines; periods overrun by a slow read are skipped, not replayed.
    next += period;
    const auto now = std::chrono::steady_clock::now();
    if (next <= now) {
      const auto behind = (now - next) / period + 1;
      c.missed_periods.fetch_add(static_cast<std::uint64_t>(behind), kRelaxed);
      next += behind * period;
    }
    std::unique_lock<std::mutex> lock(wake_mutex_);
    wake_.wait_until(lock, next, [this] { return stop_.load(); });
  }
}

NavPollerCounters NavPoller::counters() const noexcept {
  constexpr auto kRelaxed = std::memory_order_relaxed;
  const auto& c = counters_;
  NavPollerCounters r;
  r.polls = c.polls.load(kRelaxed);
  r.reads_ok = c.reads_ok.load(kRelaxed);
  r.timeouts = c.timeouts.load(kRelaxed);
  r.disconnected = c.disconnected.load(kRelaxed);
  r.read_errors = c.read_errors.load(kRelaxed);
  r.recoveries = c.recoveries.load(kRelaxed);
  r.missed_periods = c.missed_periods.load(kRelaxed);
  r.published = c.published.load(kRelaxed);
  r.decoder.samples = c.samples.load(kRelaxed);
  r.decoder.new_samples = c.new_samples.load(kRelaxed);
  r.decoder.fields_accepted = c.fields_accepted.load(kRelaxed);
  r.decoder.stale = c.stale.load(kRelaxed);
  r.decoder.wrong_size = c.wrong_size.load(kRelaxed);
  r.decoder.not_a_number = c.not_a_number.load(kRelaxed);
  r.decoder.out_of_range = c.out_of_range.load(kRelaxed);
  r.decoder.flagged_invalid = c.flagged_invalid.load(kRelaxed);
  r.decoder.counter_gaps = c.counter_gaps.load(kRelaxed);
  return r;
}

// ---- Server ---------------------------------------------------------------------------------

struct ModbusServer::Impl {
  modbus_t* ctx = nullptr;
  modbus_mapping_t* mapping = nullptr;
  int listen_fd = -1;
  int wake_fd = -1;
  std::vector<int> clients;
  std::vector<pollfd> fds;  // reserved at setup
  std::array<std::uint8_t, MODBUS_MAX_ADU_LENGTH> query{};

  ~Impl() {
    for (const int fd : clients)
      ::close(fd);
    if (listen_fd >= 0)
      ::close(listen_fd);
    if (ctx != nullptr) {
      modbus_set_socket(ctx, -1);  // client sockets are closed above
      modbus_close(ctx);           // RTU: the serial port
      modbus_free(ctx);
    }
    if (mapping != nullptr)
      modbus_mapping_free(mapping);
    if (wake_fd >= 0)
      ::close(wake_fd);
  }
};

namespace {

std::size_t checked_register_count(const ModbusServerConfig& c) {
  if (c.register_count == 0 ||
      static_cast<std::size_t>(c.start_address) + c.register_count > 65536) {
    throw std::invalid_argument("modbus server " + c.endpoint + ": register_count " +
                                std::to_string(c.register_count) + " at start_address " +
                                std::to_string(c.start_address) +
                                " must be 1 .. 65536 - start_address");
  }
  return c.register_count;
}

}  // namespace

ModbusServer::ModbusServer(const ModbusServerConfig& config)
    : config_(config),
      endpoint_(parse_modbus_endpoint(config.endpoint)),
      impl_(std::make_unique<Impl>()),
      working_(checked_register_count(config), 0),
      images_(working_) {
  const std::string where = "modbus server " + to_string(endpoint_) + ": ";
  const bool rtu = endpoint_.kind == ModbusEndpoint::Kind::kRtu;
  if (rtu && (config.unit_id < 1 || config.unit_id > 247))
    throw std::invalid_argument(where + "unit_id must be a slave address 1..247");
  if (config.max_clients < 1 || config.max_clients > 256)
    throw std::invalid_argument(where + "max_clients must be 1..256");

  impl_->ctx = new_context(endpoint_);
  if (impl_->ctx == nullptr)
    throw std::runtime_error(where + "libmodbus refused the settings: " + std::strerror(errno));
  impl_->mapping = modbus_mapping_new_start_address(
      0, 0, 0, 0, config.start_address, static_cast<unsigned int>(config.register_count), 0, 0);
  if (impl_->mapping == nullptr)
    throw std::runtime_error(where + "cannot allocate the register table");
  // A client that stops in the middle of a request cannot hold the thread for longer than this.
  modbus_set_indication_timeout(impl_->ctx, 1, 0);
  modbus_set_byte_timeout(impl_->ctx, 0, 500'000);
  if (rtu) {
    if (modbus_set_slave(impl_->ctx, config.unit_id) == -1)
      throw std::invalid_argument(where + "unit_id rejected by libmodbus");
    if (modbus_connect(impl_->ctx) == -1)
      throw std::runtime_error(where + "cannot open " + endpoint_.device + ": " +
                               modbus_strerror(errno));
    address_ = endpoint_.device;
  } else {
    impl_->listen_fd = is_ipv4_literal(endpoint_.host)
                           ? modbus_tcp_listen(impl_->ctx, config.max_clients)
                           : modbus_tcp_pi_listen(impl_->ctx, config.max_clients);
    if (impl_->listen_fd < 0) {
      throw std::runtime_error("modbus server: cannot listen on " +
                               host_port(endpoint_.host, endpoint_.port) + ": " +
                               std::strerror(errno));
    }
    sockaddr_storage bound{};
    socklen_t len = sizeof(bound);
    if (getsockname(impl_->listen_fd, reinterpret_cast<sockaddr*>(&bound), &len) == -1)
      throw std::runtime_error(where + "getsockname failed: " + std::strerror(errno));
    if (bound.ss_family == AF_INET6) {
      port_ = ntohs(reinterpret_cast<const sockaddr_in6*>(&bound)->sin6_port);
    } else {
      port_ = ntohs(reinterpret_cast<const sockaddr_in*>(&bound)->sin_port);
    }
    // Non-blocking accept: a client gone between poll() and accept() must not stall the loop.
    const int flags = fcntl(impl_->listen_fd, F_GETFL, 0);
    (void)fcntl(impl_->listen_fd, F_SETFL, flags | O_NONBLOCK);
    address_ = host_port(endpoint_.host, port_);
  }
  impl_->wake_fd = eventfd(0, EFD_CLOEXEC | EFD_NONBLOCK);
  if (impl_->wake_fd < 0)
    throw std::runtime_error(where + "eventfd failed: " + std::strerror(errno));
  impl_->clients.reserve(static_cast<std::size_t>(config.max_clients));
  impl_->fds.reserve(static_cast<std::size_t>(config.max_clients) + 2);
  thread_ = std::thread([this] { run(); });
}

ModbusServer::~ModbusServer() {
  stop();
}

void ModbusServer::stop() noexcept {
  if (thread_.joinable()) {
    const std::uint64_t one = 1;
    (void)!::write(impl_->wake_fd, &one, sizeof(one));
    thread_.join();
  }
  for (const int fd : impl_->clients)
    ::close(fd);
  impl_->clients.clear();
  if (impl_->listen_fd >= 0) {
    ::close(impl_->listen_fd);
    impl_->listen_fd = -1;
  }
}

void ModbusServer::serve_request(int length) noexcept {
  Impl& m = *impl_;
  counters_.requests.fetch_add(1, std::memory_order_relaxed);
  if (images_.update()) {
    const std::vector<std::uint16_t>& image = images_.read_slot();
    std::copy(image.begin(), image.end(), m.mapping->tab_registers);
  }
  const int header = modbus_get_header_length(m.ctx);
  const std::uint8_t fc = m.query[static_cast<std::size_t>(header)];
  int rc = 0;
  if (is_write_function(fc)) {
    counters_.refused_writes.fetch_add(1, std::memory_order_relaxed);
    rc = modbus_reply_exception(m.ctx, m.query.data(), MODBUS_EXCEPTION_ILLEGAL_FUNCTION);
  } else {
    rc = modbus_reply(m.ctx, m.query.data(), length, m.mapping);
  }
  if (rc < 0) {
    counters_.errors.fetch_add(1, std::memory_order_relaxed);
  } else if (rc > 0) {
    counters_.replies.fetch_add(1, std::memory_order_relaxed);
  }
}

void ModbusServer::run() noexcept {
  Impl& m = *impl_;
  const bool rtu = endpoint_.kind == ModbusEndpoint::Kind::kRtu;
  for (;;) {
    m.fds.clear();
    m.fds.push_back({m.wake_fd, POLLIN, 0});
    if (rtu) {
      m.fds.push_back({modbus_get_socket(m.ctx), POLLIN, 0});
    } else {
      m.fds.push_back({m.listen_fd, POLLIN, 0});
      for (const int fd : m.clients)
        m.fds.push_back({fd, POLLIN, 0});
    }
    const int n = ::poll(m.fds.data(), m.fds.size(), -1);
    if (n < 0) {
      if (errno == EINTR)
        continue;
      counters_.errors.fetch_add(1, std::memory_order_relaxed);
      return;
    }
    if (m.fds[0].revents != 0)
      return;  // stop()
    if (rtu) {
      const short ev = m.fds[1].revents;
      if (ev & POLLNVAL) {
        counters_.errors.fetch_add(1, std::memory_order_relaxed);
        return;
      }
      int rc = -1;
      if (ev & POLLIN)
        rc = modbus_receive(m.ctx, m.query.data());
      if (rc > 0) {
        serve_request(rc);
      } else if (rc < 0 && ev != 0) {
        // Garbage, CRC error or a hung-up line (a pty whose peer closed polls readable for
        // ever): count it and pause briefly instead of spinning.
        counters_.errors.fetch_add(1, std::memory_order_relaxed);
        modbus_flush(m.ctx);
        pollfd wake{m.wake_fd, POLLIN, 0};
        (void)::poll(&wake, 1, 50);
      }
      continue;
    }
    // Clients first (their indices are fixed for this round), then new connections.
    for (std::size_t i = 2; i < m.fds.size(); ++i) {
      if (m.fds[i].revents == 0)
        continue;
      const int fd = m.fds[i].fd;
      modbus_set_socket(m.ctx, fd);
      const int rc = modbus_receive(m.ctx, m.query.data());
      if (rc > 0) {
        serve_request(rc);
      } else if (rc < 0) {
        if (errno != ECONNRESET)  // ECONNRESET: the client closed (libmodbus maps EOF to it)
          counters_.errors.fetch_add(1, std::memory_order_relaxed);
        ::close(fd);
        m.clients.erase(std::find(m.clients.begin(), m.clients.end(), fd));
      }
    }
    if (m.fds[1].revents & POLLIN) {
      const int fd = ::accept4(m.listen_fd, nullptr, nullptr, SOCK_CLOEXEC);
      if (fd >= 0) {
        // libmodbus waits on a client with select(): descriptors must stay below FD_SETSIZE.
        if (m.clients.size() >= static_cast<std::size_t>(config_.max_clients) || fd >= FD_SETSIZE) {
          ::close(fd);
          counters_.clients_refused.fetch_add(1, std::memory_order_relaxed);
        } else {
          const int on = 1;
          (void)setsockopt(fd, IPPROTO_TCP, TCP_NODELAY, &on, sizeof(on));
          m.clients.push_back(fd);
          counters_.clients_accepted.fetch_add(1, std::memory_order_relaxed);
        }
      }
    }
  }
}

bool ModbusServer::publish(std::span<const std::uint16_t> image) noexcept {
  if (image.size() != working_.size()) {
    counters_.publishes_rejected.fetch_add(1, std::memory_order_relaxed);
    return false;
  }
  std::copy(image.begin(), image.end(), working_.begin());
  std::vector<std::uint16_t>& slot = images_.write_slot();
  std::copy(working_.begin(), working_.end(), slot.begin());
  images_.publish();
  counters_.publishes.fetch_add(1, std::memory_order_relaxed);
  return true;
}

RegisterStatus ModbusServer::read_holding(std::uint16_t address,
                                          std::span<std::uint16_t> out) noexcept {
  if (out.empty() || out.size() > kModbusMaxReadRegisters)
    return RegisterStatus::kError;
  const std::size_t start = config_.start_address;
  if (address < start || address - start + out.size() > working_.size())
    return RegisterStatus::kIllegalAddress;
  const auto from = working_.begin() + static_cast<std::ptrdiff_t>(address - start);
  std::copy(from, from + static_cast<std::ptrdiff_t>(out.size()), out.begin());
  return RegisterStatus::kOk;
}

RegisterStatus ModbusServer::write_holding(std::uint16_t address,
                                           std::span<const std::uint16_t> values) noexcept {
  if (values.empty() || values.size() > kModbusMaxWriteRegisters)
    return RegisterStatus::kError;
  const std::size_t start = config_.start_address;
  if (address < start || address - start + values.size() > working_.size())
    return RegisterStatus::kIllegalAddress;
  std::copy(values.begin(), values.end(),
            working_.begin() + static_cast<std::ptrdiff_t>(address - start));
  std::vector<std::uint16_t>& slot = images_.write_slot();
  std::copy(working_.begin(), working_.end(), slot.begin());
  images_.publish();
  counters_.publishes.fetch_add(1, std::memory_order_relaxed);
  return RegisterStatus::kOk;
}

ModbusServerCounters ModbusServer::counters() const noexcept {
  constexpr auto kRelaxed = std::memory_order_relaxed;
  ModbusServerCounters c;
  c.requests = counters_.requests.load(kRelaxed);
  c.replies = counters_.replies.load(kRelaxed);
  c.refused_writes = counters_.refused_writes.load(kRelaxed);
  c.errors = counters_.errors.load(kRelaxed);
  c.clients_accepted = counters_.clients_accepted.load(kRelaxed);
  c.clients_refused = counters_.clients_refused.load(kRelaxed);
  c.publishes = counters_.publishes.load(kRelaxed);
  c.publishes_rejected = counters_.publishes_rejected.load(kRelaxed);
  return c;
}

}  // namespace radar_emu::io::modbus
