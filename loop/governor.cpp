#include "loop/governor.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "common/units.hpp"

namespace radar_emu::loop {

// Measured with `build/app/radar-emu tradeoff --cases frame` (series governor_level: mean
// |SNR error| of the detections matched to the reference frame's, pooled over four frames of the
// default approach at t = 0, 3, 6, 9 s; docs/performance.md, "The fidelity governor"), on the
// default scene without corner reflectors, edges on, terrain from the terrain engine (the
// default since 2026-11-28; reference: 0.25 deg engine columns):
//   level     0     1     2     3     4     5     6     8    10
//   dB     2.67  3.72  3.40  5.25  5.07  8.18  6.56  6.46  5.56
// (at the coarse levels the matched set shrinks to the strongest detections, 37 of 46 missed at
// level 10, so their mean error falls). Made non-decreasing (a level is never estimated better
// than a finer one); levels 7 and 9 take the next measured level's value, levels past 10 the
// largest measured.
const std::array<double, FidelityGovernor::kMaxLevel + 1> FidelityGovernor::kLevelSnrError_db = {
    2.67, 3.72, 3.72, 5.25, 5.25, 8.18, 8.18, 8.18, 8.18,
    8.18, 8.18, 8.18, 8.18, 8.18, 8.18, 8.18, 8.18};

namespace {

void require(bool ok, const char* field, const char* rule) {
  if (!ok)
    throw std::invalid_argument(std::string("[governor] ") + field + " " + rule);
}

double db10(double x) noexcept {
  return common::db_from_power(std::max(x, 1e-300));
}

}  // namespace

FidelityGovernor::FidelityGovernor(const GovernorConfig& config, const scene::Scene& scene,
                                   const radar::SbrTracer& tracer, const radar::Sensor& sensor,
                                   double frame_period_s)
    : config_(config), scene_(&scene), tracer_(&tracer), sensor_(&sensor) {
  require(std::isfinite(config.compute_fraction) && config.compute_fraction > 0.0 &&
              config.compute_fraction <= 1.0,
          "compute_fraction", "must be in (0, 1]");
  require(std::isfinite(config.trace_ns_per_ray) && config.trace_ns_per_ray > 0.0,
          "trace_ns_per_ray", "must be > 0");
  require(std::isfinite(config.trace_ms_per_frame) && config.trace_ms_per_frame >= 0.0,
          "trace_ms_per_frame", "must be >= 0");
  require(std::isfinite(config.trace_ns_per_facet) && config.trace_ns_per_facet >= 0.0,
          "trace_ns_per_facet", "must be >= 0");
  require(std::isfinite(config.trace_ns_per_kept_return) && config.trace_ns_per_kept_return >= 0.0,
          "trace_ns_per_kept_return", "must be >= 0");
  require(std::isfinite(config.sensor_ns_per_cell) && config.sensor_ns_per_cell >= 0.0,
          "sensor_ns_per_cell", "must be >= 0");
  require(std::isfinite(config.sensor_ns_per_return) && config.sensor_ns_per_return >= 0.0,
          "sensor_ns_per_return", "must be >= 0");
  require(std::isfinite(config.sensor_ns_per_unmerged_return) &&
              config.sensor_ns_per_unmerged_return >= 0.0,
          "sensor_ns_per_unmerged_return", "must be >= 0");
  require(std::isfinite(config.sensor_ns_per_terrain_return) &&
              config.sensor_ns_per_terrain_return >= 0.0,
          "sensor_ns_per_terrain_return", "must be >= 0");
  require(std::isfinite(config.terrain_ns_per_patch) && config.terrain_ns_per_patch >= 0.0,
          "terrain_ns_per_patch", "must be >= 0");
  require(config.max_level >= 0 && config.max_level <= kMaxLevel, "max_level", "must be in 0..16");
  require(std::isfinite(frame_period_s) && frame_period_s > 0.0, "frame period", "must be > 0");
  deadline_ms_ = config.compute_fraction * frame_period_s * 1e3;
  const std::size_t n = scene.objects().size();
  // Each target's mean projected area over all directions: a quarter of its surface for a
  // convex body (Cauchy's surface area formula), used as its size in the ranking.
  mean_area_m2_.assign(n, 0.0);
  const scene::SceneDescription& desc = scene.description();
  for (std::uint32_t id = 0; id < n; ++id) {
    if (!tracer.is_target(id))
      continue;
    targets_.push_back(id);
    if (id >= desc.objects.size())
      continue;
    const scene::ObjectDesc& o = desc.objects[id];
    const glm::dmat3 linear(o.world_from_body);
    double area_m2 = 0.0;
    for (const auto& t : o.mesh.triangles) {
      const glm::dvec3 a = linear * glm::dvec3(o.mesh.positions_m[t[0]]);
      const glm::dvec3 b = linear * glm::dvec3(o.mesh.positions_m[t[1]]);
      const glm::dvec3 c = linear * glm::dvec3(o.mesh.positions_m[t[2]]);
      area_m2 += 0.5 * glm::length(glm::cross(b - a, c - a));
    }
    mean_area_m2_[id] = 0.25 * area_m2;
  }
  rank_.assign(n, 0);
  spacing_m_.assign(n, 0.0);
  // The loop's frame primed at setup (static path reuse) is traced at the scenario's spacing.
  last_spacing_m_.assign(n, tracer.config().target_ray_spacing_m);
  lagging_.reserve(targets_.size());
  rays_per_object_.assign(n, 0);
  decision_.deadline_ms = deadline_ms_;
  // Before the first frame the sensor's work is unknown: assume the worst (every cell of the
  // image synthesised) and half a return a ray, so the first frame errs on the early side.
  prev_cells_ = static_cast<double>(sensor.antenna().beams() * sensor.processor().range_bins() *
                                    sensor.processor().velocity_bins());
  prev_rays_ = 2.0;
  prev_returns_ = 1.0;
  decision_.knobs.target_ray_spacing_m = spacing_m_;
}

double FidelityGovernor::model_trace_ms(const radar::TracePlan& plan) const noexcept {
  // The rays and the kept returns, and the terrain engine's patches: the previous frame's, as
  // the square of the patch size scale it used over this level's (TerrainReturns::compute's
  // scale), at least one a facet. The facets, those of the level of detail the engine takes at
  // this level.
  const double s = prev_terrain_scale_ / decision_.knobs.terrain_spacing_scale;
  const double facets = prev_terrain_facets_ *
                        terrain_facet_ratio_at(decision_.knobs.terrain_spacing_scale) /
                        prev_terrain_facet_ratio_;
  const double patches = std::max(facets, prev_terrain_patches_ * s * s);
  return config_.trace_ms_per_frame +
         1e-6 * (config_.trace_ns_per_facet * static_cast<double>(plan.target_facets) +
                 config_.trace_ns_per_ray * static_cast<double>(plan.rays()) +
                 config_.trace_ns_per_kept_return * static_cast<double>(plan.reused_contributions) +
                 config_.terrain_ns_per_patch * patches);
}

std::size_t FidelityGovernor::terrain_cells_merged(int level) const noexcept {
  return radar::TerrainReturns::cell_merge(std::pow(2.0, 0.25 * std::clamp(level, 0, kMaxLevel)),
                                           terrain_.azimuth_merge_max)
      .cells();
}

double FidelityGovernor::terrain_facet_ratio_at(double scale) const noexcept {
  const radar::TerrainCellMerge m =
      radar::TerrainReturns::cell_merge(scale, terrain_.azimuth_merge_max);
  return terrain_.lod_merge > 0 && m.range >= terrain_.lod_merge && terrain_.lod_facet_ratio > 0.0
             ? terrain_.lod_facet_ratio
             : 1.0;
}

double FidelityGovernor::terrain_facet_ratio(int level) const noexcept {
  return terrain_facet_ratio_at(std::pow(2.0, 0.25 * std::clamp(level, 0, kMaxLevel)));
}

double FidelityGovernor::model_sensor_ms(const radar::TracePlan& plan) const noexcept {
  // The sensor's work follows the previous frame's: its cells (set by the clutter's extent, not
  // by the rays), its ray returns (in proportion to the rays, traced or kept) and the engine's
  // returns (in inverse proportion to the cells its coarse cells merge).
  const auto rays = static_cast<double>(plan.rays() + plan.reused_rays);
  const double ray_returns = std::max(0.0, prev_returns_ - prev_terrain_returns_);
  const double merge =
      static_cast<double>(radar::TerrainReturns::cell_merge(decision_.knobs.terrain_spacing_scale,
                                                            terrain_.azimuth_merge_max)
                              .cells());
  const double returns = prev_rays_ > 0.0 ? ray_returns * rays / prev_rays_ : 0.0;
  const double terrain_returns = prev_terrain_returns_ * prev_terrain_merge_ / merge;
  return 1e-6 * (config_.sensor_ns_per_cell * prev_cells_ + config_.sensor_ns_per_return * returns +
                 config_.sensor_ns_per_unmerged_return * returns * prev_unmerged_fraction_ +
                 config_.sensor_ns_per_terrain_return * terrain_returns);
}

radar::TracePlan FidelityGovernor::plan_for(const radar::RadarPose& pose) noexcept {
  ++decision_.plans;
  return tracer_->plan(pose, decision_.knobs);
}

double FidelityGovernor::predict_ms(const radar::TracePlan& plan) const noexcept {
  return trace_factor_ * model_trace_ms(plan) + sensor_factor_ * model_sensor_ms(plan);
}

double FidelityGovernor::target_spacing_m(std::uint32_t id, int level) const noexcept {
  const int l = level + std::min(rank_[id], level);
  return tracer_->config().target_ray_spacing_m * std::pow(2.0, 0.5 * l);
}

int FidelityGovernor::level_of_spacings(int from) const noexcept {
  for (int level = from; level < kMaxLevel; ++level) {
    bool fine_enough = true;
    for (std::uint32_t id : targets_)
      fine_enough = fine_enough && spacing_m_[id] <= target_spacing_m(id, level) * (1.0 + 1e-9);
    if (fine_enough)
      return level;
  }
  return kMaxLevel;
}

int FidelityGovernor::refine_with_kept(const radar::RadarPose& pose, int min_level, int level,
                                       radar::TracePlan& plan, double& predicted) noexcept {
  const bool deferred = decision_.knobs.defer_refresh;  // `plan` was made with it
  const std::span<const scene::ObjectState> objects = scene_->objects();
  for (int l = min_level; l < level; ++l) {
    knobs_for(l);
    // The static targets whose kept paths are coarser than level l asks (lagging_).
    lagging_.clear();
    for (std::uint32_t id : targets_) {
      if (!objects[id].moving && last_spacing_m_[id] > spacing_m_[id] * (1.0 + 1e-9))
        lagging_.push_back(id);
    }
    if (lagging_.empty())
      continue;  // level l itself: it did not fit
    // Their rays at level l (what tracing them again costs), then the mix: they keep theirs.
    ++decision_.plans;
    (void)tracer_->plan(pose, decision_.knobs, rays_per_object_);
    for (std::uint32_t id : lagging_)
      spacing_m_[id] = last_spacing_m_[id];
    radar::TracePlan mixed = plan_for(pose);
    double cost = predict_ms(mixed);
    if (cost > deadline_ms_)
      continue;
    // The strongest first (lowest rank, then object id), while their rays fit: a weaker target
    // never goes before a stronger one.
    std::sort(lagging_.begin(), lagging_.end(), [&](std::uint32_t a, std::uint32_t b) {
      return rank_[a] != rank_[b] ? rank_[a] < rank_[b] : a < b;  // std::sort: no allocation
    });
    double room = deadline_ms_ - cost;
    std::size_t upgraded = 0;
    for (; upgraded < lagging_.size(); ++upgraded) {
      const std::uint32_t id = lagging_[upgraded];
      const double extra_ms = trace_factor_ * config_.trace_ns_per_ray * 1e-6 *
                              static_cast<double>(rays_per_object_[id]);
      if (extra_ms > room)
        break;
      room -= extra_ms;
      spacing_m_[id] = target_spacing_m(id, l);
    }
    // The estimate leaves out the sensor's share of their returns: the weakest go back while
    // the whole is over the deadline.
    if (upgraded > 0) {
      mixed = plan_for(pose);
      cost = predict_ms(mixed);
      while (cost > deadline_ms_ && upgraded > 0) {
        const std::uint32_t id = lagging_[--upgraded];
        spacing_m_[id] = last_spacing_m_[id];
        mixed = plan_for(pose);
        cost = predict_ms(mixed);
      }
    }
    plan = mixed;
    predicted = cost;
    return level_of_spacings(l);
  }
  knobs_for(level);  // nothing finer: the level as chosen, its refresh as it was
  decision_.knobs.defer_refresh = deferred;
  return level;
}

void FidelityGovernor::knobs_for(int level) noexcept {
  const radar::SbrConfig& c = tracer_->config();
  // Level 0 is the scenario's fidelity for every target; above it the weaker targets coarsen
  // faster (by their rank, at most by the level itself).
  for (std::uint32_t id : targets_)
    spacing_m_[id] = target_spacing_m(id, level);
  radar::TraceKnobs& k = decision_.knobs;
  k.target_ray_spacing_m = spacing_m_;
  k.terrain_spacing_scale = std::pow(2.0, 0.25 * level);
  k.max_bounces =
      level >= kBounceLevel ? std::max(std::min(2, c.max_bounces), c.max_bounces - 1) : 0;
  k.facet_centroid_only = level >= kFacetLevel;
  k.defer_refresh = false;
}

const GovernorDecision& FidelityGovernor::decide(const radar::RadarPose& pose) noexcept {
  // Rank the targets by expected SNR (header).
  const std::span<const scene::ObjectState> objects = scene_->objects();
  const glm::dmat3 antenna_from_world = glm::transpose(pose.world_from_antenna);
  double best_db = -1e300;
  for (std::uint32_t id : targets_) {
    const scene::ObjectState& o = objects[id];
    const glm::dvec3 los = 0.5 * (o.bounds_min_m + o.bounds_max_m) - pose.position_m;
    const double range_m = glm::length(los);
    double snr_db = -1e300;
    if (range_m > 1e-6) {
      const glm::dvec3 u = los / range_m;
      const double area_m2 = mean_area_m2_[id];
      const radar::AzEl ae = radar::azel_from_direction(antenna_from_world * u);
      snr_db = db10(sensor_->expected_snr(std::max(area_m2, 1e-6), range_m) *
                    sensor_->two_way_gain(0.0, ae.elevation_rad));
    }
    spacing_m_[id] = snr_db;  // scratch until the ranks are set
    best_db = std::max(best_db, snr_db);
  }
  for (std::uint32_t id : targets_) {
    const double below_db = best_db - spacing_m_[id];
    rank_[id] = std::clamp(static_cast<int>(std::floor(below_db / kRankStep_db)), 0, kMaxRank);
  }

  return choose(pose, 0, config_.enabled ? config_.max_level : 0);
}

const GovernorDecision& FidelityGovernor::decide_at(const radar::RadarPose& pose,
                                                    int level) noexcept {
  (void)decide(pose);  // ranks the targets
  const int l = std::clamp(level, 0, kMaxLevel);
  return choose(pose, l, l);
}

const GovernorDecision& FidelityGovernor::choose(const radar::RadarPose& pose, int min_level,
                                                 int max_level) noexcept {
  GovernorDecision& d = decision_;
  d.plans = 0;
  knobs_for(0);
  const radar::TracePlan full = plan_for(pose);
  d.full_rays = full.rays();
  int level = min_level;
  if (level > 0)
    knobs_for(level);
  radar::TracePlan plan = level > 0 ? plan_for(pose) : full;
  double predicted = predict_ms(plan);
  // The finest level that fits (the cost falls with the level: one plan per level tried).
  std::array<double, kMaxLevel + 1> predicted_at{};
  std::array<radar::TracePlan, kMaxLevel + 1> plan_at{};
  std::array<bool, kMaxLevel + 1> deferred_at{};
  std::array<bool, kMaxLevel + 1> known{};  // predicted_at set
  // Over the deadline, a level first defers the refresh of kept paths (TraceKnobs): the same
  // fidelity, the kept paths a frame older.
  auto defer_if_late = [&] {
    if (predicted <= deadline_ms_ || !config_.enabled || !tracer_->config().reuse_static_paths)
      return;
    d.knobs.defer_refresh = true;
    const radar::TracePlan deferred = plan_for(pose);
    const double p = predict_ms(deferred);
    if (p < predicted) {
      plan = deferred;
      predicted = p;
    } else {
      d.knobs.defer_refresh = false;
    }
  };
  auto remember = [&] {
    predicted_at[static_cast<std::size_t>(level)] = predicted;
    plan_at[static_cast<std::size_t>(level)] = plan;
    deferred_at[static_cast<std::size_t>(level)] = d.knobs.defer_refresh;
    known[static_cast<std::size_t>(level)] = true;
  };
  auto evaluate = [&](int l) {
    level = l;
    knobs_for(level);
    plan = plan_for(pose);
    predicted = predict_ms(plan);
    defer_if_late();
    remember();
  };
  defer_if_late();
  remember();
  // What no level reduces: the frame's fixed trace cost, the facet pass over the bundled
  // targets (the same facets at every level: whether a target has a bundle does not depend on
  // its spacing) and the sensor's cells; every other term of the model only adds to it (its
  // coefficients are >= 0, the same sums in the same order, so this holds in floating point
  // too). When that floor is over the deadline no level fits, and trying each in turn would
  // end at the last: the search goes there at once, then back through the levels below while
  // they are within 5 % of the deadline (below), each planned when reached. The same choice,
  // without the plans of the levels in between (on the terrain at 100 Hz, 26 plans a frame, a
  // few ms on the frame's critical path, down to 5: docs/performance.md).
  const double floor_ms =
      trace_factor_ *
          (config_.trace_ms_per_frame +
           1e-6 * (config_.trace_ns_per_facet * static_cast<double>(full.target_facets))) +
      sensor_factor_ * (1e-6 * (config_.sensor_ns_per_cell * prev_cells_));
  if (predicted > deadline_ms_ && level < max_level && floor_ms > deadline_ms_)
    evaluate(max_level);
  while (predicted > deadline_ms_ && level < max_level)
    evaluate(level + 1);
  if (predicted > deadline_ms_) {
    // Nothing fits: the part of the cost the levels do not reach (the sensor's cells) is over
    // the deadline. Degrade no further than to within 5 % of the deadline of the cheapest.
    const double enough = predicted + 0.05 * deadline_ms_;
    int chosen = level;
    while (chosen > min_level) {
      if (!known[static_cast<std::size_t>(chosen - 1)])
        evaluate(chosen - 1);
      if (predicted_at[static_cast<std::size_t>(chosen - 1)] > enough)
        break;
      --chosen;
    }
    level = chosen;
    knobs_for(level);
    d.knobs.defer_refresh = deferred_at[static_cast<std::size_t>(level)];
    predicted = predicted_at[static_cast<std::size_t>(level)];
    plan = plan_at[static_cast<std::size_t>(level)];
  } else if (level > min_level && tracer_->config().reuse_static_paths) {
    level = refine_with_kept(pose, min_level, level, plan, predicted);
  }
  for (std::uint32_t id : targets_)
    last_spacing_m_[id] = spacing_m_[id];
  d.level = level;
  d.degraded = level > 0;
  d.over_deadline = predicted > deadline_ms_;
  d.predicted_ms = predicted;
  d.rays = plan.rays();
  d.estimated_snr_error_db =
      kLevelSnrError_db[static_cast<std::size_t>(std::min(level, kMaxLevel))];
  last_predicted_trace_ms_ = model_trace_ms(plan);
  last_predicted_sensor_ms_ = model_sensor_ms(plan);
  d.predicted_trace_ms = trace_factor_ * last_predicted_trace_ms_;
  d.predicted_sensor_ms = sensor_factor_ * last_predicted_sensor_ms_;
  return d;
}

void FidelityGovernor::observe(double trace_ms, double sensor_ms, std::uint64_t rays,
                               std::uint64_t returns, std::uint64_t cells_synthesised,
                               std::uint64_t terrain_patches, std::uint64_t terrain_returns,
                               std::uint64_t terrain_facets,
                               std::uint64_t merged_returns) noexcept {
  const bool timed = std::isfinite(trace_ms) && std::isfinite(sensor_ms);
  if (config_.mode == GovernorConfig::Mode::kMeasured && timed && timed_frames_++ > 0) {
    // Factors of measured over modelled cost (header): up when two frames in a row were slower
    // than the factor says, to the smaller of their ratios; down by an exponential average (a
    // tenth a frame); bounded so one odd frame cannot stall the governor. Not from the first
    // timed frame.
    auto update = [](double& factor, double& prev_ratio, double measured_ms, double model_ms) {
      if (!(model_ms > 0.05)) {
        prev_ratio = 0.0;
        return;
      }
      const double ratio = std::clamp(measured_ms / model_ms, 0.05, 50.0);
      const double confirmed = std::min(ratio, prev_ratio);
      if (confirmed > factor)
        factor = confirmed;
      else if (ratio < factor)
        factor += 0.1 * (ratio - factor);
      prev_ratio = ratio;
    };
    update(trace_factor_, prev_trace_ratio_, trace_ms, last_predicted_trace_ms_);
    update(sensor_factor_, prev_sensor_ratio_, sensor_ms, last_predicted_sensor_ms_);
  }
  prev_rays_ = static_cast<double>(rays);
  prev_returns_ = static_cast<double>(returns);
  prev_cells_ = static_cast<double>(cells_synthesised);
  prev_terrain_patches_ = static_cast<double>(terrain_patches);
  prev_terrain_facets_ = static_cast<double>(terrain_facets);
  prev_terrain_scale_ = decision_.knobs.terrain_spacing_scale;  // the level that frame ran at
  prev_terrain_merge_ = static_cast<double>(
      radar::TerrainReturns::cell_merge(prev_terrain_scale_, terrain_.azimuth_merge_max).cells());
  prev_terrain_facet_ratio_ = terrain_facet_ratio_at(prev_terrain_scale_);
  prev_terrain_returns_ = static_cast<double>(std::min(terrain_returns, returns));
  const double ray_returns = static_cast<double>(returns) - prev_terrain_returns_;
  prev_unmerged_fraction_ =
      ray_returns > 0.0
          ? std::clamp(1.0 - static_cast<double>(merged_returns) / ray_returns, 0.0, 1.0)
          : 1.0;
}

}  // namespace radar_emu::loop
