#include "timing/profiler.hpp"

#include <algorithm>
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
  s.sum_ns += static_cast<long double>(duration_ns);
}

StageSummary StageProfiler::summary(Stage stage) const {
  const auto& s = series_[static_cast<std::size_t>(stage)];
  StageSummary out;
  out.count = s.count;
  if (s.count == 0)
    return out;
  const std::size_t stored = static_cast<std::size_t>(std::min<std::uint64_t>(s.count, capacity_));
  std::vector<std::int64_t> samples(s.ring_ns.begin(),
                                    s.ring_ns.begin() + static_cast<std::ptrdiff_t>(stored));
  out.p50_s = seconds_from_ns(percentile_ns(samples, 50.0));
  out.p99_s = seconds_from_ns(percentile_ns(samples, 99.0));
  out.max_s = seconds_from_ns(s.max_ns);
  out.mean_s = static_cast<double>(s.sum_ns / static_cast<long double>(s.count)) * 1e-9;
  return out;
}

}  // namespace radar_emu::timing
