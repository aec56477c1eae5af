#include "io/modbus.hpp"

#include <arpa/inet.h>
#include <errno.h>
#include <fcntl.h>
#include <modbus.h>
#include <netdb.h>
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
  if (!(config.reconnect_max_interval_s >= config.reconnect_interval_s &&
        config.reconnect_max_interval_s <= 3600.0)) {
    throw std::invalid_argument(
        where + "reconnect_max_interval_s must be in [reconnect_interval_s, 3600] s");
  }
  if (config.timeouts_before_reconnect < 1)
    throw std::invalid_argument(where + "timeouts_before_reconnect must be >= 1");
  backoff_ns_.store(std::llround(config.reconnect_interval_s * 1e9));
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
  const std::int64_t wait_ns = backoff_ns_.load();
  if (modbus_connect(impl_->ctx) == -1) {
    // libmodbus 3.1.6 leaves EINPROGRESS when the non-blocking connect ran out of time.
    last_error_.store(errno == EINPROGRESS ? ETIMEDOUT : errno);
    counters_.connect_failures.fetch_add(1, std::memory_order_relaxed);
    // Back-off: the next attempt after `wait`, which doubles up to the ceiling.
    next_connect_ns_ = monotonic_ns() + wait_ns;
    backoff_ns_.store(
        std::min<std::int64_t>(2 * wait_ns, std::llround(config_.reconnect_max_interval_s * 1e9)));
    return false;
  }
  backoff_ns_.store(std::llround(config_.reconnect_interval_s * 1e9));
  next_connect_ns_ = 0;
  if (ever_connected_)
    counters_.reconnects.fetch_add(1, std::memory_order_relaxed);
  ever_connected_ = true;
  consecutive_timeouts_ = 0;
  connected_.store(true);
  return true;
}

std::string ModbusClient::last_error_text() const {
  const int e = last_error_.load();
  if (e == 0)
    return {};
  return modbus_strerror(e);  // libmodbus's text for its own codes, strerror() for the rest
}

void ModbusClient::drop_link() noexcept {
  modbus_close(impl_->ctx);
  connected_.store(false);
  next_connect_ns_ = 0;  // the next call tries at once (a restarted server is back quickly)
}

RegisterStatus ModbusClient::classify_failure(int error) noexcept {
  last_error_.store(error);
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
  c.start_ns.store(monotonic_ns(), kRelaxed);
  while (!stop_.load()) {
    c.polls.fetch_add(1, kRelaxed);
    const RegisterStatus status = bank_.read_holding(config_.map.base_address, image);
    track_link(status, monotonic_ns());
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

void NavPoller::track_link(RegisterStatus status, std::int64_t now_ns) noexcept {
  constexpr auto kRelaxed = std::memory_order_relaxed;
  auto& c = counters_;
  const NavLinkState before = link_.load();
  if (status == RegisterStatus::kOk) {
    if (c.first_ok_ns.load(kRelaxed) == 0)
      c.first_ok_ns.store(now_ns, kRelaxed);
    if (before == NavLinkState::kDown) {
      const std::int64_t down_since = c.down_since_ns.load(kRelaxed);
      if (down_since != 0) {  // an outage after having been up: close it
        const std::int64_t d = now_ns - down_since;
        c.outage_total_ns.fetch_add(d, kRelaxed);
        if (d > c.longest_outage_ns.load(kRelaxed))
          c.longest_outage_ns.store(d, kRelaxed);
        c.down_since_ns.store(0, kRelaxed);
      }
      if (config_.on_link) {
        NavLinkEvent e;
        e.kind = NavLinkEvent::Kind::kRecovered;
        e.outage_s = static_cast<double>(now_ns - failing_since_ns_) * 1e-9;
        e.failed_polls = failed_polls_;
        config_.on_link(e);
      }
    }
    failed_polls_ = 0;
    link_.store(NavLinkState::kUp);
    return;
  }
  if (failed_polls_++ == 0)
    failing_since_ns_ = now_ns;
  // Down at once when the link is refused or breaks; after a few failed reads in a row for
  // time-outs and exception answers (one late answer on a busy machine is not an outage).
  if (before == NavLinkState::kDown ||
      (status != RegisterStatus::kDisconnected && failed_polls_ < kFailedReadsForDown)) {
    return;
  }
  if (before == NavLinkState::kUp) {
    c.outages.fetch_add(1, kRelaxed);
    c.down_since_ns.store(failing_since_ns_, kRelaxed);
  }
  link_.store(NavLinkState::kDown);
  if (config_.on_link) {
    NavLinkEvent e;
    e.kind =
        before == NavLinkState::kUp ? NavLinkEvent::Kind::kLost : NavLinkEvent::Kind::kUnreachable;
    e.status = status;
    config_.on_link(e);
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
  r.outages = c.outages.load(kRelaxed);
  const std::int64_t start = c.start_ns.load(kRelaxed);
  const std::int64_t first_ok = c.first_ok_ns.load(kRelaxed);
  r.ever_up = first_ok != 0;
  r.first_read_s = first_ok != 0 ? static_cast<double>(first_ok - start) * 1e-9 : -1.0;
  std::int64_t total = c.outage_total_ns.load(kRelaxed);
  std::int64_t longest = c.longest_outage_ns.load(kRelaxed);
  const std::int64_t down_since = c.down_since_ns.load(kRelaxed);
  if (down_since != 0) {  // an outage still going on counts up to now
    const std::int64_t d = monotonic_ns() - down_since;
    total += d;
    longest = std::max(longest, d);
  }
  r.outage_s_total = static_cast<double>(total) * 1e-9;
  r.longest_outage_s = static_cast<double>(longest) * 1e-9;
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

namespace {

// Modbus messaging on TCP/IP implementation guide v1.0b, sec. 3.1.3: the MBAP header is
// transaction id (2), protocol id (2, 0 = Modbus), length (2: the bytes that follow, unit id
// included), unit id (1); an ADU is at most 260 bytes, so length is 2 (unit id + function
// code) .. 254.
constexpr std::size_t kMbapBytes = 7;
constexpr std::size_t kMaxTcpAdu = 260;
constexpr std::size_t kMinMbapLength = 2;
constexpr std::size_t kMaxMbapLength = kMaxTcpAdu - 6;
// Per connection: room for two requests, so a pipelining client is read ahead a little.
constexpr std::size_t kRxBuffer = 2 * kMaxTcpAdu;
// Requests answered per connection per poll round: the others' turn comes after that.
constexpr int kRequestsPerRound = 4;
// New connections taken per poll round (a flood is served in slices too).
constexpr int kAcceptsPerRound = 16;

// Exception codes (Modbus application protocol v1.1b3, sec. 7).
constexpr std::uint8_t kIllegalFunction = 0x01;
constexpr std::uint8_t kIllegalDataAddress = 0x02;
constexpr std::uint8_t kIllegalDataValue = 0x03;
constexpr std::uint8_t kReadHoldingRegisters = 0x03;

std::int64_t seconds_to_ns(double s) noexcept {
  return std::llround(s * 1e9);
}

// A listening TCP socket for HOST:PORT (numeric IPv4/IPv6 or a name), non-blocking; -1 with
// errno set on failure.
int listen_tcp(const std::string& host, std::uint16_t port, int backlog) noexcept {
  addrinfo hints{};
  hints.ai_family = AF_UNSPEC;
  hints.ai_socktype = SOCK_STREAM;
  hints.ai_flags = AI_PASSIVE;
  addrinfo* found = nullptr;
  const std::string service = std::to_string(port);
  const int gai = getaddrinfo(host.c_str(), service.c_str(), &hints, &found);
  if (gai != 0) {
    errno = gai == EAI_SYSTEM ? errno : EADDRNOTAVAIL;
    return -1;
  }
  int fd = -1;
  int error = EADDRNOTAVAIL;
  for (addrinfo* a = found; a != nullptr; a = a->ai_next) {
    fd = ::socket(a->ai_family, a->ai_socktype | SOCK_NONBLOCK | SOCK_CLOEXEC, a->ai_protocol);
    if (fd < 0) {
      error = errno;
      continue;
    }
    const int on = 1;
    (void)setsockopt(fd, SOL_SOCKET, SO_REUSEADDR, &on, sizeof(on));
    if (::bind(fd, a->ai_addr, a->ai_addrlen) == 0 && ::listen(fd, backlog) == 0)
      break;
    error = errno;
    ::close(fd);
    fd = -1;
  }
  freeaddrinfo(found);
  if (fd < 0)
    errno = error;
  return fd;
}

std::uint16_t be16(const std::uint8_t* p) noexcept {
  return static_cast<std::uint16_t>((p[0] << 8) | p[1]);
}

void put_be16(std::uint8_t* p, std::uint16_t v) noexcept {
  p[0] = static_cast<std::uint8_t>(v >> 8);
  p[1] = static_cast<std::uint8_t>(v);
}

}  // namespace

struct ModbusServer::Connection {
  int fd = -1;
  std::array<std::uint8_t, kRxBuffer> rx{};
  std::size_t rx_len = 0;
  std::int64_t last_activity_ns = 0;  // last byte received (or the accept)
  std::int64_t request_start_ns = 0;  // first byte of the unfinished request (rx_len > 0)
};

struct ModbusServer::Impl {
  // RTU (libmodbus).
  modbus_t* ctx = nullptr;
  modbus_mapping_t* mapping = nullptr;
  std::array<std::uint8_t, MODBUS_MAX_ADU_LENGTH> query{};
  // TCP.
  int listen_fd = -1;
  int spare_fd = -1;  // held open so that a connection can still be accepted (and closed)
                      // when the process runs out of descriptors
  std::vector<Connection> connections;  // max_clients slots, fd -1 when free
  std::vector<pollfd> fds;              // reserved at setup
  std::vector<Connection*> polled;      // connection of fds[2 + i]
  std::array<std::uint8_t, kMaxTcpAdu> reply{};
  std::int64_t request_timeout_ns = 0, idle_timeout_ns = 0, evict_idle_ns = 0;
  int wake_fd = -1;

  ~Impl() {
    for (const Connection& c : connections) {
      if (c.fd >= 0)
        ::close(c.fd);
    }
    if (listen_fd >= 0)
      ::close(listen_fd);
    if (spare_fd >= 0)
      ::close(spare_fd);
    if (ctx != nullptr) {
      modbus_close(ctx);  // RTU: the serial port
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
  if (config.max_clients < 1 || config.max_clients > 1024)
    throw std::invalid_argument(where + "max_clients must be 1..1024");
  const auto in_range = [](double s) { return s > 0.0 && s <= 86400.0; };
  if (!in_range(config.request_timeout_s) || !in_range(config.idle_timeout_s) ||
      !(config.evict_idle_s >= 0.0 && config.evict_idle_s <= 86400.0)) {
    throw std::invalid_argument(where +
                                "request_timeout_s and idle_timeout_s must be in (0, 86400] s, "
                                "evict_idle_s in [0, 86400] s");
  }
  Impl& m = *impl_;
  if (rtu) {
    m.ctx = new_context(endpoint_);
    if (m.ctx == nullptr)
      throw std::runtime_error(where + "libmodbus refused the settings: " + std::strerror(errno));
    m.mapping = modbus_mapping_new_start_address(
        0, 0, 0, 0, config.start_address, static_cast<unsigned int>(config.register_count), 0, 0);
    if (m.mapping == nullptr)
      throw std::runtime_error(where + "cannot allocate the register table");
    // A master that stops in the middle of a frame cannot hold the line for longer than this.
    modbus_set_indication_timeout(m.ctx, 1, 0);
    modbus_set_byte_timeout(m.ctx, 0, 500'000);
    if (modbus_set_slave(m.ctx, config.unit_id) == -1)
      throw std::invalid_argument(where + "unit_id rejected by libmodbus");
    if (modbus_connect(m.ctx) == -1)
      throw std::runtime_error(where + "cannot open " + endpoint_.device + ": " +
                               modbus_strerror(errno));
    address_ = endpoint_.device;
  } else {
    m.listen_fd = listen_tcp(endpoint_.host, endpoint_.port, std::max(config.max_clients, 64));
    if (m.listen_fd < 0) {
      throw std::runtime_error("modbus server: cannot listen on " +
                               host_port(endpoint_.host, endpoint_.port) + ": " +
                               std::strerror(errno));
    }
    sockaddr_storage bound{};
    socklen_t len = sizeof(bound);
    if (getsockname(m.listen_fd, reinterpret_cast<sockaddr*>(&bound), &len) == -1)
      throw std::runtime_error(where + "getsockname failed: " + std::strerror(errno));
    if (bound.ss_family == AF_INET6) {
      port_ = ntohs(reinterpret_cast<const sockaddr_in6*>(&bound)->sin6_port);
    } else {
      port_ = ntohs(reinterpret_cast<const sockaddr_in*>(&bound)->sin_port);
    }
    address_ = host_port(endpoint_.host, port_);
    m.spare_fd = ::open("/dev/null", O_RDONLY | O_CLOEXEC);
    m.connections.resize(static_cast<std::size_t>(config.max_clients));
    m.polled.reserve(m.connections.size());
    m.request_timeout_ns = seconds_to_ns(config.request_timeout_s);
    m.idle_timeout_ns = seconds_to_ns(config.idle_timeout_s);
    m.evict_idle_ns = seconds_to_ns(config.evict_idle_s);
  }
  m.wake_fd = eventfd(0, EFD_CLOEXEC | EFD_NONBLOCK);
  if (m.wake_fd < 0)
    throw std::runtime_error(where + "eventfd failed: " + std::strerror(errno));
  m.fds.reserve(m.connections.size() + 2);
  thread_ = std::thread([this, rtu] {
    if (rtu)
      run_rtu();
    else
      run_tcp();
  });
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
  for (Connection& c : impl_->connections) {
    if (c.fd >= 0)
      ::close(c.fd);
    c.fd = -1;
  }
  if (impl_->listen_fd >= 0) {
    ::close(impl_->listen_fd);
    impl_->listen_fd = -1;
  }
}

// ---- RTU (libmodbus) ------------------------------------------------------------------------

void ModbusServer::serve_rtu_request(int length) noexcept {
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
    if (fc == kReadHoldingRegisters)
      counters_.reads.fetch_add(1, std::memory_order_relaxed);
    rc = modbus_reply(m.ctx, m.query.data(), length, m.mapping);
  }
  if (rc < 0) {
    counters_.errors.fetch_add(1, std::memory_order_relaxed);
  } else if (rc > 0) {
    counters_.replies.fetch_add(1, std::memory_order_relaxed);
  }
}

void ModbusServer::run_rtu() noexcept {
  Impl& m = *impl_;
  for (;;) {
    pollfd fds[2] = {{m.wake_fd, POLLIN, 0}, {modbus_get_socket(m.ctx), POLLIN, 0}};
    const int n = ::poll(fds, 2, -1);
    if (n < 0) {
      if (errno == EINTR)
        continue;
      counters_.errors.fetch_add(1, std::memory_order_relaxed);
      return;
    }
    if (fds[0].revents != 0)
      return;  // stop()
    const short ev = fds[1].revents;
    if (ev & POLLNVAL) {
      counters_.errors.fetch_add(1, std::memory_order_relaxed);
      return;
    }
    int rc = -1;
    if (ev & POLLIN)
      rc = modbus_receive(m.ctx, m.query.data());
    if (rc > 0) {
      serve_rtu_request(rc);
    } else if (rc < 0 && ev != 0) {
      // Garbage, CRC error or a hung-up line (a pty whose peer closed polls readable for
      // ever): count it and pause briefly instead of spinning.
      counters_.errors.fetch_add(1, std::memory_order_relaxed);
      modbus_flush(m.ctx);
      pollfd wake{m.wake_fd, POLLIN, 0};
      (void)::poll(&wake, 1, 50);
    }
  }
}

// ---- TCP ------------------------------------------------------------------------------------

void ModbusServer::close_connection(Connection& c) noexcept {
  if (c.fd >= 0)
    ::close(c.fd);
  c.fd = -1;
  c.rx_len = 0;
}

// One complete request `adu` (MBAP header valid, `length` bytes in all): its answer.
void ModbusServer::answer(Connection& c, const std::uint8_t* adu, std::size_t length) noexcept {
  Impl& m = *impl_;
  auto& k = counters_;
  constexpr auto kRelaxed = std::memory_order_relaxed;
  k.requests.fetch_add(1, kRelaxed);
  const std::uint8_t* pdu = adu + kMbapBytes;
  const std::size_t pdu_len = length - kMbapBytes;  // >= 1: the function code
  const std::uint8_t fc = pdu[0];
  std::uint8_t* out = m.reply.data();
  std::size_t out_pdu = 0;  // answer's PDU length
  const auto exception = [&](std::uint8_t code) {
    out[kMbapBytes] = static_cast<std::uint8_t>(fc | 0x80);
    out[kMbapBytes + 1] = code;
    out_pdu = 2;
  };
  if (fc == kReadHoldingRegisters) {
    if (pdu_len != 5) {
      k.bad_length.fetch_add(1, kRelaxed);
      exception(kIllegalDataValue);
    } else {
      const std::size_t address = be16(pdu + 1);
      const std::size_t quantity = be16(pdu + 3);
      // Sec. 6.3 state diagram: quantity first (exception 3), then the address range (2).
      if (quantity < 1 || quantity > kModbusMaxReadRegisters) {
        k.illegal_quantity.fetch_add(1, kRelaxed);
        exception(kIllegalDataValue);
      } else if (address < config_.start_address ||
                 address - config_.start_address + quantity > working_.size()) {
        k.illegal_address.fetch_add(1, kRelaxed);
        exception(kIllegalDataAddress);
      } else {
        (void)images_.update();
        const std::vector<std::uint16_t>& image = images_.read_slot();
        const std::size_t first = address - config_.start_address;
        out[kMbapBytes] = fc;
        out[kMbapBytes + 1] = static_cast<std::uint8_t>(2 * quantity);
        for (std::size_t i = 0; i < quantity; ++i)
          put_be16(out + kMbapBytes + 2 + 2 * i, image[first + i]);
        out_pdu = 2 + 2 * quantity;
        k.reads.fetch_add(1, kRelaxed);
      }
    }
  } else if (is_write_function(fc)) {
    k.refused_writes.fetch_add(1, kRelaxed);
    exception(kIllegalFunction);
  } else {
    k.unknown_function.fetch_add(1, kRelaxed);
    exception(kIllegalFunction);
  }
  // MBAP of the answer: the request's transaction id and unit id, length = unit id + PDU.
  out[0] = adu[0];
  out[1] = adu[1];
  put_be16(out + 2, 0);
  put_be16(out + 4, static_cast<std::uint16_t>(1 + out_pdu));
  out[6] = adu[6];
  const std::size_t total = kMbapBytes + out_pdu;
  const ssize_t sent = ::send(c.fd, out, total, MSG_NOSIGNAL | MSG_DONTWAIT);
  if (sent == static_cast<ssize_t>(total)) {
    k.replies.fetch_add(1, kRelaxed);
  } else {
    // The peer does not take its answers (its receive window and our send buffer are full), or
    // the connection broke: never wait for it.
    k.send_failures.fetch_add(1, kRelaxed);
    close_connection(c);
  }
}

bool ModbusServer::serve_connection(Connection& c, bool readable, std::int64_t now_ns) noexcept {
  auto& k = counters_;
  constexpr auto kRelaxed = std::memory_order_relaxed;
  if (readable && c.rx_len < c.rx.size()) {
    const ssize_t n = ::recv(c.fd, c.rx.data() + c.rx_len, c.rx.size() - c.rx_len, MSG_DONTWAIT);
    if (n == 0 || (n < 0 && errno != EAGAIN && errno != EWOULDBLOCK && errno != EINTR)) {
      // EOF or reset: the peer is gone (an unfinished request with it is not counted as one).
      if (n == 0 || errno == ECONNRESET)
        k.clients_closed.fetch_add(1, kRelaxed);
      else
        k.errors.fetch_add(1, kRelaxed);
      close_connection(c);
      return false;
    }
    if (n > 0) {
      if (c.rx_len == 0)
        c.request_start_ns = now_ns;
      c.rx_len += static_cast<std::size_t>(n);
      c.last_activity_ns = now_ns;
    }
  }
  for (int served = 0; served < kRequestsPerRound && c.rx_len >= kMbapBytes; ++served) {
    const std::uint16_t protocol = be16(c.rx.data() + 2);
    const std::size_t length = be16(c.rx.data() + 4);
    if (protocol != 0 || length < kMinMbapLength || length > kMaxMbapLength) {
      k.requests.fetch_add(1, kRelaxed);
      k.malformed_mbap.fetch_add(1, kRelaxed);
      close_connection(c);
      return false;
    }
    const std::size_t adu = 6 + length;
    if (c.rx_len < adu)
      break;  // the rest has not arrived yet
    answer(c, c.rx.data(), adu);
    if (c.fd < 0)
      return false;
    std::memmove(c.rx.data(), c.rx.data() + adu, c.rx_len - adu);
    c.rx_len -= adu;
    c.request_start_ns = now_ns;  // a request that follows started (at the latest) now
  }
  return true;
}

void ModbusServer::accept_clients(std::int64_t now_ns) noexcept {
  Impl& m = *impl_;
  auto& k = counters_;
  constexpr auto kRelaxed = std::memory_order_relaxed;
  for (int round = 0; round < kAcceptsPerRound; ++round) {
    int fd = ::accept4(m.listen_fd, nullptr, nullptr, SOCK_NONBLOCK | SOCK_CLOEXEC);
    if (fd < 0) {
      if ((errno == EMFILE || errno == ENFILE) && m.spare_fd >= 0) {
        // Out of descriptors: take the pending connection with the spare one and close it,
        // else it stays in the backlog and poll() reports it for ever.
        ::close(m.spare_fd);
        fd = ::accept4(m.listen_fd, nullptr, nullptr, SOCK_CLOEXEC);
        if (fd >= 0) {
          k.clients_refused.fetch_add(1, kRelaxed);  // counted before the peer can see it
          ::close(fd);
        }
        m.spare_fd = ::open("/dev/null", O_RDONLY | O_CLOEXEC);
        continue;
      }
      if (errno != EAGAIN && errno != EWOULDBLOCK && errno != EINTR && errno != ECONNABORTED)
        k.errors.fetch_add(1, kRelaxed);
      return;
    }
    Connection* slot = nullptr;
    Connection* idlest = nullptr;
    for (Connection& c : m.connections) {
      if (c.fd < 0) {
        slot = &c;
        break;
      }
      if (c.rx_len == 0 && (idlest == nullptr || c.last_activity_ns < idlest->last_activity_ns))
        idlest = &c;
    }
    if (slot == nullptr && idlest != nullptr &&
        now_ns - idlest->last_activity_ns >= m.evict_idle_ns) {
      k.clients_evicted.fetch_add(1, kRelaxed);  // counted before the peer can see it
      close_connection(*idlest);
      slot = idlest;
    }
    if (slot == nullptr) {
      k.clients_refused.fetch_add(1, kRelaxed);
      ::close(fd);
      continue;
    }
    const int on = 1;
    (void)setsockopt(fd, IPPROTO_TCP, TCP_NODELAY, &on, sizeof(on));
    slot->fd = fd;
    slot->rx_len = 0;
    slot->last_activity_ns = now_ns;
    slot->request_start_ns = 0;
    k.clients_accepted.fetch_add(1, kRelaxed);
  }
}

void ModbusServer::run_tcp() noexcept {
  Impl& m = *impl_;
  auto& k = counters_;
  constexpr auto kRelaxed = std::memory_order_relaxed;
  bool pending = false;  // a connection holds a complete request not answered yet
  for (;;) {
    std::int64_t now = monotonic_ns();
    // Sleep until something arrives, the nearest time-out, or at once if requests wait.
    std::int64_t wait_ns = 1'000'000'000;
    m.fds.clear();
    m.polled.clear();
    m.fds.push_back({m.wake_fd, POLLIN, 0});
    m.fds.push_back({m.listen_fd, POLLIN, 0});
    for (Connection& c : m.connections) {
      if (c.fd < 0)
        continue;
      // A full buffer is not read further until its requests are answered.
      m.fds.push_back({c.fd, static_cast<short>(c.rx_len < c.rx.size() ? POLLIN : 0), 0});
      m.polled.push_back(&c);
      const std::int64_t deadline = c.rx_len > 0 ? c.request_start_ns + m.request_timeout_ns
                                                 : c.last_activity_ns + m.idle_timeout_ns;
      wait_ns = std::min(wait_ns, deadline - now);
    }
    const int timeout_ms =
        pending
            ? 0
            : static_cast<int>(std::clamp<std::int64_t>((wait_ns + 999'999) / 1'000'000, 0, 1000));
    const int n = ::poll(m.fds.data(), m.fds.size(), timeout_ms);
    if (n < 0 && errno != EINTR) {
      k.errors.fetch_add(1, kRelaxed);
      return;
    }
    if (n > 0 && m.fds[0].revents != 0)
      return;  // stop()
    now = monotonic_ns();
    pending = false;
    for (std::size_t i = 0; i < m.polled.size(); ++i) {
      Connection& c = *m.polled[i];
      const short ev = n > 0 ? m.fds[2 + i].revents : 0;
      const bool readable = (ev & (POLLIN | POLLHUP | POLLERR)) != 0;
      if ((readable || c.rx_len >= kMbapBytes) && !serve_connection(c, readable, now))
        continue;
      // Time-outs: an unfinished request (stalled, half-open), or silence.
      if (c.rx_len > 0 && now - c.request_start_ns >= m.request_timeout_ns) {
        k.incomplete.fetch_add(1, kRelaxed);
        close_connection(c);
        continue;
      }
      if (c.rx_len == 0 && now - c.last_activity_ns >= m.idle_timeout_ns) {
        k.idle_closed.fetch_add(1, kRelaxed);
        close_connection(c);
        continue;
      }
      // A complete request, or a malformed header, left (a pipelining client past its share):
      // next round at once.
      if (c.rx_len >= kMbapBytes) {
        const std::size_t length = be16(c.rx.data() + 4);
        if (be16(c.rx.data() + 2) != 0 || length < kMinMbapLength || length > kMaxMbapLength ||
            c.rx_len >= 6 + length) {
          pending = true;
        }
      }
    }
    if (n > 0 && (m.fds[1].revents & POLLIN) != 0)
      accept_clients(now);
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
  const auto& k = counters_;
  ModbusServerCounters c;
  c.requests = k.requests.load(kRelaxed);
  c.replies = k.replies.load(kRelaxed);
  c.reads = k.reads.load(kRelaxed);
  c.refused_writes = k.refused_writes.load(kRelaxed);
  c.unknown_function = k.unknown_function.load(kRelaxed);
  c.bad_length = k.bad_length.load(kRelaxed);
  c.illegal_quantity = k.illegal_quantity.load(kRelaxed);
  c.illegal_address = k.illegal_address.load(kRelaxed);
  c.malformed_mbap = k.malformed_mbap.load(kRelaxed);
  c.incomplete = k.incomplete.load(kRelaxed);
  c.idle_closed = k.idle_closed.load(kRelaxed);
  c.send_failures = k.send_failures.load(kRelaxed);
  c.errors = k.errors.load(kRelaxed);
  c.clients_accepted = k.clients_accepted.load(kRelaxed);
  c.clients_refused = k.clients_refused.load(kRelaxed);
  c.clients_evicted = k.clients_evicted.load(kRelaxed);
  c.clients_closed = k.clients_closed.load(kRelaxed);
  c.publishes = k.publishes.load(kRelaxed);
  c.publishes_rejected = k.publishes_rejected.load(kRelaxed);
  return c;
}

}  // namespace radar_emu::io::modbus
