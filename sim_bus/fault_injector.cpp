#include "sim_bus/fault_injector.hpp"

#include <algorithm>
#include <cmath>
#include <sstream>
#include <stdexcept>
#include <string>

namespace radar_emu::sim_bus {

namespace {

// ---- setup checks ----

template <typename T>
std::string text(T value) {
  std::ostringstream s;
  s << value;
  return s.str();
}

[[noreturn]] void bad(const char* table, const char* field, const std::string& expected,
                      const std::string& got) {
  throw std::invalid_argument(std::string(table) + "." + field + ": expected " + expected +
                              ", got " + got);
}

void check_probability(const char* table, const char* field, double p) {
  if (!(p >= 0.0 && p <= 1.0))
    bad(table, field, "a probability in [0, 1]", text(p));
}

void check_bits(const char* table, const char* field, std::uint32_t bits) {
  if (bits < 1 || bits > kMaxCorruptBits)
    bad(table, field, "1.." + text(kMaxCorruptBits) + " bits", text(bits));
}

void check_window(const char* table, const char* start_field, double start_s, double end_s) {
  if (std::isnan(start_s) || std::isnan(end_s) || !(end_s >= start_s)) {
    bad(table, start_field, "a window with start <= end", text(start_s) + " .. " + text(end_s));
  }
}

// Bus time of scenario time `t_s` (epoch + t in integer ns: a double of a 2020s epoch in ns
// resolves only 256 ns), saturating at the int64 range (infinite ends are allowed).
std::int64_t bus_time_ns(std::int64_t epoch_ns, double t_s) noexcept {
  constexpr auto kMax = std::numeric_limits<std::int64_t>::max();
  constexpr auto kMin = std::numeric_limits<std::int64_t>::min();
  const double offset_ns = t_s * 1e9;
  if (offset_ns >= 9.2e18)
    return kMax;
  if (offset_ns <= -9.2e18)
    return kMin;
  std::int64_t sum = 0;
  if (__builtin_add_overflow(epoch_ns, std::llround(offset_ns), &sum))
    return offset_ns > 0 ? kMax : kMin;
  return sum;
}

// ---- CAN DLC coding (ISO 11898-1:2015, DLC table) ----

constexpr std::array<std::uint8_t, 7> kFdLengths = {12, 16, 20, 24, 32, 48, 64};

// DLC code of the frame's length, or -1 when `len` is not valid for the frame's kind.
int dlc_of(const io::CanFrame& f) noexcept {
  if (f.len <= 8)
    return f.len;
  if (!f.fd)
    return -1;
  for (std::size_t i = 0; i < kFdLengths.size(); ++i) {
    if (kFdLengths[i] == f.len)
      return 9 + static_cast<int>(i);
  }
  return -1;
}

std::uint8_t length_of(int code, bool fd) noexcept {
  if (code <= 8)
    return static_cast<std::uint8_t>(code);
  return fd ? kFdLengths[static_cast<std::size_t>(code - 9)] : std::uint8_t{8};
}

// `k` distinct values uniform in [0, total), k <= min(total, kMaxCorruptBits).
void choose_distinct(std::uint64_t total, std::uint32_t k, FaultRandom& random,
                     std::array<std::uint64_t, kMaxCorruptBits>& out) noexcept {
  for (std::uint32_t i = 0; i < k; ++i) {
    for (;;) {
      const std::uint64_t v = random.below(total);
      bool repeated = false;
      for (std::uint32_t j = 0; j < i; ++j)
        repeated = repeated || out[j] == v;
      if (!repeated) {
        out[i] = v;
        break;
      }
    }
  }
}

bool same_content(const io::CanFrame& a, const io::CanFrame& b) noexcept {
  if (a.id != b.id || a.len != b.len)
    return false;
  for (std::size_t i = 0; i < a.len && i < io::kCanFdMaxBytes; ++i) {
    if (a.data[i] != b.data[i])
      return false;
  }
  return true;
}

}  // namespace

std::uint32_t corrupt_frame(io::CanFrame& frame, std::uint32_t bits, FaultRandom& random) noexcept {
  const std::uint64_t id_bits = frame.extended ? 29 : 11;
  const int dlc = dlc_of(frame);
  const std::uint64_t dlc_bits = dlc >= 0 ? 4 : 0;
  const std::size_t old_len = std::min<std::size_t>(frame.len, io::kCanFdMaxBytes);
  const std::uint64_t total = id_bits + dlc_bits + 8 * old_len;
  const auto k = static_cast<std::uint32_t>(
      std::clamp<std::uint64_t>(bits, 1, std::min<std::uint64_t>(total, kMaxCorruptBits)));
  std::array<std::uint64_t, kMaxCorruptBits> positions{};
  for (int attempt = 0; attempt < 16; ++attempt) {
    io::CanFrame f = frame;
    choose_distinct(total, k, random, positions);
    std::uint32_t id_mask = 0;
    unsigned dlc_mask = 0;
    for (std::uint32_t i = 0; i < k; ++i) {
      const std::uint64_t p = positions[i];
      if (p < id_bits) {
        id_mask |= 1u << p;
      } else if (p < id_bits + dlc_bits) {
        dlc_mask |= 1u << (p - id_bits);
      } else {
        const std::uint64_t d = p - id_bits - dlc_bits;
        f.data[d / 8] = static_cast<std::uint8_t>(f.data[d / 8] ^ (1u << (d % 8)));
      }
    }
    f.id ^= id_mask;
    if (dlc_mask != 0) {
      const std::uint8_t new_len = length_of(dlc ^ static_cast<int>(dlc_mask), f.fd);
      const std::size_t lo = std::min<std::size_t>(new_len, old_len);
      const std::size_t hi = std::max<std::size_t>(new_len, old_len);
      for (std::size_t i = lo; i < hi; ++i)
        f.data[i] = 0;  // bytes past the length are zero (io::CanFrame)
      f.len = new_len;
    }
    if (!same_content(f, frame)) {
      frame = f;
      return k;
    }
  }
  frame.id ^= 1u;  // sixteen draws in a row changed nothing (p < 0.1^16): flip the id's LSB
  return 1;
}

// ---- FaultyCanLink -----------------------------------------------------------------------

void validate(const FaultConfig& c) {
  constexpr const char* t = "faults";
  check_probability(t, "drop_probability", c.drop_probability);
  check_probability(t, "corrupt_probability", c.corrupt_probability);
  check_probability(t, "reorder_probability", c.reorder_probability);
  check_probability(t, "duplicate_probability", c.duplicate_probability);
  check_bits(t, "corrupt_max_bits", c.corrupt_max_bits);
  if (!(c.delay_s >= 0.0 && c.delay_s <= 3600.0))
    bad(t, "delay_s", "0 .. 3600 s", text(c.delay_s));
  if (!(c.jitter_s >= 0.0 && c.jitter_s <= c.delay_s))
    bad(t, "jitter_s", "0 .. delay_s (" + text(c.delay_s) + " s)", text(c.jitter_s));
  if (c.max_held_frames < 1 || c.max_held_frames > (1u << 24))
    bad(t, "max_held_frames", "1 .. 16777216 frames", text(c.max_held_frames));
}

bool no_faults(const FaultConfig& c) noexcept {
  return c.drop_probability <= 0.0 && c.corrupt_probability <= 0.0 &&
         c.reorder_probability <= 0.0 && c.duplicate_probability <= 0.0 && c.delay_s <= 0.0;
}

FaultyCanLink::FaultyCanLink(io::CanEndpoint& inner, const FaultConfig& config)
    : inner_(&inner), config_(config), random_(config.seed), delay_enabled_(config.delay_s > 0.0) {
  validate(config_);
  const std::size_t n = delay_enabled_ ? config_.max_held_frames : 0;
  pool_.resize(n);
  heap_.resize(n);
  free_.resize(n);
  for (std::size_t i = 0; i < n; ++i)
    free_[i] = static_cast<std::uint32_t>(n - 1 - i);
  free_size_ = n;
}

void FaultyCanLink::advance_to(std::int64_t now_ns) noexcept {
  now_ns_ = std::max(now_ns_, now_ns);
  ++advances_;
  if (swap_held_ && advances_ >= swap_advance_ + 2) {
    swap_held_ = false;  // no successor came: deliver it in place
    (void)emit(swap_frame_, std::numeric_limits<std::int64_t>::min());
  }
}

bool FaultyCanLink::send(const io::CanFrame& frame) noexcept {
  return inner_->send(frame);
}

bool FaultyCanLink::receive(io::CanFrame& out) noexcept {
  // Without delay one input frame at a time until something is ready; with delay the whole
  // inner queue (due order can differ from arrival order).
  io::CanFrame in;
  while (ready_size_ == 0 && inner_->receive(in))
    process(in);
  if (ready_size_ > 0) {
    out = ready_[ready_head_];
    ready_head_ = (ready_head_ + 1) % ready_.size();
    --ready_size_;
    ++counters_.frames_out;
    return true;
  }
  if (heap_size_ == 0 || heap_[0].due_ns > now_ns_)
    return false;
  const Due top = heap_[0];
  // Pop the min-heap: last element to the root, then sift down.
  heap_[0] = heap_[--heap_size_];
  std::size_t i = 0;
  for (;;) {
    const std::size_t l = 2 * i + 1, r = l + 1;
    std::size_t m = i;
    if (l < heap_size_ && earlier(heap_[l], heap_[m]))
      m = l;
    if (r < heap_size_ && earlier(heap_[r], heap_[m]))
      m = r;
    if (m == i)
      break;
    std::swap(heap_[i], heap_[m]);
    i = m;
  }
  out = pool_[top.slot];
  out.timestamp_ns = top.due_ns;  // received when due
  free_[free_size_++] = top.slot;
  ++counters_.frames_out;
  return true;
}

void FaultyCanLink::process(const io::CanFrame& frame) noexcept {
  ++counters_.frames_in;
  if (random_.chance(config_.drop_probability)) {
    ++counters_.dropped;
    return;
  }
  io::CanFrame f = frame;
  if (random_.chance(config_.corrupt_probability)) {
    const auto bits = static_cast<std::uint32_t>(1 + random_.below(config_.corrupt_max_bits));
    (void)corrupt_frame(f, bits, random_);
    ++counters_.corrupted;
  }
  constexpr std::int64_t kAny = std::numeric_limits<std::int64_t>::min();
  if (swap_held_) {
    // The held frame follows this one, and never becomes due before it.
    swap_held_ = false;
    const std::int64_t due = emit(f, kAny);
    (void)emit(swap_frame_, due);
    ++counters_.reordered;
    return;
  }
  if (random_.chance(config_.reorder_probability)) {
    swap_frame_ = f;
    swap_held_ = true;
    swap_advance_ = advances_;
    return;
  }
  (void)emit(f, kAny);
}

std::int64_t FaultyCanLink::emit(const io::CanFrame& frame, std::int64_t not_before_ns) noexcept {
  const bool duplicate = random_.chance(config_.duplicate_probability);
  const std::int64_t due = enqueue(frame, not_before_ns);
  if (duplicate) {
    ++counters_.duplicated;
    (void)enqueue(frame, due);  // the copy follows at once
  }
  return due;
}

std::int64_t FaultyCanLink::enqueue(const io::CanFrame& frame,
                                    std::int64_t not_before_ns) noexcept {
  if (!delay_enabled_) {
    (void)push_ready(frame);
    return frame.timestamp_ns;
  }
  double delay_s = config_.delay_s;
  if (config_.jitter_s > 0.0)
    delay_s += config_.jitter_s * (2.0 * random_.uniform() - 1.0);  // uniform in +-jitter
  const std::int64_t due = std::max<std::int64_t>(
      frame.timestamp_ns + std::llround(std::max(delay_s, 0.0) * 1e9), not_before_ns);
  (void)push_due(frame, due);
  return due;
}

bool FaultyCanLink::push_ready(const io::CanFrame& frame) noexcept {
  if (ready_size_ == ready_.size()) {
    ++counters_.held_overflow;  // unreachable by construction (one input yields at most 4)
    return false;
  }
  ready_[(ready_head_ + ready_size_) % ready_.size()] = frame;
  ++ready_size_;
  return true;
}

bool FaultyCanLink::push_due(const io::CanFrame& frame, std::int64_t due_ns) noexcept {
  if (free_size_ == 0) {
    ++counters_.held_overflow;
    return false;
  }
  ++counters_.delayed;
  const std::uint32_t slot = free_[--free_size_];
  pool_[slot] = frame;
  std::size_t i = heap_size_++;
  heap_[i] = Due{due_ns, sequence_++, slot};
  while (i > 0) {
    const std::size_t parent = (i - 1) / 2;
    if (!earlier(heap_[i], heap_[parent]))
      break;
    std::swap(heap_[i], heap_[parent]);
    i = parent;
  }
  return true;
}

// ---- StaleSender -------------------------------------------------------------------------

StaleSender::StaleSender(io::CanEndpoint& inner, const StaleConfig& config)
    : inner_(&inner),
      config_(config),
      start_ns_(bus_time_ns(config.epoch_ns, config.start_s)),
      end_ns_(bus_time_ns(config.epoch_ns, config.end_s)) {
  check_window("stale", "start_s", config.start_s, config.end_s);
  if (config.mode != StaleMode::kSilent && config.mode != StaleMode::kFrozen &&
      config.mode != StaleMode::kFrozenValue) {
    bad("stale", "mode", "silent, frozen or frozen_value", text(static_cast<int>(config.mode)));
  }
  if (config.max_keys < 1 || config.max_keys > 4096)
    bad("stale", "max_keys", "1 .. 4096", text(config.max_keys));
  keys_.resize(config.max_keys);
  last_.resize(config.max_keys);
}

StaleSender::Key StaleSender::key_of(const io::CanFrame& frame) noexcept {
  return Key{frame.id, frame.extended,
             frame.len >= 2 ? static_cast<std::int32_t>(frame.data[1]) : -1};
}

bool StaleSender::send(const io::CanFrame& frame) noexcept {
  const Key key = key_of(frame);
  std::size_t found = key_count_;
  for (std::size_t i = 0; i < key_count_; ++i) {
    if (keys_[i].id == key.id && keys_[i].extended == key.extended && keys_[i].type == key.type) {
      found = i;
      break;
    }
  }
  if (!in_window(frame.timestamp_ns)) {
    if (found < key_count_) {
      last_[found] = frame;
    } else if (key_count_ < keys_.size()) {
      keys_[key_count_] = key;
      last_[key_count_] = frame;
      ++key_count_;
    } else {
      ++counters_.keys_overflow;
    }
    ++counters_.passed;
    return inner_->send(frame);
  }
  if (config_.mode == StaleMode::kSilent || found == key_count_) {
    ++counters_.suppressed;
    return true;
  }
  io::CanFrame replay = last_[found];
  replay.timestamp_ns = frame.timestamp_ns;
  if (config_.mode == StaleMode::kFrozenValue && replay.len >= 4 && frame.len >= 4)
    replay.data[3] = frame.data[3];  // live CANaerospace message code (v1.7 sec. 4.1.4)
  ++counters_.replayed;
  return inner_->send(replay);
}

bool StaleSender::receive(io::CanFrame& out) noexcept {
  return inner_->receive(out);
}

// ---- BabblingNode ------------------------------------------------------------------------

BabblingNode::BabblingNode(const BabbleConfig& config) : config_(config) {
  if (config.extended ? config.id > 0x1FFFFFFFu : config.id > 0x7FFu) {
    bad("babble", "id", config.extended ? "a 29-bit identifier" : "an 11-bit identifier",
        text(config.id));
  }
  if (config.len > io::kCanClassicMaxBytes)
    bad("babble", "len", "0..8 bytes", text(static_cast<int>(config.len)));
  if (!(config.rate_hz > 0.0 && std::isfinite(config.rate_hz)))
    bad("babble", "rate_hz", "a finite rate > 0 Hz", text(config.rate_hz));
  if (!std::isfinite(config.start_s))
    bad("babble", "start_s", "a finite time", text(config.start_s));
  check_window("babble", "start_s", config.start_s, config.end_s);
  if (config.max_frames_per_call < 1)
    bad("babble", "max_frames_per_call", ">= 1", text(config.max_frames_per_call));
}

bool BabblingNode::send_one(io::CanEndpoint& bus, std::int64_t timestamp_ns) noexcept {
  io::CanFrame f;
  f.id = config_.id;
  f.extended = config_.extended;
  f.len = config_.len;
  for (std::size_t i = 0; i < 4 && i < f.len; ++i)
    f.data[i] = static_cast<std::uint8_t>(counter_ >> (24 - 8 * i));
  f.timestamp_ns = timestamp_ns;
  ++counter_;
  if (bus.send(f)) {
    ++counters_.sent;
    return true;
  }
  ++counters_.send_failures;
  return false;
}

std::size_t BabblingNode::send_burst(io::CanEndpoint& bus, std::int64_t timestamp_ns,
                                     std::size_t frames) noexcept {
  std::size_t sent = 0;
  for (std::size_t i = 0; i < frames; ++i)
    sent += send_one(bus, timestamp_ns) ? 1u : 0u;
  return sent;
}

std::size_t BabblingNode::publish_until(double time_s, io::CanEndpoint& bus) noexcept {
  auto due_s = [&](std::uint64_t k) {
    return config_.start_s + static_cast<double>(k) / config_.rate_hz;
  };
  auto is_due = [&](std::uint64_t k) {
    const double t = due_s(k);
    return t <= time_s && t < config_.end_s;
  };
  std::size_t sent = 0, attempted = 0;
  while (is_due(next_index_) && attempted < config_.max_frames_per_call) {
    sent += send_one(bus, bus_time_ns(config_.epoch_ns, due_s(next_index_))) ? 1u : 0u;
    ++attempted;
    ++next_index_;
  }
  if (is_due(next_index_)) {
    // Over the per-call bound: skip what else is due, found in closed form (due_s is monotone
    // in k) and corrected for rounding, so the work stays bounded.
    const double horizon_s = std::min(time_s, config_.end_s) - config_.start_s;
    const double estimate = std::floor(std::min(horizon_s * config_.rate_hz, 1e18));
    std::uint64_t k = std::max(next_index_, static_cast<std::uint64_t>(std::max(estimate, 0.0)));
    while (is_due(k))
      ++k;
    while (k > next_index_ + 1 && !is_due(k - 1))
      --k;
    counters_.skipped += k - next_index_;
    next_index_ = k;
  }
  return sent;
}

// ---- FaultyRegisterBank ------------------------------------------------------------------

FaultyRegisterBank::FaultyRegisterBank(io::RegisterBank& inner, const RegisterFaultConfig& config)
    : inner_(&inner),
      config_(config),
      random_(config.seed),
      frozen_start_ns_(bus_time_ns(config.epoch_ns, config.frozen_start_s)),
      frozen_end_ns_(bus_time_ns(config.epoch_ns, config.frozen_end_s)),
      image_(std::size_t{1} << 16, 0),
      known_(std::size_t{1} << 16, 0) {
  constexpr const char* t = "register_faults";
  check_probability(t, "timeout_probability", config.timeout_probability);
  check_probability(t, "corrupt_probability", config.corrupt_probability);
  check_bits(t, "corrupt_max_bits", config.corrupt_max_bits);
  check_window(t, "frozen_start_s", config.frozen_start_s, config.frozen_end_s);
}

io::RegisterStatus FaultyRegisterBank::read_holding(std::uint16_t address,
                                                    std::span<std::uint16_t> out) noexcept {
  ++counters_.reads;
  if (random_.chance(config_.timeout_probability)) {
    ++counters_.timeouts;
    return io::RegisterStatus::kTimeout;
  }
  if (frozen()) {
    for (std::size_t i = 0; i < out.size(); ++i) {
      const std::size_t a = address + i;
      if (a >= image_.size() || known_[a] == 0) {
        ++counters_.frozen_unknown;
        return io::RegisterStatus::kTimeout;
      }
    }
    for (std::size_t i = 0; i < out.size(); ++i)
      out[i] = image_[address + i];
    ++counters_.frozen_reads;
    return io::RegisterStatus::kOk;
  }
  const io::RegisterStatus status = inner_->read_holding(address, out);
  if (status != io::RegisterStatus::kOk)
    return status;
  for (std::size_t i = 0; i < out.size() && address + i < image_.size(); ++i) {
    image_[address + i] = out[i];
    known_[address + i] = 1;
  }
  if (!out.empty() && random_.chance(config_.corrupt_probability)) {
    const std::uint64_t total = 16 * out.size();
    const auto k = static_cast<std::uint32_t>(std::min<std::uint64_t>(
        1 + random_.below(config_.corrupt_max_bits), std::min<std::uint64_t>(total, 16)));
    std::array<std::uint64_t, kMaxCorruptBits> positions{};
    choose_distinct(total, k, random_, positions);
    for (std::uint32_t i = 0; i < k; ++i) {
      std::uint16_t& reg = out[positions[i] / 16];
      reg = static_cast<std::uint16_t>(reg ^ (1u << (positions[i] % 16)));
    }
    ++counters_.corrupted;
  }
  return io::RegisterStatus::kOk;
}

io::RegisterStatus FaultyRegisterBank::write_holding(
    std::uint16_t address, std::span<const std::uint16_t> values) noexcept {
  ++counters_.writes;
  if (random_.chance(config_.timeout_probability)) {
    ++counters_.timeouts;
    return io::RegisterStatus::kTimeout;
  }
  return inner_->write_holding(address, values);
}

}  // namespace radar_emu::sim_bus
