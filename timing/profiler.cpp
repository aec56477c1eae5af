#include "timing/profiler.hpp"

#include <algorithm>
#include <bit>
#include <cmath>
#include <stdexcept>

namespace radar_emu::timing {

std::string_view stage_name(Stage stage) noexcept {
  switch (stage) {
    case Stage::kInput:
      return "input";
    case Stage::kSceneUpdate:
      return "scene_update";
    case Stage::kTrace:
      return "trace";
    case Stage::kSensor:
      return "sensor";
    case Stage::kOutput:
      return "output";
    case Stage::kFrame:
      return "frame";
    case Stage::kWakeLatency:
      return "wake_latency";
    case Stage::kCount:
      break;
  }
  return "unknown";
}

std::int64_t percentile_ns(std::vector<std::int64_t>& samples_ns, double p) {
  if (samples_ns.empty())
    return 0;
  std::sort(samples_ns.begin(), samples_ns.end());
  // Nearest rank: the smallest value such that at least p% of the samples are <= it.
  const double n = static_cast<double>(samples_ns.size());
  auto rank = static_cast<std::size_t>(std::ceil(std::clamp(p, 0.0, 100.0) / 100.0 * n));
  rank = std::clamp<std::size_t>(rank, 1, samples_ns.size());
  return samples_ns[rank - 1];
}

std::size_t DurationHistogram::bin_of(std::int64_t value_ns) noexcept {
  constexpr std::uint64_t kSub = std::uint64_t{1} << kSubBits;
  const std::uint64_t v = value_ns > 0 ? static_cast<std::uint64_t>(value_ns) : 0;
  if (v < kSub)
    return static_cast<std::size_t>(v);
  const int exponent =
      static_cast<int>(std::bit_width(v)) - 1;  // v in [2^exponent, 2^(exponent + 1))
  if (exponent >= kMaxExponent)
    return kBins - 1;
  const int shift = exponent - kSubBits;
  // v >> shift is in [2^kSubBits, 2^(kSubBits + 1)): the octave's sub-bin, offset by one octave.
  return static_cast<std::size_t>(shift) * kSub + static_cast<std::size_t>(v >> shift);
}

std::int64_t DurationHistogram::bin_low_ns(std::size_t bin) noexcept {
  constexpr std::size_t kSub = std::size_t{1} << kSubBits;
  if (bin < kSub)
    return static_cast<std::int64_t>(bin);
  const std::size_t shift = bin / kSub - 1;
  return static_cast<std::int64_t>((bin - shift * kSub) << shift);
}

std::int64_t DurationHistogram::bin_width_ns(std::size_t bin) noexcept {
  constexpr std::size_t kSub = std::size_t{1} << kSubBits;
  return bin < kSub ? 1 : std::int64_t{1} << (bin / kSub - 1);
}

void DurationHistogram::add(std::int64_t value_ns) noexcept {
  ++bins_[bin_of(value_ns)];
  min_ns_ = count_ == 0 ? value_ns : std::min(min_ns_, value_ns);
  max_ns_ = count_ == 0 ? value_ns : std::max(max_ns_, value_ns);
  ++count_;
}

std::int64_t DurationHistogram::percentile_ns(double p) const noexcept {
  if (count_ == 0)
    return 0;
  // Nearest rank, as timing::percentile_ns() on the samples themselves.
  const double n = static_cast<double>(count_);
  auto rank = static_cast<std::uint64_t>(std::ceil(std::clamp(p, 0.0, 100.0) / 100.0 * n));
  rank = std::clamp<std::uint64_t>(rank, 1, count_);
  if (rank == 1)
    return min_ns_;  // the extremes are known exactly
  if (rank == count_)
    return max_ns_;
  std::uint64_t seen = 0;
  for (std::size_t b = 0; b < kBins; ++b) {
    seen += bins_[b];
    if (seen >= rank) {
      const std::int64_t mid = bin_low_ns(b) + (bin_width_ns(b) - 1) / 2;
      return std::clamp(mid, min_ns_, max_ns_);
    }
  }
  return max_ns_;
}

StageProfiler::StageProfiler(std::size_t capacity_frames, std::size_t event_capacity)
    : capacity_(capacity_frames) {
  if (capacity_frames == 0)
    throw std::invalid_argument("StageProfiler: capacity_frames must be > 0");
  for (auto& s : series_)
    s.ring_ns.resize(capacity_frames, 0);
  events_.resize(event_capacity);
}

void StageProfiler::record_span(Stage stage, std::int64_t start_ns, std::int64_t end_ns) noexcept {
  record(stage, end_ns - start_ns);
  if (events_.empty())
    return;
  if (events_used_ == events_.size()) {
    ++events_dropped_;
    return;
  }
  events_[events_used_++] = StageEvent{frame_, start_ns, end_ns - start_ns, stage};
}

std::vector<std::int64_t> StageProfiler::history_ns(Stage stage) const {
  const auto& s = series_[static_cast<std::size_t>(stage)];
  const std::size_t stored = static_cast<std::size_t>(std::min<std::uint64_t>(s.count, capacity_));
  std::vector<std::int64_t> out;
  out.reserve(stored);
  // The ring's oldest sample is at `next` once it has wrapped, at 0 before.
  const std::size_t first = s.count > capacity_ ? s.next : 0;
  for (std::size_t i = 0; i < stored; ++i)
    out.push_back(s.ring_ns[(first + i) % capacity_]);
  return out;
}

void StageProfiler::record(Stage stage, std::int64_t duration_ns) noexcept {
  auto& s = series_[static_cast<std::size_t>(stage)];
  s.ring_ns[s.next] = duration_ns;
  s.next = (s.next + 1) % capacity_;
  ++s.count;
  s.max_ns = std::max(s.max_ns, duration_ns);
  s.last_ns = duration_ns;
  s.sum_ns += static_cast<long double>(duration_ns);
  s.histogram.add(duration_ns);
}

StageSummary StageProfiler::summary(Stage stage) const {
  const auto& s = series_[static_cast<std::size_t>(stage)];
  StageSummary out;
  out.count = s.count;
  if (s.count == 0)
    return out;
  if (s.count <= capacity_) {
    // Every sample is still in the ring: exact percentiles.
    std::vector<std::int64_t> samples(s.ring_ns.begin(),
                                      s.ring_ns.begin() + static_cast<std::ptrdiff_t>(s.count));
    out.p50_s = seconds_from_ns(percentile_ns(samples, 50.0));
    out.p99_s = seconds_from_ns(percentile_ns(samples, 99.0));
  } else {
    out.p50_s = seconds_from_ns(s.histogram.percentile_ns(50.0));
    out.p99_s = seconds_from_ns(s.histogram.percentile_ns(99.0));
    out.percentiles_exact = false;
  }
  out.max_s = seconds_from_ns(s.max_ns);
  out.mean_s = static_cast<double>(s.sum_ns / static_cast<long double>(s.count)) * 1e-9;
  return out;
}

}  // namespace radar_emu::timing
