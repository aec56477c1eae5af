// Software CAN bus throughput (issue 6): frames per second through sim_bus's loopback bus, one
// sender and 2 or 3 receivers draining, plain, through a FaultyCanLink with no faults, and with
// 10 % drop plus 1 ms +- 0.5 ms delay. items_per_second counts frames sent (each delivered to
// every receiver); delivered_per_second counts frames handed to receivers. Goal: >= 100 000
// frames/s with no loss. Each run checks its own bookkeeping and fails (SkipWithError) when a
// frame was lost without a fault injected, or when the fault counters do not add up.
// Run: build/bench/bench_sim_bus --benchmark_repetitions=3 --benchmark_report_aggregates_only=true

#include <benchmark/benchmark.h>

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "io/canaerospace.hpp"
#include "sim_bus/fault_injector.hpp"
#include "sim_bus/loopback_can.hpp"

namespace sb = radar_emu::sim_bus;
namespace io = radar_emu::io;

namespace {

enum Mode : int { kPlain = 0, kLinkNoFaults = 1, kDropJitter = 2 };

constexpr std::size_t kBatch = 256;               // frames sent between two drains
constexpr std::int64_t kFrameSpacingNs = 10'000;  // bus time between frames: 100 000 frames/s
constexpr std::size_t kQueue = 4096;              // receive queue per endpoint [frames]

void BM_LoopbackBus(benchmark::State& state, Mode mode) {
  const auto receivers = static_cast<std::size_t>(state.range(0));
  sb::LoopbackCanBus bus;
  sb::LoopbackEndpoint& tx = bus.add_endpoint("ins", 16);
  std::vector<sb::LoopbackEndpoint*> rx;
  std::vector<std::unique_ptr<sb::FaultyCanLink>> links;
  sb::FaultConfig faults;
  if (mode == kDropJitter) {
    faults.drop_probability = 0.1;
    faults.delay_s = 1e-3;
    faults.jitter_s = 0.5e-3;
    faults.seed = 6;
  }
  for (std::size_t r = 0; r < receivers; ++r) {
    rx.push_back(&bus.add_endpoint("rx" + std::to_string(r), kQueue));
    if (mode != kPlain) {
      faults.seed += r;
      links.push_back(std::make_unique<sb::FaultyCanLink>(*rx.back(), faults));
    }
  }
  std::vector<io::CanEndpoint*> drains;
  for (std::size_t r = 0; r < receivers; ++r) {
    drains.push_back(mode == kPlain ? static_cast<io::CanEndpoint*>(rx[r])
                                    : static_cast<io::CanEndpoint*>(links[r].get()));
  }

  std::int64_t now_ns = 1'767'225'600'000'000'000;
  std::uint8_t code = 0;
  std::uint64_t sent = 0, delivered = 0;
  std::vector<std::uint64_t> per_receiver(receivers, 0);
  io::CanFrame frame;
  auto drain_all = [&] {
    for (auto& link : links)
      link->advance_to(now_ns);
    for (std::size_t r = 0; r < receivers; ++r) {
      while (drains[r]->receive(frame)) {
        ++per_receiver[r];
        benchmark::DoNotOptimize(frame.data[4]);
      }
    }
  };
  for (auto _ : state) {
    for (std::size_t i = 0; i < kBatch; ++i) {
      io::CanFrame f =
          io::canas::encode_float(io::canas::id::kPitchAngle, 1, code++, static_cast<float>(i));
      now_ns += kFrameSpacingNs;
      f.timestamp_ns = now_ns;
      sent += tx.send(f) ? 1u : 0u;
    }
    drain_all();
  }
  // Everything still delayed is released: the books must balance exactly.
  now_ns += 1'000'000'000;
  drain_all();
  for (std::uint64_t n : per_receiver)
    delivered += n;
  state.SetItemsProcessed(static_cast<std::int64_t>(sent));
  state.counters["delivered_per_second"] =
      benchmark::Counter(static_cast<double>(delivered), benchmark::Counter::kIsRate);
  for (std::size_t r = 0; r < receivers; ++r) {
    if (rx[r]->rx_overflows() != 0) {
      state.SkipWithError("receive queue overflowed");
      return;
    }
    if (mode != kDropJitter && per_receiver[r] != sent) {
      state.SkipWithError("frames lost without a fault injected");
      return;
    }
    if (mode != kPlain) {
      const sb::FaultCounters& c = links[r]->counters();
      if (c.frames_in != sent || c.frames_out != per_receiver[r] ||
          c.frames_in - c.dropped + c.duplicated - c.held_overflow != c.frames_out ||
          links[r]->held() != 0) {
        state.SkipWithError("fault counters do not add up");
        return;
      }
      if (mode == kDropJitter) {
        state.counters["dropped_fraction"] =
            static_cast<double>(c.dropped) / static_cast<double>(c.frames_in);
      }
    }
  }
}

}  // namespace

BENCHMARK_CAPTURE(BM_LoopbackBus, plain, kPlain)
    ->ArgName("receivers")
    ->DenseRange(2, 3)
    ->Unit(benchmark::kMicrosecond);
BENCHMARK_CAPTURE(BM_LoopbackBus, faulty_link_no_faults, kLinkNoFaults)
    ->ArgName("receivers")
    ->DenseRange(2, 3)
    ->Unit(benchmark::kMicrosecond);
BENCHMARK_CAPTURE(BM_LoopbackBus, drop10_delay1ms_jitter05ms, kDropJitter)
    ->ArgName("receivers")
    ->DenseRange(2, 3)
    ->Unit(benchmark::kMicrosecond);

BENCHMARK_MAIN();
