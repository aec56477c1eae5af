#pragma once
// The fidelity governor: before a frame is traced it chooses how much of the scene to model so
// that the frame's computation fits its deadline, and never the other way round.
//
// Levels. Level 0 is the scenario's own fidelity ([radar] ray spacings, bounces). Each level up
// halves the rays of a target bundle (bundle spacing x sqrt 2) and coarsens the terrain grid by
// 2^(1/4) (its rays x 0.71), or with the terrain engine its patches by the same factor (their
// count x 0.71, down to one a facet), its range cells merged 2^floor(level / 4) a cell (their total
// mean power stays) and from level 12 the terrain's coarser level of detail
// (radar/products/terrain_returns.hpp); from level kBounceLevel on, rays bounce one
// time less (at least twice: the target-ground double bounce and dihedrals stay); from level
// kFacetLevel on, bounce 1 judges each facet by its centroid's visibility alone
// (TraceKnobs::facet_centroid_only: a seventh of the facet pass's occlusion queries, which dominate
// targets of tens of thousands of facets over the 207k-triangle terrain). Up to kMaxLevel.
//
// Where the rays go. Above level 0 a target's level is the frame's level plus its "rank", at
// most the frame's level again: rank 0 for targets whose expected SNR is within kRankStep_db of
// the strongest target's, one more for every further kRankStep_db below (at most kMaxRank). So
// the strongest returns keep the finest sampling and rays leave the weak ones first (issue 15:
// "spending rays where the return is strongest"). The expected SNR is the radar equation
// (Sensor::expected_snr) at the target's range, with the two-way elevation gain of the beam at
// its direction, of an RCS equal to its mean projected area: a quarter of its surface (Cauchy's
// surface area formula for convex bodies; a size, not a prediction of its RCS; a thin wire's
// bounding box would be much larger than its surface).
//
// Cost model. predicted = trace + sensor, with
//   trace  = trace_ms_per_frame (what a frame costs whatever its level: the bundles' facet pass
//            and edges, the passes' set-up)
//          + trace_ns_per_facet x the bundled targets' facets (their bounce-1 facet pass)
//          + trace_ns_per_ray x rays planned (SbrTracer::plan(): exact count, no tracing)
//          + trace_ns_per_kept_return x the kept returns it re-evaluates instead
//            ([radar] reuse_static_paths: SbrTracer::plan() counts them too)
//          + terrain_ns_per_patch x max(F x f / f', P x (s' / s)^2) ([radar] terrain =
//            "engine"), P and F the engine's patches and facets of the previous frame, s' its
//            patch scale, s this level's (terrain_spacing_scale): the patches fall as the square
//            of the scale down to one a facet (a facet smaller than a patch stays one); f' and f
//            the facets of the level of detail the engine took then and takes at this level
//            (1, or lod_facet_ratio from its coarse level on: radar::TerrainCoarsening)
//   sensor = sensor_ns_per_cell x cells synthesised by the previous frame
//          + sensor_ns_per_return x R, R = the previous frame's ray returns x (rays / its rays)
//          + sensor_ns_per_unmerged_return x R x (1 - the fraction of its ray returns the
//            sensor merged into another: Sensor's merge_step_bins; a return left alone is
//            synthesised in every beam it reaches, a merged one only summed)
//          + sensor_ns_per_terrain_return x T x m' / m
//            (rays: traced and kept alike, each stands for its returns)
//            T the engine's returns (lit cells) of the previous frame, m' and m the cells its
//            coarse cells merged then and at this level (radar::TerrainReturns::cell_merge:
//            the returns fall as the cells merge; set_terrain_cells gives the columns' limit)
// The frame takes the finest level whose prediction is within the deadline (compute_fraction of
// the frame period); if none is, the finest level within 5 % of the deadline of the coarsest
// level's cost (degrading further would buy less than that). In "model" mode the coefficients are
// the configured ones (defaults measured on the project's 2-core machine, docs/performance.md), so
// the choice depends only on the scenario and the previous frames: runs and replays are
// reproducible. In "measured" mode (the default with --realtime) two factors scale the trace and
// sensor terms by what the last frames measured: two slower frames in a row raise them at once
// (to the smaller of the two ratios), a faster one lowers them slowly (exponential average), so
// the governor errs on the side of the deadline. One slow frame alone does not: a frame that
// costs more once (a refresh, a new level's first trace, the machine taking the core for a
// moment) would otherwise degrade the frames after it for tens of frames, and at each coarser
// level's first trace raise the factors again. The first timed frame is not learnt from at all:
// it traces everything and touches every buffer for the first time (in a real-time run on the
// 2-core machine it took three times its model's trace time, and no later frame does).
//
// Returning to a finer level. With static path reuse a target's paths are kept at the spacing
// they were traced with, and a level that asks another spacing traces the target again (plan()
// counts it). Left alone, that makes a finer level cost a whole frame's rays the first time:
// after one frame over the deadline the governor would never come back. So when it chooses a
// level L above the frame's finest, it also tries each finer level l: the static targets whose
// kept paths are coarser than l asks keep them (no new rays), the rest take l; if that fits,
// the strongest of those lagging targets (lowest rank first) are traced at l's spacing while
// their rays fit the deadline. The frame's level is then its coarsest target's (the finest level
// whose spacings are all at least as coarse as the frame's), and it falls to l over the
// following frames as the targets come up.
//
// Estimated error. Each level carries the mean |SNR error| of matched detections that `radar-emu
// tradeoff` measured on the default scenario's frame at that level against a high-fidelity
// frame (kLevelSnrError_db, with the command in docs/performance.md). It is an estimate for
// scenes like the default one, not a bound.
//
// Real-time: decide() and observe() do not allocate, block or throw.

#include <algorithm>
#include <array>
#include <cstddef>
#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include "radar/em/sbr.hpp"
#include "radar/products/terrain_returns.hpp"
#include "radar/sensor/sensor.hpp"
#include "scene/scene.hpp"

namespace radar_emu::loop {

// The defaults are the embedded scenario's (loop/scenario.cpp: fitted on the project's 2-core
// machine by scripts/fit-governor-costs.py).
struct GovernorConfig {
  bool enabled = true;  ///< false: every frame at level 0, whatever it costs
  /// Deadline of a frame's computation (trace + sensor) as a fraction of the frame period (half:
  /// issue 29's budget for the scenario's full physics). The rest of the period absorbs the
  /// model's error and the machine's jitter.
  double compute_fraction = 0.5;
  /// kModel: fixed coefficients, reproducible; kMeasured: cost factors learnt from the measured
  /// stage times; kAuto: kMeasured with --realtime, kModel otherwise (the loop resolves it).
  enum class Mode { kAuto, kModel, kMeasured } mode = Mode::kAuto;
  /// Wall time of a frame's tracing at any level (facet pass, edges, set-up) [ms].
  double trace_ms_per_frame = 1.5;
  double trace_ns_per_facet = 345.0;  ///< per facet of the bundled targets (facet pass) [ns]
  double trace_ns_per_ray = 216.0;    ///< wall time of the frame's tracing per ray [ns]
  /// Wall time per kept return re-evaluated instead of traced ([radar] reuse_static_paths) [ns].
  double trace_ns_per_kept_return = 91.0;
  double sensor_ns_per_cell = 12.5;     ///< sensor wall time per cell synthesised [ns]
  double sensor_ns_per_return = 107.0;  ///< sensor wall time per ray return (contribution) [ns]
  /// Per ray return the sensor does not merge into another (synthesised in its beams) [ns].
  double sensor_ns_per_unmerged_return = 0.0;
  /// Per return of the terrain engine (a diffuse cell: its footprint over the taps) [ns].
  double sensor_ns_per_terrain_return = 0.0;
  /// Wall time of the terrain engine ([radar] terrain = "engine") per patch it evaluates [ns]
  /// (its horizon sweep and queries included).
  double terrain_ns_per_patch = 0.0;
  int max_level = 12;  ///< coarsest level allowed (0..kMaxLevel)
};

/// What the governor chose for one frame.
struct GovernorDecision {
  int level = 0;                        ///< 0: the scenario's fidelity
  bool degraded = false;                ///< level > 0
  bool over_deadline = false;           ///< even the coarsest level was predicted late
  double predicted_ms = 0.0;            ///< trace + sensor predicted at the level
  double predicted_trace_ms = 0.0;      ///< of which the trace (the terrain engine's included)
  double predicted_sensor_ms = 0.0;     ///< and the sensor
  double deadline_ms = 0.0;             ///< compute_fraction x period
  double estimated_snr_error_db = 0.0;  ///< kLevelSnrError_db at the level
  std::size_t rays = 0;                 ///< rays planned
  std::size_t full_rays = 0;            ///< rays level 0 would have shot
  /// Trace plans made to choose (SbrTracer::plan, the governor's own cost on the frame's path).
  std::size_t plans = 0;
  radar::TraceKnobs knobs{};  ///< spans point into the governor
};

class FidelityGovernor {
 public:
  static constexpr int kMaxLevel = 16;
  static constexpr int kBounceLevel = 8;
  static constexpr int kFacetLevel = 6;
  static constexpr double kRankStep_db = 10.0;
  static constexpr int kMaxRank = 4;
  /// Mean |SNR error| [dB] of matched detections per level on the default frame (index: level,
  /// clamped to the last entry), measured by `radar-emu tradeoff --cases frame` (its
  /// governor_level series; docs/performance.md, "The fidelity governor").
  static const std::array<double, kMaxLevel + 1> kLevelSnrError_db;

  /// Setup: throws std::invalid_argument naming the field when the configuration is invalid.
  /// Keeps references to the scene, tracer and sensor (they must outlive it).
  FidelityGovernor(const GovernorConfig& config, const scene::Scene& scene,
                   const radar::SbrTracer& tracer, const radar::Sensor& sensor,
                   double frame_period_s);

  /// Chooses the level and knobs for a frame seen from `pose` (scene at the frame's time).
  [[nodiscard]] const GovernorDecision& decide(const radar::RadarPose& pose) noexcept;
  /// The same at a given level (clamped to 0..kMaxLevel), whatever it costs: for measuring what
  /// a level gives (radar-emu tradeoff, tests).
  [[nodiscard]] const GovernorDecision& decide_at(const radar::RadarPose& pose, int level) noexcept;
  /// What the frame decided last cost: stage wall times [ms] and what it processed (`rays` the
  /// rays traced and those kept paths stood for, `returns` all of them, `terrain_returns` of those
  /// the terrain engine's, `terrain_patches` the engine's patches; both 0 without the engine).
  /// `terrain_facets`: the facets the engine cut into those patches (0: unknown, no floor).
  /// `merged_returns`: the returns summed into another or left out under the floor before the
  /// merge (neither becomes an item of the sensor's image).
  /// Times that are not finite (a frame processed at setup): its counts only; measured mode's
  /// factors learn nothing from it.
  void observe(double trace_ms, double sensor_ms, std::uint64_t rays, std::uint64_t returns,
               std::uint64_t cells_synthesised, std::uint64_t terrain_patches = 0,
               std::uint64_t terrain_returns = 0, std::uint64_t terrain_facets = 0,
               std::uint64_t merged_returns = 0) noexcept;
  /// Setup: what the terrain engine coarsens with the level (radar::TerrainReturns::
  /// coarsening(); until set: no columns merged, no coarse level of detail), for its cost.
  void set_terrain_cells(const radar::TerrainCoarsening& c) noexcept {
    terrain_ = c;
    terrain_.azimuth_merge_max = std::max<std::size_t>(1, c.azimuth_merge_max);
  }
  /// The facets of the level of detail the engine takes at `level`, over the finest's.
  [[nodiscard]] double terrain_facet_ratio(int level) const noexcept;
  [[nodiscard]] double terrain_facet_ratio_at(double scale) const noexcept;
  /// The engine's cells merged into one at `level` (radar::TerrainReturns::cell_merge of its
  /// terrain knob). Real-time safe.
  [[nodiscard]] std::size_t terrain_cells_merged(int level) const noexcept;

  [[nodiscard]] const GovernorConfig& config() const noexcept { return config_; }
  /// Cost factors of measured mode (1 in model mode).
  [[nodiscard]] double trace_factor() const noexcept { return trace_factor_; }
  [[nodiscard]] double sensor_factor() const noexcept { return sensor_factor_; }

 private:
  [[nodiscard]] double predict_ms(const radar::TracePlan& plan) const noexcept;
  /// The tracer's plan at the decision's knobs, counted in GovernorDecision::plans.
  [[nodiscard]] radar::TracePlan plan_for(const radar::RadarPose& pose) noexcept;
  /// The finest level in [min_level, max_level] predicted within the deadline (else max_level).
  const GovernorDecision& choose(const radar::RadarPose& pose, int min_level,
                                 int max_level) noexcept;
  void knobs_for(int level) noexcept;
  /// Target `id`'s bundle spacing at `level` (its rank applied) [m].
  [[nodiscard]] double target_spacing_m(std::uint32_t id, int level) const noexcept;
  /// The finest level from `from` on whose spacings are all at least as coarse as spacing_m_'s.
  [[nodiscard]] int level_of_spacings(int from) const noexcept;
  /// With static path reuse, after `level` was chosen above `min_level`: the finest level l
  /// below it at which the static targets whose kept paths are coarser than l asks keep them
  /// and the rest fits the deadline; of those, the strongest are traced at l's spacing while
  /// their rays fit (header: returning to a finer level). Sets the knobs, `plan` and
  /// `predicted`, and returns the level the frame then has (its coarsest target's); else
  /// leaves them at `level` and returns it.
  int refine_with_kept(const radar::RadarPose& pose, int min_level, int level,
                       radar::TracePlan& plan, double& predicted) noexcept;

  GovernorConfig config_;
  const scene::Scene* scene_;
  const radar::SbrTracer* tracer_;
  const radar::Sensor* sensor_;
  double deadline_ms_;
  std::vector<std::uint32_t> targets_;        ///< object ids of the tracer's targets
  std::vector<int> rank_;                     ///< per object id
  std::vector<double> mean_area_m2_;          ///< per object id: surface / 4 (targets)
  std::vector<double> spacing_m_;             ///< per object id, for TraceKnobs
  std::vector<double> last_spacing_m_;        ///< per object id: the previous decision's spacing
  std::vector<std::uint32_t> lagging_;        ///< refine_with_kept's targets (capacity: all)
  std::vector<std::size_t> rays_per_object_;  ///< SbrTracer::plan's, per object id
  GovernorDecision decision_{};
  // The previous frame, for the sensor term.
  double prev_cells_ = 0.0, prev_returns_ = 0.0, prev_rays_ = 0.0;
  double prev_terrain_patches_ = 0.0, prev_terrain_returns_ = 0.0;
  double prev_unmerged_fraction_ = 1.0;  ///< of the previous frame's ray returns
  double prev_terrain_scale_ = 1.0;      ///< the engine's patch scale of the previous frame
  double prev_terrain_facets_ = 0.0;
  double prev_terrain_merge_ = 1.0;        ///< cells merged by the engine in the previous frame
  double prev_terrain_facet_ratio_ = 1.0;  ///< its level of detail's terrain_facet_ratio
  radar::TerrainCoarsening terrain_{};
  /// The model's trace and sensor terms [ms] for a plan (factors not applied).
  [[nodiscard]] double model_trace_ms(const radar::TracePlan& plan) const noexcept;
  [[nodiscard]] double model_sensor_ms(const radar::TracePlan& plan) const noexcept;
  double trace_factor_ = 1.0, sensor_factor_ = 1.0;
  /// Measured mode: the previous timed frame's measured / modelled ratios (0: none yet).
  double prev_trace_ratio_ = 0.0, prev_sensor_ratio_ = 0.0;
  std::uint64_t timed_frames_ = 0;  ///< frames observed with finite times
  double last_predicted_trace_ms_ = 0.0, last_predicted_sensor_ms_ = 0.0;
};

}  // namespace radar_emu::loop
