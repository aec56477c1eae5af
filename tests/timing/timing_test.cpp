// Tests of timing/: clocks, the fixed-rate scheduler and the stage profiler. No test asserts
// how long anything takes on this machine (timing.md): the scheduler is driven by the
// simulated clock, and the wall clock is checked only for ordering.

#include <gtest/gtest.h>

#include <cstdint>
#include <vector>

#include "timing/clock.hpp"
#include "timing/profiler.hpp"
#include "timing/realtime.hpp"
#include "timing/scheduler.hpp"

namespace rt = radar_emu::timing;

namespace {
constexpr std::int64_t kPeriod_ns = 50'000'000;  // 20 Hz
}

TEST(SimulatedClock, SleepJumpsForwardNeverBack) {
  rt::SimulatedClock clock(1000);
  clock.sleep_until_ns(500);
  EXPECT_EQ(clock.now_ns(), 1000);
  clock.sleep_until_ns(2500);
  EXPECT_EQ(clock.now_ns(), 2500);
  clock.advance_ns(-10);
  EXPECT_EQ(clock.now_ns(), 2500);
  clock.advance_ns(7);
  EXPECT_EQ(clock.now_ns(), 2507);
}

TEST(MonotonicClock, NeverGoesBackAndSleepReachesDeadline) {
  rt::MonotonicClock clock;
  std::int64_t prev = clock.now_ns();
  for (int i = 0; i < 1000; ++i) {
    const std::int64_t now = clock.now_ns();
    ASSERT_GE(now, prev);
    prev = now;
  }
  const std::int64_t deadline = clock.now_ns() + 2'000'000;
  clock.sleep_until_ns(deadline);
  EXPECT_GE(clock.now_ns(), deadline);             // an absolute sleep never returns early
  clock.sleep_until_ns(deadline - 1'000'000'000);  // past deadline: returns at once
  EXPECT_GE(clock.now_ns(), deadline);
}

TEST(FixedRateScheduler, DeadlinesAreExactMultiplesOfThePeriod) {
  // 1/3 s cannot be represented in binary floating point; in integer ns the grid is exact.
  const std::int64_t period = 333'333'333;
  const std::int64_t start = 1'700'000'000LL * rt::kNanosecondsPerSecond;
  rt::SimulatedClock clock(start);
  rt::FixedRateScheduler sched(clock, period, start);
  for (std::uint64_t k = 0; k < 100'000; ++k) {
    const rt::Tick t = sched.wait_next();
    ASSERT_EQ(t.period_index, k);
    ASSERT_EQ(t.deadline_ns, start + static_cast<std::int64_t>(k) * period);
    ASSERT_EQ(t.wake_ns, t.deadline_ns);
    ASSERT_FALSE(t.late);
  }
  EXPECT_EQ(sched.missed_periods(), 0u);
  EXPECT_EQ(sched.overruns(), 0u);
}

TEST(FixedRateScheduler, WorkOfExactlyOnePeriodIsOnTime) {
  rt::SimulatedClock clock(0);
  rt::FixedRateScheduler sched(clock, kPeriod_ns, 0);
  (void)sched.wait_next();
  clock.advance_ns(kPeriod_ns);  // ends exactly at the next deadline
  const rt::Tick t = sched.wait_next();
  EXPECT_FALSE(t.late);
  EXPECT_EQ(t.period_index, 1u);
  EXPECT_EQ(sched.overruns(), 0u);
}

TEST(FixedRateScheduler, OverrunSkipsWholePeriodsWithoutBurst) {
  rt::SimulatedClock clock(0);
  rt::FixedRateScheduler sched(clock, kPeriod_ns, 0);
  (void)sched.wait_next();               // frame at deadline 0
  clock.advance_ns(kPeriod_ns * 5 / 2);  // 2.5 periods of work
  // Deadline 1 (at 1 P) ended entirely before now (2.5 P >= 1 P + P): skipped. Deadline 2 (2 P)
  // is still running: the frame starts at once, late, on deadline 2.
  rt::Tick t = sched.wait_next();
  EXPECT_TRUE(t.late);
  EXPECT_EQ(t.missed_before, 1u);
  EXPECT_EQ(t.period_index, 2u);
  EXPECT_EQ(t.deadline_ns, 2 * kPeriod_ns);
  EXPECT_EQ(t.wake_ns, kPeriod_ns * 5 / 2);
  // No catch-up burst: with no further work the next frames come one per period on the grid.
  for (std::uint64_t k = 3; k < 8; ++k) {
    t = sched.wait_next();
    EXPECT_FALSE(t.late);
    EXPECT_EQ(t.period_index, k);
    EXPECT_EQ(t.wake_ns, static_cast<std::int64_t>(k) * kPeriod_ns);
  }
  EXPECT_EQ(sched.missed_periods(), 1u);
  EXPECT_EQ(sched.overruns(), 1u);
}

TEST(FixedRateScheduler, LongStallCountsEveryMissedPeriod) {
  rt::SimulatedClock clock(0);
  rt::FixedRateScheduler sched(clock, kPeriod_ns, 0);
  (void)sched.wait_next();
  clock.advance_ns(10 * kPeriod_ns + 1);  // just past deadline 10
  const rt::Tick t = sched.wait_next();
  // Deadlines 1..9 ended entirely (now >= d_k + P for k <= 9); deadline 10 is running.
  EXPECT_EQ(t.missed_before, 9u);
  EXPECT_EQ(t.period_index, 10u);
  EXPECT_EQ(sched.missed_periods(), 9u);
}

TEST(Percentile, NearestRankOnKnownSamples) {
  std::vector<std::int64_t> s;
  for (std::int64_t i = 100; i >= 1; --i)
    s.push_back(i);  // 1..100, unsorted
  EXPECT_EQ(rt::percentile_ns(s, 50.0), 50);
  EXPECT_EQ(rt::percentile_ns(s, 99.0), 99);
  EXPECT_EQ(rt::percentile_ns(s, 100.0), 100);
  EXPECT_EQ(rt::percentile_ns(s, 0.0), 1);
  std::vector<std::int64_t> three{30, 10, 20};
  EXPECT_EQ(rt::percentile_ns(three, 50.0), 20);  // rank ceil(1.5) = 2
  std::vector<std::int64_t> empty;
  EXPECT_EQ(rt::percentile_ns(empty, 50.0), 0);
}

TEST(StageProfiler, SummaryOfKnownDurations) {
  rt::StageProfiler prof(1000);
  for (std::int64_t i = 1; i <= 100; ++i)
    prof.record(rt::Stage::kTrace, i * 1'000'000);  // 1..100 ms
  const rt::StageSummary s = prof.summary(rt::Stage::kTrace);
  EXPECT_EQ(s.count, 100u);
  EXPECT_DOUBLE_EQ(s.p50_s, 0.050);
  EXPECT_DOUBLE_EQ(s.p99_s, 0.099);
  EXPECT_DOUBLE_EQ(s.max_s, 0.100);
  EXPECT_NEAR(s.mean_s, 0.0505, 1e-12);
  EXPECT_EQ(prof.summary(rt::Stage::kSensor).count, 0u);
}

TEST(StageProfiler, PercentilesCoverTheWholeRunBeyondTheRing) {
  rt::StageProfiler prof(10);
  prof.record(rt::Stage::kInput, 1'000'000'000);  // one huge early sample, then 10 small ones
  for (int i = 0; i < 10; ++i)
    prof.record(rt::Stage::kInput, 1000);
  const rt::StageSummary s = prof.summary(rt::Stage::kInput);
  EXPECT_EQ(s.count, 11u);
  EXPECT_FALSE(s.percentiles_exact);  // 11 samples, a ring of 10: from the histogram
  // Nearest rank over all 11 samples: p99 is rank ceil(10.89) = 11, the 1 s sample (clamped to
  // the maximum); p50 is rank 6, a 1000 ns sample (bin width 8 ns at 1000: midpoint 1003).
  EXPECT_DOUBLE_EQ(s.p99_s, 1.0);
  EXPECT_NEAR(s.p50_s, 1e-6, 1e-6 / 256.0);
  EXPECT_DOUBLE_EQ(s.max_s, 1.0);
  EXPECT_EQ(prof.history_ns(rt::Stage::kInput).size(), 10u);  // the ring: the last 10
  EXPECT_EQ(prof.last_ns(rt::Stage::kInput), 1000);
  EXPECT_EQ(prof.last_ns(rt::Stage::kTrace), -1);
}

TEST(DurationHistogram, BinsAreExactBelow128AndAtMost1Over128OfTheValueWideAbove) {
  using H = rt::DurationHistogram;
  EXPECT_EQ(H::bin_of(0), 0u);
  EXPECT_EQ(H::bin_of(-5), 0u);
  EXPECT_EQ(H::bin_of(127), 127u);
  EXPECT_EQ(H::bin_of(128), 128u);
  EXPECT_EQ(H::bin_of(255), 255u);
  EXPECT_EQ(H::bin_of(256), 256u);  // next octave: bins 2 ns wide
  EXPECT_EQ(H::bin_of(257), 256u);
  EXPECT_EQ(H::bin_of(258), 257u);
  EXPECT_EQ(H::bin_of(std::int64_t{1} << 50), H::kBins - 1);  // beyond 2^41 ns: the last bin
  // Every bin holds exactly the values [low, low + width), the bins tile the axis without gaps,
  // and a bin is at most 1/128 of its lowest value wide.
  for (std::size_t b = 0; b + 1 < H::kBins; ++b) {
    const std::int64_t lo = H::bin_low_ns(b), w = H::bin_width_ns(b);
    ASSERT_EQ(H::bin_of(lo), b);
    ASSERT_EQ(H::bin_of(lo + w - 1), b);
    ASSERT_EQ(H::bin_low_ns(b + 1), lo + w) << b;
    if (lo >= 128) {
      ASSERT_LE(static_cast<double>(w) / static_cast<double>(lo), 1.0 / 128.0);
    }
  }
}

TEST(DurationHistogram, PercentilesOfAUniformRampWithinHalfABin) {
  // 1, 2, ..., 100000 us: the nearest-rank p50 is 50000 us and p99 99000 us exactly; the
  // histogram returns its bin's midpoint, within half a bin (1/256 of the value).
  rt::DurationHistogram h;
  for (std::int64_t i = 1; i <= 100'000; ++i)
    h.add(i * 1000);
  EXPECT_EQ(h.count(), 100'000u);
  EXPECT_NEAR(static_cast<double>(h.percentile_ns(50.0)), 50'000'000.0, 50'000'000.0 / 256.0);
  EXPECT_NEAR(static_cast<double>(h.percentile_ns(99.0)), 99'000'000.0, 99'000'000.0 / 256.0);
  EXPECT_EQ(h.percentile_ns(100.0), 100'000'000);  // clamped to the maximum
  EXPECT_EQ(h.percentile_ns(0.0), 1000);           // rank 1: the minimum
  EXPECT_EQ(rt::DurationHistogram{}.percentile_ns(50.0), 0);
}

TEST(StageProfiler, ScopedStageRecordsClockDifference) {
  rt::SimulatedClock clock(0);
  rt::StageProfiler prof(4);
  {
    rt::ScopedStage stage(prof, clock, rt::Stage::kOutput);
    clock.advance_ns(1234);
  }
  EXPECT_DOUBLE_EQ(prof.summary(rt::Stage::kOutput).max_s, 1234e-9);
}

TEST(Realtime, RefusalsAreWarningsNotCrashes) {
  rt::RealtimeOptions opt;
  opt.cpu = 100000;  // no such CPU: must be refused with a warning
  opt.flush_denormals = false;
  const rt::RealtimeReport r = rt::bring_up_realtime(opt);
  EXPECT_FALSE(r.pinned);
  ASSERT_EQ(r.warnings.size(), 1u);
  EXPECT_NE(r.warnings[0].find("CPU affinity"), std::string::npos);
}

TEST(StageProfiler, SpansAreKeptInOrderUpToTheBoundThenCounted) {
  rt::StageProfiler prof(4, 3);
  prof.set_frame(7);
  prof.record_span(rt::Stage::kInput, 100, 150);
  prof.record_span(rt::Stage::kFrame, 90, 400);
  prof.set_frame(8);
  prof.record_span(rt::Stage::kTrace, 500, 530);
  prof.record_span(rt::Stage::kSensor, 530, 560);  // beyond the 3 kept: counted
  prof.record(rt::Stage::kOutput, 5);              // a duration alone is no span
  const auto ev = prof.events();
  ASSERT_EQ(ev.size(), 3u);
  EXPECT_EQ(prof.events_dropped(), 1u);
  EXPECT_EQ(ev[0].frame, 7u);
  EXPECT_EQ(ev[0].stage, rt::Stage::kInput);
  EXPECT_EQ(ev[0].start_ns, 100);
  EXPECT_EQ(ev[0].duration_ns, 50);
  EXPECT_EQ(ev[1].duration_ns, 310);
  EXPECT_EQ(ev[2].frame, 8u);
  EXPECT_EQ(ev[2].stage, rt::Stage::kTrace);
  // The durations still reach the summaries, dropped span included.
  EXPECT_EQ(prof.summary(rt::Stage::kSensor).count, 1u);
  // No event capacity: nothing kept, nothing counted.
  rt::StageProfiler none(4);
  none.record_span(rt::Stage::kInput, 0, 10);
  EXPECT_TRUE(none.events().empty());
  EXPECT_EQ(none.events_dropped(), 0u);
}

TEST(StageProfiler, HistoryIsInRecordingOrderAfterTheRingWraps) {
  rt::StageProfiler prof(3);
  for (std::int64_t v : {1, 2, 3, 4, 5})
    prof.record(rt::Stage::kFrame, v);
  EXPECT_EQ(prof.history_ns(rt::Stage::kFrame), (std::vector<std::int64_t>{3, 4, 5}));
  rt::StageProfiler short_run(5);
  short_run.record(rt::Stage::kFrame, 9);
  short_run.record(rt::Stage::kFrame, 8);
  EXPECT_EQ(short_run.history_ns(rt::Stage::kFrame), (std::vector<std::int64_t>{9, 8}));
  EXPECT_TRUE(short_run.history_ns(rt::Stage::kTrace).empty());
}
