// Tests of sim_bus/fault_injector: every fault's rate against the binomial distribution (4 sigma),
// delays against their configured bounds, each kind of fault observed in the delivered stream
// (not only counted), windows to the nanosecond, overflow accounting and no allocation after
// construction. Random tests use fixed seeds, printed.

#include <gtest/gtest.h>

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <random>
#include <vector>

#include "common/units.hpp"
#include "io/canaerospace.hpp"
#include "sim_bus/aircraft_player.hpp"
#include "sim_bus/fault_injector.hpp"
#include "sim_bus/loopback_can.hpp"
#include "tests/alloc_counter.hpp"

namespace sb = radar_emu::sim_bus;
namespace io = radar_emu::io;
namespace canas = radar_emu::io::canas;

namespace {

constexpr std::int64_t kEpochNs = 1'767'225'600'000'000'000;  // 2026-01-01T00:00:00Z
constexpr std::int64_t kMs = 1'000'000;

// Frame `seq` of a numbered stream: the sequence number in the payload (little-endian).
io::CanFrame numbered(std::uint64_t seq, std::int64_t timestamp_ns) {
  io::CanFrame f;
  f.id = 0x100 + static_cast<std::uint32_t>(seq % 256);
  f.len = 8;
  for (std::size_t i = 0; i < 8; ++i)
    f.data[i] = static_cast<std::uint8_t>(seq >> (8 * i));
  f.timestamp_ns = timestamp_ns;
  return f;
}

std::uint64_t seq_of(const io::CanFrame& f) {
  std::uint64_t s = 0;
  for (std::size_t i = 0; i < 8; ++i)
    s |= static_cast<std::uint64_t>(f.data[i]) << (8 * i);
  return s;
}

// The sending side of a link, without storage: frame k is stamped t0 + k step and can be
// received once the source's clock has reached its stamp.
class NumberedSource final : public io::CanEndpoint {
 public:
  NumberedSource(std::uint64_t count, std::int64_t t0_ns, std::int64_t step_ns)
      : count_(count), t0_ns_(t0_ns), step_ns_(step_ns) {}
  void release_until(std::int64_t t_ns) { until_ns_ = t_ns; }
  [[nodiscard]] std::int64_t stamp(std::uint64_t k) const {
    return t0_ns_ + static_cast<std::int64_t>(k) * step_ns_;
  }
  bool send(const io::CanFrame&) noexcept override { return false; }
  bool receive(io::CanFrame& out) noexcept override {
    if (next_ >= count_ || stamp(next_) > until_ns_)
      return false;
    out = numbered(next_, stamp(next_));
    ++next_;
    return true;
  }

 private:
  std::uint64_t count_, next_ = 0;
  std::int64_t t0_ns_, step_ns_;
  std::int64_t until_ns_ = std::numeric_limits<std::int64_t>::max();
};

// |observed - n p| <= 4 sqrt(n p (1 - p)): a binomial count within four standard deviations
// (fails by chance with probability 6e-5 for a fair generator; the seeds are fixed).
void expect_binomial(std::uint64_t observed, std::uint64_t n, double p, const char* what) {
  const double mean = static_cast<double>(n) * p;
  const double sigma = std::sqrt(mean * (1.0 - p));
  EXPECT_LE(std::abs(static_cast<double>(observed) - mean), 4.0 * sigma)
      << what << ": " << observed << " of " << n << ", expected " << mean << " +- " << sigma;
}

void expect_conserved(const sb::FaultyCanLink& link) {
  const sb::FaultCounters& c = link.counters();
  EXPECT_EQ(c.frames_in - c.dropped + c.duplicated - c.held_overflow, c.frames_out + link.held());
}

std::vector<io::CanFrame> drain(sb::FaultyCanLink& link) {
  std::vector<io::CanFrame> out;
  io::CanFrame f;
  while (link.receive(f))
    out.push_back(f);
  return out;
}

// A random valid frame: classic or FD, 11- or 29-bit.
io::CanFrame random_frame(std::mt19937_64& rng) {
  static constexpr std::uint8_t kFd[] = {0, 1, 2, 3, 4, 5, 6, 7, 8, 12, 16, 20, 24, 32, 48, 64};
  io::CanFrame f;
  f.extended = rng() % 2 == 0;
  f.id = static_cast<std::uint32_t>(rng() & (f.extended ? 0x1FFFFFFFu : 0x7FFu));
  f.fd = rng() % 3 == 0;
  f.fd_flags = f.fd ? static_cast<std::uint8_t>(rng() % 4) : 0;
  f.len = f.fd ? kFd[rng() % 16] : static_cast<std::uint8_t>(rng() % 9);
  for (std::size_t i = 0; i < f.len; ++i)
    f.data[i] = static_cast<std::uint8_t>(rng());
  f.timestamp_ns = kEpochNs + static_cast<std::int64_t>(rng() % 1'000'000'000);
  return f;
}

bool same_frame(const io::CanFrame& a, const io::CanFrame& b) {
  return a.id == b.id && a.len == b.len && a.extended == b.extended && a.fd == b.fd &&
         a.fd_flags == b.fd_flags && a.data == b.data && a.timestamp_ns == b.timestamp_ns;
}

bool valid_length(const io::CanFrame& f) {
  if (f.len <= 8)
    return true;
  if (!f.fd)
    return false;
  for (int n : {12, 16, 20, 24, 32, 48, 64})
    if (f.len == n)
      return true;
  return false;
}

}  // namespace

TEST(FaultyCanLink, ZeroFaultsIsBitIdenticalPassThrough) {
  const std::uint64_t seed = 20260601;
  std::printf("seed %llu\n", static_cast<unsigned long long>(seed));
  std::mt19937_64 rng(seed);
  sb::LoopbackCanBus bus;
  auto& tx = bus.add_endpoint("tx", 1 << 12);
  auto& rx = bus.add_endpoint("rx", 1 << 12);
  sb::FaultConfig config;
  config.seed = seed;
  ASSERT_TRUE(sb::no_faults(config));
  sb::FaultyCanLink link(rx, config);
  std::vector<io::CanFrame> sent;
  for (int round = 0; round < 50; ++round) {
    link.advance_to(kEpochNs + round * 50 * kMs);
    for (int i = 0; i < 40; ++i) {
      sent.push_back(random_frame(rng));
      ASSERT_TRUE(tx.send(sent.back()));
    }
  }
  const std::vector<io::CanFrame> got = drain(link);
  ASSERT_EQ(got.size(), sent.size());
  for (std::size_t i = 0; i < got.size(); ++i)
    EXPECT_TRUE(same_frame(got[i], sent[i])) << "frame " << i;
  const sb::FaultCounters& c = link.counters();
  EXPECT_EQ(c.frames_in, sent.size());
  EXPECT_EQ(c.frames_out, sent.size());
  EXPECT_EQ(c.dropped + c.delayed + c.corrupted + c.reordered + c.duplicated + c.held_overflow, 0u);
  // send() goes through unchanged.
  const io::CanFrame probe = numbered(7, kEpochNs);
  ASSERT_TRUE(link.send(probe));
  io::CanFrame echo;
  ASSERT_TRUE(tx.receive(echo));
  EXPECT_TRUE(same_frame(echo, probe));
}

TEST(FaultyCanLink, DropRateWithinFourSigmaAndOrderKept) {
  constexpr std::uint64_t kFrames = 100'000;
  for (const double p : {0.01, 0.1, 0.5}) {
    sb::FaultConfig config;
    config.drop_probability = p;
    config.seed = 12345;
    std::printf("drop %.2f seed %llu\n", p, static_cast<unsigned long long>(config.seed));
    NumberedSource source(kFrames, kEpochNs, kMs);
    sb::FaultyCanLink link(source, config);
    std::uint64_t received = 0, last = 0;
    bool in_order = true;
    io::CanFrame f;
    while (link.receive(f)) {
      in_order = in_order && (received == 0 || seq_of(f) > last);
      last = seq_of(f);
      ++received;
    }
    EXPECT_TRUE(in_order);
    EXPECT_EQ(link.counters().frames_in, kFrames);
    EXPECT_EQ(received + link.counters().dropped, kFrames);
    expect_binomial(link.counters().dropped, kFrames, p, "dropped");
    expect_conserved(link);
  }
}

TEST(FaultyCanLink, DuplicatesAndReordersAreCountedAndObserved) {
  constexpr std::uint64_t kFrames = 100'000;
  sb::FaultConfig config;
  config.duplicate_probability = 0.05;
  config.seed = 777;
  std::printf("duplicate seed %llu\n", static_cast<unsigned long long>(config.seed));
  {
    NumberedSource source(kFrames, kEpochNs, kMs);
    sb::FaultyCanLink link(source, config);
    const std::vector<io::CanFrame> got = drain(link);
    std::uint64_t repeats = 0;
    for (std::size_t i = 1; i < got.size(); ++i) {
      if (seq_of(got[i]) == seq_of(got[i - 1])) {
        ++repeats;
        EXPECT_TRUE(same_frame(got[i], got[i - 1]));
      } else {
        EXPECT_EQ(seq_of(got[i]), seq_of(got[i - 1]) + 1);
      }
    }
    EXPECT_EQ(repeats, link.counters().duplicated);
    EXPECT_EQ(got.size(), kFrames + repeats);
    expect_binomial(repeats, kFrames, config.duplicate_probability, "duplicated");
    expect_conserved(link);
  }
  // Reordering: each swap shows as one adjacent inversion (k+1 before k). A frame is held with
  // probability p only while none is held, so swaps per frame are p / (1 + p) on average
  // (two-state Markov chain: free -> held with p, held -> free on the next frame).
  sb::FaultConfig reorder;
  reorder.reorder_probability = 0.2;
  reorder.seed = 4242;
  std::printf("reorder seed %llu\n", static_cast<unsigned long long>(reorder.seed));
  NumberedSource source(kFrames, kEpochNs, kMs);
  sb::FaultyCanLink link(source, reorder);
  std::vector<io::CanFrame> got = drain(link);
  ASSERT_LE(link.held(), 1u);  // the last frame may wait for a successor
  link.advance_to(kEpochNs);
  link.advance_to(kEpochNs);  // a frame held with no successor comes out after two advances
  for (const io::CanFrame& f : drain(link))
    got.push_back(f);
  ASSERT_EQ(got.size(), kFrames);
  std::uint64_t inversions = 0;
  std::vector<bool> seen(kFrames, false);
  for (std::size_t i = 0; i < got.size(); ++i) {
    seen[seq_of(got[i])] = true;
    if (i > 0 && seq_of(got[i]) + 1 == seq_of(got[i - 1]))
      ++inversions;
    // No frame moves by more than one place.
    EXPECT_LE(std::abs(static_cast<double>(seq_of(got[i])) - static_cast<double>(i)), 1.0);
  }
  EXPECT_EQ(std::count(seen.begin(), seen.end(), true), static_cast<long>(kFrames));
  EXPECT_EQ(inversions, link.counters().reordered);
  const double p = reorder.reorder_probability;
  EXPECT_NEAR(static_cast<double>(inversions) / kFrames, p / (1.0 + p), 0.01);
  expect_conserved(link);
}

TEST(FaultyCanLink, DelaysStayWithinJitterBoundsAndAreReleasedInDueOrder) {
  constexpr std::uint64_t kFrames = 20'000;
  sb::FaultConfig config;
  config.delay_s = 5e-3;
  config.jitter_s = 2e-3;  // uniform in [3, 7] ms
  config.seed = 99;
  std::printf("delay seed %llu\n", static_cast<unsigned long long>(config.seed));
  // One frame every 0.25 ms; the loop advances every millisecond and drains.
  NumberedSource source(kFrames, kEpochNs, kMs / 4);
  sb::FaultyCanLink link(source, config);
  std::vector<io::CanFrame> got;
  double sum_delay_s = 0.0;
  bool due_order = true, never_early = true, in_bounds = true;
  for (std::int64_t t = kEpochNs; got.size() < kFrames && t < kEpochNs + 10'000 * kMs; t += kMs) {
    source.release_until(t);
    link.advance_to(t);
    io::CanFrame f;
    while (link.receive(f)) {
      const std::int64_t delay_ns = f.timestamp_ns - source.stamp(seq_of(f));
      in_bounds = in_bounds && delay_ns >= 3 * kMs && delay_ns <= 7 * kMs;
      never_early = never_early && f.timestamp_ns <= t;
      due_order = due_order && (got.empty() || f.timestamp_ns >= got.back().timestamp_ns);
      sum_delay_s += static_cast<double>(delay_ns) * 1e-9;
      got.push_back(f);
    }
  }
  ASSERT_EQ(got.size(), kFrames);
  EXPECT_TRUE(in_bounds);
  EXPECT_TRUE(never_early);
  EXPECT_TRUE(due_order);
  EXPECT_EQ(link.counters().delayed, kFrames);
  // Mean of a uniform on [d - j, d + j]: d, standard deviation j / sqrt(3) per frame.
  const double sigma_mean_s = config.jitter_s / std::sqrt(3.0) / std::sqrt(double(kFrames));
  EXPECT_NEAR(sum_delay_s / kFrames, config.delay_s, 4.0 * sigma_mean_s);
  // With jitter larger than the frame spacing, some frames did overtake others.
  std::uint64_t overtaken = 0;
  for (std::size_t i = 1; i < got.size(); ++i)
    overtaken += seq_of(got[i]) < seq_of(got[i - 1]) ? 1u : 0u;
  EXPECT_GT(overtaken, 0u);
  expect_conserved(link);
}

TEST(FaultyCanLink, FullDelayQueueCountsOverflow) {
  sb::FaultConfig config;
  config.delay_s = 1.0;
  config.max_held_frames = 16;
  NumberedSource source(100, kEpochNs, kMs);
  sb::FaultyCanLink link(source, config);
  link.advance_to(kEpochNs);
  io::CanFrame f;
  EXPECT_FALSE(link.receive(f));  // drains the source into the queue; nothing due yet
  EXPECT_EQ(link.counters().held_overflow, 84u);
  EXPECT_EQ(link.held(), 16u);
  link.advance_to(kEpochNs + 2'000 * kMs);
  const std::vector<io::CanFrame> got = drain(link);
  ASSERT_EQ(got.size(), 16u);
  for (std::size_t i = 0; i < got.size(); ++i) {
    EXPECT_EQ(seq_of(got[i]), i);  // the first 16 were kept, in order
    EXPECT_EQ(got[i].timestamp_ns, source.stamp(i) + 1'000 * kMs);
  }
  expect_conserved(link);
}

TEST(FaultyCanLink, CorruptionAlwaysChangesTheFrameAndKeepsItWellFormed) {
  const std::uint64_t seed = 31337;
  std::printf("corrupt seed %llu\n", static_cast<unsigned long long>(seed));
  std::mt19937_64 rng(seed);
  sb::FaultRandom random(seed);
  std::uint64_t length_changes = 0, id_changes = 0;
  for (int i = 0; i < 20'000; ++i) {
    const io::CanFrame before = random_frame(rng);
    io::CanFrame after = before;
    const auto bits = static_cast<std::uint32_t>(1 + rng() % 4);
    const std::uint32_t flipped = sb::corrupt_frame(after, bits, random);
    ASSERT_EQ(flipped, bits);
    EXPECT_EQ(after.extended, before.extended);
    EXPECT_EQ(after.fd, before.fd);
    EXPECT_EQ(after.timestamp_ns, before.timestamp_ns);
    EXPECT_LE(after.id, before.extended ? 0x1FFFFFFFu : 0x7FFu);
    EXPECT_TRUE(valid_length(after));
    for (std::size_t b = after.len; b < io::kCanFdMaxBytes; ++b)
      ASSERT_EQ(after.data[b], 0) << "byte " << b << " past len " << int(after.len);
    const bool changed = after.id != before.id || after.len != before.len ||
                         std::memcmp(after.data.data(), before.data.data(), after.len) != 0;
    EXPECT_TRUE(changed);
    id_changes += after.id != before.id ? 1u : 0u;
    if (after.len != before.len) {
      ++length_changes;
    } else {
      // Same length: `bits` bits differ across identifier and payload, fewer only where a
      // classic 8-byte frame's DLC flip aliased to 8 again (codes 9..15).
      int diff = std::popcount(after.id ^ before.id);
      for (std::size_t b = 0; b < after.len; ++b)
        diff += std::popcount(static_cast<unsigned>(after.data[b] ^ before.data[b]));
      if (!before.fd && before.len == 8) {
        EXPECT_GE(diff, 1);
        EXPECT_LE(diff, static_cast<int>(bits));
      } else {
        EXPECT_EQ(diff, static_cast<int>(bits));
      }
    }
  }
  EXPECT_GT(length_changes, 0u);
  EXPECT_GT(id_changes, 0u);

  // Through the link: the configured rate (binomial), every corrupted frame differs.
  constexpr std::uint64_t kFrames = 50'000;
  sb::FaultConfig config;
  config.corrupt_probability = 0.2;
  config.corrupt_max_bits = 3;
  config.seed = seed;
  NumberedSource source(kFrames, kEpochNs, kMs);
  sb::FaultyCanLink link(source, config);
  std::uint64_t differing = 0, n = 0;
  io::CanFrame f;
  while (link.receive(f)) {
    const io::CanFrame original = numbered(n, source.stamp(n));
    differing += same_frame(f, original) ? 0u : 1u;
    ++n;
  }
  ASSERT_EQ(n, kFrames);
  EXPECT_EQ(differing, link.counters().corrupted);
  expect_binomial(link.counters().corrupted, kFrames, config.corrupt_probability, "corrupted");
}

TEST(FaultyCanLink, SameSeedSameFaultsAndBadConfigFailsNamingTheField) {
  sb::FaultConfig config;
  config.drop_probability = 0.1;
  config.corrupt_probability = 0.1;
  config.duplicate_probability = 0.1;
  config.reorder_probability = 0.1;
  config.delay_s = 2e-3;
  config.jitter_s = 1e-3;
  config.seed = 5;
  auto run = [](const sb::FaultConfig& c) {
    NumberedSource source(5'000, kEpochNs, kMs / 2);
    sb::FaultyCanLink link(source, c);
    std::vector<io::CanFrame> got;
    for (std::int64_t t = kEpochNs; t < kEpochNs + 3'000 * kMs; t += kMs) {
      source.release_until(t);
      link.advance_to(t);
      for (const io::CanFrame& f : drain(link))
        got.push_back(f);
    }
    return got;
  };
  const auto a = run(config), b = run(config);
  auto same = [](const std::vector<io::CanFrame>& x, const std::vector<io::CanFrame>& y) {
    return x.size() == y.size() && std::equal(x.begin(), x.end(), y.begin(), same_frame);
  };
  EXPECT_TRUE(same(a, b));
  EXPECT_GT(a.size(), 4'000u);
  config.seed = 6;
  EXPECT_FALSE(same(a, run(config)));

  auto message = [](const sb::FaultConfig& bad) -> std::string {
    try {
      sb::validate(bad);
    } catch (const std::invalid_argument& e) {
      return e.what();
    }
    return "";
  };
  sb::FaultConfig bad;
  bad.drop_probability = 1.5;
  EXPECT_EQ(message(bad), "faults.drop_probability: expected a probability in [0, 1], got 1.5");
  bad = {};
  bad.delay_s = 1e-3;
  bad.jitter_s = 2e-3;
  EXPECT_NE(message(bad).find("faults.jitter_s: expected 0 .. delay_s"), std::string::npos);
  bad = {};
  bad.corrupt_max_bits = 0;
  EXPECT_NE(message(bad).find("faults.corrupt_max_bits"), std::string::npos);
  bad = {};
  bad.max_held_frames = 0;
  NumberedSource source(1, 0, 1);
  EXPECT_THROW((void)sb::FaultyCanLink(source, bad), std::invalid_argument);
}

namespace {

// The scripted INS on a bus, through a StaleSender, received and decoded by the radar.
struct StaleRig {
  explicit StaleRig(const sb::StaleConfig& config)
      : ins(bus.add_endpoint("ins", 1 << 14)),
        radar(bus.add_endpoint("radar", 1 << 14)),
        stale(ins, config),
        player(trajectory(), sb::PlayerConfig{1, 80.0, 10.0, kEpochNs}) {}
  static sb::Trajectory trajectory() {
    sb::AircraftState a, b;
    a.time_s = 0.0;
    a.pitch_rad = 0.01;
    a.height_m = 500.0;
    a.latitude_rad = 0.76;
    b = a;
    b.time_s = 10.0;
    b.pitch_rad = 0.05;
    b.height_m = 300.0;
    b.latitude_rad = 0.761;
    return sb::Trajectory({a, b});
  }
  sb::LoopbackCanBus bus;
  sb::LoopbackEndpoint& ins;
  sb::LoopbackEndpoint& radar;
  sb::StaleSender stale;
  sb::AircraftStatePlayer player;
};

}  // namespace

TEST(StaleSender, SilentWindowSuppressesExactlyItsFrames) {
  sb::StaleConfig config;
  config.mode = sb::StaleMode::kSilent;
  config.start_s = 1.0;  // an attitude and a navigation instant (80 Hz and 10 Hz grids)
  config.end_s = 2.0;
  config.epoch_ns = kEpochNs;
  StaleRig rig(config);
  const std::size_t published = rig.player.publish_until(3.0, rig.stale);
  // 0..3 s inclusive: 241 attitude instants x 3 frames + 31 navigation instants x 8 frames.
  ASSERT_EQ(published, 241u * 3 + 31u * 8);
  // In [1, 2): 80 attitude and 10 navigation instants.
  const std::uint64_t in_window = 80u * 3 + 10u * 8;
  EXPECT_EQ(rig.stale.counters().suppressed, in_window);
  EXPECT_EQ(rig.stale.counters().passed, published - in_window);
  std::uint64_t at_start = 0, at_end = 0;
  io::CanFrame f;
  while (rig.radar.receive(f)) {
    EXPECT_FALSE(f.timestamp_ns >= kEpochNs + 1'000 * kMs &&
                 f.timestamp_ns < kEpochNs + 2'000 * kMs);
    at_start += f.timestamp_ns == kEpochNs + 1'000 * kMs ? 1u : 0u;
    at_end += f.timestamp_ns == kEpochNs + 2'000 * kMs ? 1u : 0u;
  }
  EXPECT_EQ(at_start, 0u);
  EXPECT_EQ(at_end, 3u + 8u);  // the instant at end_s is sent (window end exclusive)
  EXPECT_EQ(rig.ins.sent(), published - in_window);
}

TEST(StaleSender, FrozenReplaysLastValuesWithFrozenOrLiveMessageCode) {
  for (const sb::StaleMode mode : {sb::StaleMode::kFrozen, sb::StaleMode::kFrozenValue}) {
    sb::StaleConfig config;
    config.mode = mode;
    config.start_s = 1.0;
    config.end_s = 2.0;
    config.epoch_ns = kEpochNs;
    StaleRig rig(config);
    canas::Decoder decoder;
    const sb::Trajectory traj = StaleRig::trajectory();
    // Last instants before the window: attitude 0.9875 s, navigation 0.9 s.
    // Degrees as the player converts, a float on the bus, radians as the decoder converts.
    const double frozen_pitch_rad = radar_emu::common::radians(static_cast<double>(
        static_cast<float>(radar_emu::common::degrees(traj.at(0.9875).pitch_rad))));
    const double frozen_height_m = static_cast<double>(static_cast<float>(traj.at(0.9).height_m));
    std::uint64_t gaps_before = 0;
    for (std::int64_t t_ms = 50; t_ms <= 3'000; t_ms += 50) {  // 50 ms loop frames
      const double t = static_cast<double>(t_ms) / 1000.0;
      (void)rig.player.publish_until(t, rig.stale);
      io::CanFrame f;
      while (rig.radar.receive(f))
        (void)decoder.decode(f, f.timestamp_ns);
      if (t_ms == 950)
        gaps_before = decoder.counters().message_code_gaps;
      if (t_ms >= 1'000 && t_ms < 2'000) {
        EXPECT_DOUBLE_EQ(decoder.state()[canas::Field::kPitch].value, frozen_pitch_rad) << t;
        EXPECT_DOUBLE_EQ(decoder.state()[canas::Field::kHeight].value, frozen_height_m) << t;
        if (mode == sb::StaleMode::kFrozenValue) {
          // Live message codes: the frames are taken as new and the reception time stamps stay
          // live, so a freshness check alone cannot see this frozen node.
          const std::int64_t last_attitude_ns = (t_ms * kMs / 12'500'000) * 12'500'000;
          EXPECT_EQ(decoder.state()[canas::Field::kPitch].updated_ns, kEpochNs + last_attitude_ns);
        } else {
          // Frozen codes repeat the last message: not taken, so the fields age (last attitude
          // frame before the window: 0.9875 s) and the state goes stale after the timeout.
          EXPECT_EQ(decoder.state()[canas::Field::kPitch].updated_ns, kEpochNs + 987'500'000);
        }
      }
      if (t_ms >= 2'000) {  // after the window the live values come back
        EXPECT_NE(decoder.state()[canas::Field::kPitch].value, frozen_pitch_rad);
      }
    }
    EXPECT_EQ(gaps_before, 0u);
    EXPECT_EQ(rig.stale.counters().replayed, 80u * 3 + 10u * 8);
    EXPECT_EQ(rig.stale.counters().suppressed, 0u);
    EXPECT_EQ(decoder.counters().unpaired_double,
              0u);  // DOUBLEH and DOUBLEL replay their own halves
    if (mode == sb::StaleMode::kFrozenValue) {
      EXPECT_EQ(decoder.counters().message_code_gaps, 0u);  // invisible to the code check
    } else {
      // Each replayed frame repeats its code: every one of them is a repetition (a DOUBLEH
      // repeats the code of the last completed pair, its DOUBLEL the identifier's last code),
      // none is a gap; after the window the first frame on each identifier (3 attitude + 6
      // navigation) breaks the sequence once.
      EXPECT_EQ(decoder.counters().repeated_message_code, 80u * 3 + 10u * 8);
      EXPECT_EQ(decoder.counters().message_code_gaps, 3u + 6u);
    }
  }
}

TEST(BabblingNode, FloodOverflowsBoundedQueueAndRadarKeepsDecoding) {
  sb::LoopbackCanBus bus;
  auto& ins = bus.add_endpoint("ins", 1 << 14);
  auto& babbler_ep = bus.add_endpoint("babbler", 16);
  auto& radar = bus.add_endpoint("radar", 512);
  sb::AircraftStatePlayer player(StaleRig::trajectory(), sb::PlayerConfig{1, 80.0, 10.0, kEpochNs});
  sb::BabbleConfig bc;
  bc.id = 5;  // CANaerospace emergency-event range: wins every arbitration on a real bus
  bc.rate_hz = 100'000.0;
  bc.epoch_ns = kEpochNs;
  bc.max_frames_per_call = 1'000;
  sb::BabblingNode babbler(bc);
  canas::Decoder decoder;
  std::uint64_t babble_seen = 0;
  bool always_fresh = true;
  for (std::int64_t t_ms = 50; t_ms <= 2'000; t_ms += 50) {
    const double t = static_cast<double>(t_ms) / 1000.0;
    (void)player.publish_until(t, ins);  // the INS's frames are queued first
    (void)babbler.publish_until(t, babbler_ep);
    io::CanFrame f;
    while (radar.receive(f)) {
      babble_seen += f.id == bc.id ? 1u : 0u;
      (void)decoder.decode(f, f.timestamp_ns);
    }
    const std::int64_t now = kEpochNs + t_ms * kMs;
    always_fresh = always_fresh && decoder.state().all_fresh(now, 150 * kMs);
  }
  EXPECT_TRUE(always_fresh);
  // Due by 2 s at 100 kHz from 0: 200001 frames; 1000 a call are sent, the rest skipped.
  EXPECT_EQ(babbler.counters().sent, 40u * 1'000);
  EXPECT_EQ(babbler.counters().sent + babbler.counters().skipped, 200'001u);
  EXPECT_GT(radar.rx_overflows(), 0u);
  EXPECT_EQ(babble_seen + radar.rx_overflows(), babbler.counters().sent);
  EXPECT_EQ(decoder.counters().ignored_id, babble_seen);
  EXPECT_EQ(decoder.counters().rejected(), 0u);

  // A burst without rate limit.
  sb::BabblingNode burst(bc);
  EXPECT_EQ(burst.send_burst(babbler_ep, kEpochNs, 10'000), 10'000u);
  EXPECT_EQ(radar.pending(), 512u);
  EXPECT_THROW((void)sb::BabblingNode(sb::BabbleConfig{.id = 0x800}), std::invalid_argument);
}

namespace {

class ArrayBank final : public io::RegisterBank {
 public:
  std::array<std::uint16_t, 1000> regs{};
  io::RegisterStatus read_holding(std::uint16_t address,
                                  std::span<std::uint16_t> out) noexcept override {
    if (address + out.size() > regs.size())
      return io::RegisterStatus::kIllegalAddress;
    std::copy_n(regs.begin() + address, out.size(), out.begin());
    return io::RegisterStatus::kOk;
  }
  io::RegisterStatus write_holding(std::uint16_t address,
                                   std::span<const std::uint16_t> values) noexcept override {
    if (address + values.size() > regs.size())
      return io::RegisterStatus::kIllegalAddress;
    std::copy(values.begin(), values.end(), regs.begin() + address);
    return io::RegisterStatus::kOk;
  }
};

}  // namespace

TEST(FaultyRegisterBank, TimeoutsCorruptionAndFrozenImage) {
  ArrayBank bank;
  for (std::size_t i = 0; i < bank.regs.size(); ++i)
    bank.regs[i] = static_cast<std::uint16_t>(3 * i + 1);
  sb::RegisterFaultConfig config;
  config.timeout_probability = 0.2;
  config.corrupt_probability = 0.3;
  config.corrupt_max_bits = 4;
  config.frozen_start_s = 10.0;
  config.frozen_end_s = 20.0;
  config.epoch_ns = kEpochNs;
  config.seed = 2718;
  std::printf("register seed %llu\n", static_cast<unsigned long long>(config.seed));
  sb::FaultyRegisterBank faulty(bank, config);
  faulty.advance_to(kEpochNs);
  constexpr int kReads = 100'000;
  std::uint64_t timeouts = 0, corrupted = 0, ok = 0;
  bool bits_in_range = true, untouched_on_timeout = true;
  std::array<std::uint16_t, 8> out{};
  for (int i = 0; i < kReads; ++i) {
    const auto address = static_cast<std::uint16_t>(i % 990);
    out.fill(0xABCD);
    const io::RegisterStatus s = faulty.read_holding(address, out);
    if (s == io::RegisterStatus::kTimeout) {
      ++timeouts;
      for (std::uint16_t v : out)
        untouched_on_timeout = untouched_on_timeout && v == 0xABCD;
      continue;
    }
    ASSERT_EQ(s, io::RegisterStatus::kOk);
    ++ok;
    int diff = 0;
    for (std::size_t k = 0; k < out.size(); ++k)
      diff += std::popcount(static_cast<unsigned>(out[k] ^ bank.regs[address + k]));
    corrupted += diff > 0 ? 1u : 0u;
    bits_in_range = bits_in_range && diff <= 4;
  }
  EXPECT_TRUE(untouched_on_timeout);
  EXPECT_TRUE(bits_in_range);
  EXPECT_EQ(timeouts, faulty.counters().timeouts);
  EXPECT_EQ(corrupted, faulty.counters().corrupted);
  expect_binomial(timeouts, kReads, 0.2, "register timeouts");
  expect_binomial(corrupted, ok, 0.3, "register corruption");

  // Frozen window [10, 20) s: reads return the last image although the device changed.
  sb::RegisterFaultConfig frozen_config;
  frozen_config.frozen_start_s = 10.0;
  frozen_config.frozen_end_s = 20.0;
  frozen_config.epoch_ns = kEpochNs;
  sb::FaultyRegisterBank frozen(bank, frozen_config);
  std::array<std::uint16_t, 4> before{}, during{};
  frozen.advance_to(kEpochNs + 9'999 * kMs);
  ASSERT_EQ(frozen.read_holding(100, before), io::RegisterStatus::kOk);
  const std::array<std::uint16_t, 4> changed = {1, 2, 3, 4};
  frozen.advance_to(kEpochNs + 10'000 * kMs);  // window start: inclusive
  ASSERT_EQ(frozen.write_holding(100, changed), io::RegisterStatus::kOk);  // writes pass
  EXPECT_EQ(bank.regs[100], 1);
  ASSERT_EQ(frozen.read_holding(100, during), io::RegisterStatus::kOk);
  EXPECT_EQ(during, before);
  EXPECT_EQ(frozen.read_holding(500, during), io::RegisterStatus::kTimeout);  // never read
  EXPECT_EQ(frozen.counters().frozen_reads, 1u);
  EXPECT_EQ(frozen.counters().frozen_unknown, 1u);
  frozen.advance_to(kEpochNs + 20'000 * kMs);  // window end: exclusive
  ASSERT_EQ(frozen.read_holding(100, during), io::RegisterStatus::kOk);
  EXPECT_EQ(during, changed);
  EXPECT_EQ(frozen.read_holding(999, during), io::RegisterStatus::kIllegalAddress);
}

TEST(FaultInjection, NothingAllocatesAfterConstruction) {
  sb::LoopbackCanBus bus;
  auto& ins = bus.add_endpoint("ins", 1 << 12);
  auto& babbler_ep = bus.add_endpoint("babbler", 16);
  auto& radar = bus.add_endpoint("radar", 1 << 12);
  sb::AircraftStatePlayer player(StaleRig::trajectory(), sb::PlayerConfig{1, 80.0, 10.0, kEpochNs});
  sb::StaleConfig stale_config{sb::StaleMode::kFrozen, 0.5, 0.8, kEpochNs, 64};
  sb::StaleSender stale(ins, stale_config);
  sb::BabbleConfig bc;
  bc.id = 3;
  bc.rate_hz = 2'000.0;
  bc.epoch_ns = kEpochNs;
  sb::BabblingNode babbler(bc);
  sb::FaultConfig fc;
  fc.drop_probability = 0.05;
  fc.delay_s = 3e-3;
  fc.jitter_s = 2e-3;
  fc.corrupt_probability = 0.05;
  fc.corrupt_max_bits = 5;
  fc.reorder_probability = 0.05;
  fc.duplicate_probability = 0.05;
  fc.max_held_frames = 64;  // small: overflow happens too
  sb::FaultyCanLink link(radar, fc);
  ArrayBank bank;
  sb::RegisterFaultConfig rc;
  rc.timeout_probability = 0.1;
  rc.corrupt_probability = 0.1;
  rc.frozen_start_s = 0.5;
  rc.frozen_end_s = 0.7;
  rc.epoch_ns = kEpochNs;
  sb::FaultyRegisterBank faulty_bank(bank, rc);
  canas::Decoder decoder;
  std::array<std::uint16_t, 16> regs{};
  std::uint64_t received = 0;

  radar_emu::test::start_counting_allocations();
  for (std::int64_t t_ms = 50; t_ms <= 2'000; t_ms += 50) {
    const double t = static_cast<double>(t_ms) / 1000.0;
    const std::int64_t now = kEpochNs + t_ms * kMs;
    (void)player.publish_until(t, stale);
    (void)babbler.publish_until(t, babbler_ep);
    link.advance_to(now);
    io::CanFrame f;
    while (link.receive(f)) {
      ++received;
      (void)decoder.decode(f, f.timestamp_ns);
    }
    faulty_bank.advance_to(now);
    (void)faulty_bank.read_holding(10, regs);
    (void)faulty_bank.write_holding(20, regs);
  }
  const std::uint64_t allocations = radar_emu::test::stop_counting_allocations();
  EXPECT_EQ(allocations, 0u);
  EXPECT_GT(received, 0u);
  EXPECT_GT(link.counters().held_overflow, 0u);
  EXPECT_GT(stale.counters().replayed, 0u);
  expect_conserved(link);
}
