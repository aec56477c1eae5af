#pragma once
// The frame tracer: shooting and bouncing rays (Ling, Chou & Lee, IEEE TAP 37(2), 1989) with
// spherical-wave illumination from the antenna. Ray tubes are fanned from the antenna phase
// centre across the field of view (diverging with the distance), bounced specularly by
// geometrical optics off conductors (PEC) and dielectric surfaces (Fresnel coefficients of the
// terrain catalogue's permittivity at the carrier) up to max_bounces, and at every hit on a path
// that has met a target the tube's footprint radiates back to the radar through the
// physical-optics integral, in the antenna's polarisation channel. The field, reflection and PO
// machinery is the SBR core shared with the offline RCS engine (radar/em/sbr_core.hpp); materials
// are resolved once at setup, at the carrier, by radar::resolve_surfaces() (radar/em/surfaces.hpp).
// Diffuse terrain returns sigma0 x footprint at a terrain ray's first hit (the clutter model). Pure
// computation: no I/O, clocks or threads of its own.
//
// Ownership (each path is counted once, by one grid):
//   - A path's owner is the first target (object with a conducting triangle) it meets. Rays of a
//     target's bundle count only paths owned by that target; terrain-grid rays count only paths
//     owned by a target that has no bundle this frame (outside the field of view), so a target in
//     view is sampled by its own, finer bundle alone.
//   - Bounce 1 follows the lighting rule shared with the RCS engine (sbr_core.hpp, FacetLight):
//     every frame, each facet of a target that has a bundle is judged against the radar's phase
//     centre. Inside the field of view, within range and in its own far field
//     (facet_in_far_field), a facet whose seven visibility samples all see the radar returns
//     the exact PO integral over the triangle, a partly seen one that of its lit
//     sub-triangles, each as one contribution at the facet's centroid; one not seen at all
//     returns nothing; the bundle's first hits on such facets radiate nothing. Facets near
//     field, out of view or out of range are left to the rays: their first hits radiate their
//     tube footprints. Facet contributions follow all ray contributions in the output, in
//     facet order.
//   - A path radiates coherently (PO toward the radar) at every hit from its first target hit on:
//     radar -> target -> ... and radar -> ground -> target -> ... (the target-ground double
//     bounce, both orders) are all counted, each by the bundle of its first target (a bundle
//     also covers the ground image of its target, SbrConfig::target_ground_image, where the
//     ground-first rays start).
//     Terrain-only paths (ground -> wall) radiate nothing coherent: terrain is the diffuse
//     model's.
//   - The diffuse clutter of a terrain surface is returned only by a terrain-grid ray at its first
//     hit (bundle rays first hitting terrain add no clutter; they continue specularly).
//   - A ray that meets a target it does not count ends there; every ray still shadows what lies
//     behind its hits.
//   - A ray that has not met a target yet is followed past a hit only if its next segment
//     crosses the bounding box of a target it may count (the bundle's own target; for terrain
//     rays, the targets in range without a bundle). Everything else such a segment could reach
//     radiates nothing coherent, so only paths with two or more non-target hits before their
//     target are lost (counted in TraceStats::pruned_paths with every culled segment); the
//     cull spares the long, grazing upward queries of rays reflected off the ground.
//   - Every return is labelled with its path's owner (Contribution::object_id), whichever
//     surface the path last met: radar -> target -> ground -> radar is the target's echo.

#include <algorithm>
#include <array>
#include <atomic>
#include <complex>
#include <cstddef>
#include <cstdint>
#include <glm/glm.hpp>
#include <memory>
#include <span>
#include <vector>

#include "radar/clutter/terrain.hpp"
#include "radar/em/edges.hpp"
#include "radar/em/sbr_core.hpp"
#include "radar/em/surfaces.hpp"
#include "scene/scene.hpp"

namespace radar_emu::radar {

/// Where the radar is and where it looks, in the world (ENU) frame.
struct RadarPose {
  glm::dvec3 position_m{0.0};    ///< antenna phase centre, world [m]
  glm::dvec3 velocity_mps{0.0};  ///< antenna velocity, world [m/s]
  /// Rotation world from antenna; antenna frame: x boresight, y right, z down.
  glm::dmat3 world_from_antenna{1.0};
};

/// Azimuth/elevation in the antenna frame: azimuth positive right of boresight, elevation
/// positive up, both [rad].
struct AzEl {
  double azimuth_rad = 0.0;
  double elevation_rad = 0.0;
};
[[nodiscard]] AzEl azel_from_direction(const glm::dvec3& direction_antenna) noexcept;
[[nodiscard]] glm::dvec3 direction_from_azel(const AzEl& azel) noexcept;

/// Ray densities. Terrain (objects without any conducting triangle) is sampled by one coarse
/// grid over the whole field of view; each target (an object with a conducting triangle) that
/// lies inside the field of view gets its own ray bundle over its angular bounds, dense enough
/// in metres at its range (ownership of paths: header).
struct SbrConfig {
  double carrier_hz = 94e9;
  double azimuth_min_rad = -0.1745;  ///< field of view, antenna frame
  double azimuth_max_rad = 0.1745;
  double elevation_min_rad = -0.0873;
  double elevation_max_rad = 0.0873;
  double terrain_ray_spacing_rad = 1e-3;  ///< angular spacing of the terrain grid (az and el)
  /// Shoot the terrain grid (diffuse clutter at its first hits, and the paths of targets out of
  /// view). Off when the caller takes terrain clutter from the terrain engine instead
  /// (radar/products/terrain_returns.hpp): only the targets' bundles are traced.
  bool terrain_rays = true;
  double target_ray_spacing_m = 0.25;       ///< bundle spacing at the target's nearest range
  std::size_t max_rays_per_target = 50000;  ///< bundles coarsen beyond this (counted)
  double max_range_m = 6000.0;              ///< rays end here (one-way)
  int max_bounces = 3;                      ///< hits per ray, reflections included (1..16)
  /// Bundles also cover the mirror image of the target's bounding box in the horizontal plane
  /// of its base (world z up), where the rays of the ground-first double bounce (radar ->
  /// ground -> target) start; off: only the box (the target-first order is still traced).
  bool target_ground_image = true;
  /// Antenna polarisation channel, receive first ("HV": receive H, transmit V). V along a ray
  /// of direction d is the antenna's "up" (-z of the antenna frame) projected perpendicular to
  /// d, H = V x d (right of boresight for a level antenna); so V = -theta_hat, H = -phi_hat of
  /// the RCS engine's frame and S_pq equals its S_pq for every channel.
  Polarisation polarisation = Polarisation::kVV;
  /// Edge diffraction of the targets' wedge edges (radar/em/edges.hpp, the RCS engine's PTD
  /// fringe equivalent edge currents): every frame, each diffracting edge of a target in view,
  /// in range and in its own far field radiates one contribution at its midpoint when a face of
  /// it is lit and the path from beside its midpoint to the radar is clear. Off here; the
  /// scenario's [radar] edges turns it on by default.
  bool edges = false;
  /// Shared edges turning by more than this diffract (open-sheet boundaries always do) [rad].
  double edge_min_turn_rad = 0.5235987755982988;
  /// With edges: 1 = first-order edge currents; 2 = also the hard polarisation's double
  /// diffraction between parallel edges across a flat face (edges.hpp), one contribution per
  /// pair at the middle of its receiving segment when both edges radiate this frame.
  int edge_order = 2;
  /// Static path reuse (the temporal lever of issue 29): the rays of a target that does not
  /// move are not traced every frame. Their returns' paths (first hit P1, radiating hit Pn and
  /// the path between them) are kept from the frame that traced them and re-evaluated for each
  /// new pose R: length L = |P1 - R| + L(P1..Pn) + |Pn - R|, phase exp(-j k L), range L / 2, the
  /// arrival direction of Pn and the Doppler of the two end segments, all exact; the amplitude
  /// without its path phase is kept. A single bounce (P1 = Pn) is then exact; for more, the
  /// kept reflection points differ from those of the ray that reaches Pn from R by about
  /// D dtheta (D: the target's extent with its ground image, dtheta: the change in the
  /// direction from the target to the radar), and since a reflected path's length is
  /// stationary in its reflection points (Fermat's principle; Born & Wolf, Principles of
  /// Optics, 7th ed., sec. 3.3.2) the length is off by the second order, at most about
  /// D dtheta^2 (a right dihedral: 0.26 D dtheta^2, tests/radar/sbr_reuse_test.cpp).
  /// Kept paths are used while dtheta <= min(spacing / (2 D), sqrt(reuse_max_phase_rad / (k D)))
  /// (the hit points move by less than half a tube, the phase by less than reuse_max_phase_rad),
  /// the antenna has turned by no more than that angle (polarisation basis), the bundle's spacing
  /// and bounces are unchanged, the part of it inside the field of view lies within the part its
  /// paths cover, to half a tube (a target leaving the view keeps its paths and leaves out for good
  /// those whose first hit has left it, as a trace would not shoot them; one coming into view, or
  /// whose box straddles the antenna's plane, is traced), the same facets are left to its rays
  /// (FacetLight::kLightByRays), no path met a moving object and no moving object comes near the
  /// target or its line of sight to the radar; else the bundle is traced again. Besides, about 1 /
  /// reuse_refresh_frames of the kept rays are traced again each frame, the longest kept first, so
  /// a kept path is at most about that many frames old (a frame is a trace() call). The refresh
  /// goes a slice at a time: a bundle's rows fall into reuse_refresh_slices bands of its box's
  /// elevation span (a row whose centre lies in band s belongs to slice s), each kept and traced
  /// again on its own, so one refresh traces a slice's rays, not the bundle's. The refresh takes
  /// the most urgent slice first: the larger of its age over reuse_refresh_frames and its aspect
  /// change over its limit. The aspect rule holds per slice: the slices past their limit (and
  /// any between them) are traced again, the bundle's others kept. Slices are traced apart only
  /// while the bundle has the rows its paths were kept with, so that the slices' rows together
  /// are each of the bundle's rows once; else the whole bundle is. To that end a kept bundle
  /// keeps its rows while its grid asks for one row more or fewer, or up to 2 % of them (its
  /// elevation step then differs from the spacing's by as much), and a kept target cut by the
  /// view takes the grid of its whole box (its rows over the box's whole elevation extent, the
  /// ray cap on the whole box) and shoots the rows whose centres are in view, so its slices stay
  /// put as it leaves the view.
  /// While its paths are kept, a target's bounce-1 facets also keep the answers of their occlusion
  /// queries (which samples and sub-triangles see the radar): under the same rule a shadow boundary
  /// moves across it by at most D dtheta <= spacing / 2, within the rays' own resolution. Their PO
  /// integrals, phases and angles are computed for the pose. Off: every bundle every frame.
  bool reuse_static_paths = false;
  double reuse_max_phase_rad = 0.39269908169872414;  ///< pi / 8
  int reuse_refresh_frames = 16;                     ///< >= 1
  int reuse_refresh_slices = 4;                      ///< 1..kMaxKeptSlices
  static constexpr int kMaxKeptSlices = 8;
  /// A target's bundle shoots, in each row of its grid, only the columns where a part of its
  /// facets or its image in the ground below projects (16 parts a target, split at setup; each
  /// part's box, one cell added on every side), instead of its whole box: a ray elsewhere can
  /// meet the target only by way of another object (those paths are then not traced). The
  /// grid and its spacing stay the box's, so the rays shot are the same rays.
  bool mask_target_rays = true;
};

/// Per-frame overrides for the fidelity governor. Defaults leave the configuration as it is.
/// Invalid values fall back to the configuration (counted in TraceStats::knob_fallbacks; the
/// frame path cannot throw).
struct TraceKnobs {
  /// Terrain grid spacing = config spacing x this factor (>= 1: coarser only).
  double terrain_spacing_scale = 1.0;
  /// Hits per ray this frame, 1..config.max_bounces; 0: config.max_bounces.
  int max_bounces = 0;
  /// Target bundle spacing [m] at the target's nearest range, indexed by scene object id; an
  /// empty span, a missing entry or 0 take config.target_ray_spacing_m. Bundles still coarsen
  /// at config.max_rays_per_target.
  std::span<const double> target_ray_spacing_m{};
  /// Bounce 1 judges each facet by one visibility sample (its centroid) instead of seven: a
  /// seventh of the occlusion queries, no partly lit facets (a facet is lit or dark whole).
  bool facet_centroid_only = false;
  /// Static path reuse: no bundle is traced again for the refresh alone this frame, and the
  /// refresh's credit waits (the governor's resort before a coarser level when the refresh
  /// would take the frame past its deadline; the reuse rule's own retraces still happen), as
  /// long as no kept bundle is 2 x reuse_refresh_frames frames old.
  bool defer_refresh = false;
};

/// What trace() would shoot for a pose and knobs (plan()).
struct TracePlan {
  std::size_t terrain_rays = 0;       ///< the terrain grid
  std::size_t target_rays = 0;        ///< all bundles together
  std::size_t target_bundles = 0;     ///< targets inside the field of view
  std::size_t coarsened_bundles = 0;  ///< bundles held at max_rays_per_target
  /// Rays of bundles whose kept paths would be reused (SbrConfig::reuse_static_paths; not in
  /// target_rays), and their kept returns.
  std::size_t reused_rays = 0;
  std::size_t reused_contributions = 0;
  std::size_t target_facets = 0;  ///< facets of the bundled targets (the facet pass's work)
  int max_bounces = 0;            ///< hits per ray the knobs give
  [[nodiscard]] std::size_t rays() const noexcept { return terrain_rays + target_rays; }
};

/// One return: a ray tube's contribution at one hit point, as seen by the radar.
struct Contribution {
  /// Complex scattering amplitude [m] in the configured polarisation channel: sigma = |A|^2
  /// (m^2), phase exp(-j k L) over the whole path L (time convention exp(+j w t); the RCS
  /// engine's S_pq of this path referred to the radar instead of the target origin). No range
  /// term: the sensor applies it. For diffuse clutter (coherent == false) only |A|^2 is
  /// meaningful and is summed as power.
  std::complex<double> amplitude{0.0, 0.0};
  double range_m = 0.0;  ///< half the total path length [m]
  /// Extent along range of a diffuse footprint [m] (the sensor spreads its power uniformly over
  /// [range_m - spread/2, range_m + spread/2]); 0 for coherent returns.
  double range_spread_m = 0.0;
  double radial_velocity_mps = 0.0;  ///< half the rate of change of the path [m/s], + receding
  double azimuth_rad = 0.0;          ///< direction of arrival at the radar, antenna frame
  double elevation_rad = 0.0;
  /// The path's owner (the first target it met: header); diffuse clutter: the terrain object.
  std::uint32_t object_id = 0;
  std::uint8_t bounces = 0;  ///< 1 = single bounce
  bool coherent = true;      ///< false: diffuse clutter power
  /// Whether the hit that radiates this return is on the owner itself (false: the path went on
  /// from its owner to another surface, e.g. radar -> target -> ground -> radar).
  bool radiated_by_owner = true;
};

/// Diagnostics (bench_frame's BM_TraceRaw, which replays a frame's queries through Embree alone
/// to measure the tracer against the raw rate on the same rays): while SbrTracer::set_query_log
/// holds one, trace() copies every scene query it makes into it, closest-hit queries (the rays'
/// segments) into `intersects` and occlusion queries (bounce 1's facet samples, the edges'
/// probes, the shadow rays of later bounces) into `occlusions`, while there is room; the counts
/// go on past the spans' ends. Thread-safe (atomic counters), so the order is the threads'.
struct QueryLog {
  std::span<scene::Ray> intersects{};
  std::span<scene::Ray> occlusions{};
  std::atomic<std::size_t> n_intersects{0};
  std::atomic<std::size_t> n_occlusions{0};
};

struct TraceStats {
  std::uint64_t rays = 0;
  std::uint64_t target_bundles = 0;     ///< targets inside the field of view
  std::uint64_t coarsened_bundles = 0;  ///< bundles that hit max_rays_per_target
  std::uint64_t hits = 0;
  std::uint64_t contributions = 0;
  std::uint64_t dropped_contributions = 0;   ///< output span full
  std::uint64_t grazing_skipped = 0;         ///< footprints skipped at |cos(theta_i)| < 1e-3
  std::uint64_t dielectric_reflections = 0;  ///< specular bounces off dielectric surfaces
  std::uint64_t knob_fallbacks = 0;          ///< invalid TraceKnobs values replaced by config
  /// Rays ended before a target because their next segment could reach no countable target
  /// (header: ownership).
  std::uint64_t pruned_paths = 0;
  std::uint64_t target_facets = 0;   ///< facets of the bundled targets (the facet pass)
  std::uint64_t lit_facets = 0;      ///< facets returned whole by exact PO (bounce 1, header)
  std::uint64_t partial_facets = 0;  ///< partly lit facets returned by their lit sub-triangles
  std::uint64_t facet_queries = 0;   ///< occlusion queries of the bounce-1 rule and the edges
  /// Facets of moving targets in the facet pass, and those of them in the groups that read
  /// their bounce-1 occlusion answers back this frame (SbrTracer's facet memo of movers) instead
  /// of asking again (a facet with no answer recorded, turned away then, still asks).
  std::uint64_t mover_facets = 0;
  std::uint64_t replayed_mover_facets = 0;
  /// Of the others, those in groups that read back only what the mover's own body blocks and ask
  /// the rest of the scene (its own shadows within half a tube, the scene's not).
  std::uint64_t self_replayed_mover_facets = 0;
  std::uint64_t edges_used = 0;      ///< edge-diffraction contributions (SbrConfig::edges)
  std::uint64_t edges_shadowed = 0;  ///< edges whose midpoint does not see the radar
  std::uint64_t edges_skipped = 0;   ///< back-facing, along the Keller cone, out of view/range
  std::uint64_t edges_double = 0;    ///< double-diffraction contributions (edge_order 2)
  /// Issue 28: diffuse terrain returns, those whose sigma0 sample the catalogue flags (outside
  /// a model's validity, extrapolated, assumed), and the OR of their flags (surface.hpp).
  std::uint64_t terrain_returns = 0;
  std::uint64_t terrain_returns_flagged = 0;
  std::uint32_t terrain_sigma0_flags = 0;
  /// Static path reuse (SbrConfig::reuse_static_paths): bundles whose returns came from kept
  /// paths, the rays they did not shoot, the returns re-evaluated, the kept bundles traced again
  /// by the refresh rule alone, the largest aspect change of a reused bundle as a fraction of
  /// its limit (<= 1), and the oldest kept paths used [frames].
  std::uint64_t reused_bundles = 0;
  std::uint64_t reused_rays = 0;
  std::uint64_t reused_contributions = 0;
  std::uint64_t refreshed_bundles = 0;
  std::uint64_t refresh_deferred = 0;  ///< frames whose refresh waited (TraceKnobs)
  /// Kept paths of targets cut by the field of view whose first hit had left the view: left
  /// out, as a trace would not shoot them (SbrTracer::prune_outside_view).
  std::uint64_t kept_paths_left_view = 0;
  /// Cells of the traced bundles' grids where none of the target's facets projects
  /// (SbrConfig::mask_target_rays): rays not shot.
  std::uint64_t masked_rays = 0;
  double reuse_max_angle_fraction = 0.0;
  std::uint64_t reuse_max_age_frames = 0;
};

class SbrTracer {
 public:
  /// Setup: validates the configuration (throws std::invalid_argument with the field name) and
  /// resolves the scene's materials at the carrier (resolve_surfaces(), in the antenna's
  /// channel; throws its UnresolvedMaterial for an unknown name).
  SbrTracer(const scene::Scene& scene, const SbrConfig& config);

  /// Upper bound on the contributions one trace() can produce for this scene and config (size
  /// the output span with it).
  [[nodiscard]] std::size_t max_contributions() const noexcept;
  /// Shoots all rays for `pose` against the scene at its current time and writes contributions
  /// to `out` (in a deterministic order, whatever the threading). Returns the number written.
  /// `stats` is added to, not reset, so one TraceStats can total a run.
  /// Real-time safe apart from the worker threads it uses (TBB): no allocation per call. `out`
  /// must hold max_contributions() elements (fewer: the excess is dropped and counted).
  /// `knobs` (default: the configuration as it is) coarsen the terrain grid, cap the bounces and
  /// set per-target bundle spacings for this frame only.
  [[nodiscard]] std::size_t trace(const RadarPose& pose, std::span<Contribution> out,
                                  TraceStats& stats, const TraceKnobs& knobs = {}) noexcept;
  /// The rays trace() would shoot for `pose` and `knobs`, without tracing: cheap (one pass over
  /// the objects' bounds), no allocation. `rays_per_object[id]` (when the span reaches id) gets
  /// the bundle size of object id, 0 for terrain and targets out of view. With static path reuse
  /// the bundles whose kept paths trace() would re-evaluate are counted apart (reused_rays,
  /// reused_contributions; 0 in rays_per_object), by trace()'s rule except the facet check,
  /// which needs the frame's facet pass. Not to be called concurrently with trace() or itself
  /// (it fills a scratch of the tracer's).
  [[nodiscard]] TracePlan plan(const RadarPose& pose, const TraceKnobs& knobs = {},
                               std::span<std::size_t> rays_per_object = {}) const noexcept;

  /// Diagnostics: trace() records its queries into `log` (QueryLog) until set back to nullptr.
  /// Not for the frame path (each query then also writes the log).
  void set_query_log(QueryLog* log) noexcept { query_log_ = log; }

  [[nodiscard]] const SbrConfig& config() const noexcept { return config_; }
  /// The scene's materials as this tracer resolved them (at its carrier, in its channel).
  [[nodiscard]] const SurfaceSet& surfaces() const noexcept { return surfaces_; }
  /// Whether scene object `id` is a target (has a conducting triangle: it gets a ray bundle).
  [[nodiscard]] bool is_target(std::uint32_t id) const noexcept {
    return id < is_target_.size() && is_target_[id] != 0;
  }

 private:
  const scene::Scene* scene_;
  SbrConfig config_;
  QueryLog* query_log_ = nullptr;  ///< set_query_log (diagnostics)
  /// The scene's queries, through the query log when one is set.
  [[nodiscard]] bool intersect(const scene::Ray& ray, scene::Hit& hit) const noexcept;
  [[nodiscard]] bool occluded(const scene::Ray& ray) const noexcept;
  void intersect(std::span<const scene::Ray> rays, std::span<scene::Hit> hits,
                 std::span<std::uint8_t> found) const noexcept;
  void occluded(std::span<const scene::Ray> rays, std::span<std::uint8_t> blocked) const noexcept;
  /// The same answers through the scene's batched query (scene::Scene::occluded over a span:
  /// coherent Embree streams, traced in SIMD packets), for rays that leave neighbouring points
  /// toward one point (the facet pass's samples). A stream's closest hit had depended on its
  /// neighbours (intersect above: which of the triangles met at an edge comes first); whether
  /// a ray is blocked does not depend on the order in which triangles are met, and the
  /// streams answered as the single queries for every ray the facet pass batched (its
  /// samples and sub-triangles') in the default scenario and 60 frames of the terrain one
  /// (10.0 million rays, none different; 2026-11-28). The facet pass's batches are the same
  /// whatever the threads (trace: simple partitioner).
  /// occluded_coherent split by the mover of each ray (scene::Scene::occluded's split).
  void occluded_split(std::span<const scene::Ray> rays, std::span<const std::uint32_t> mover,
                      scene::MoverSplit split, std::span<std::uint8_t> blocked) const noexcept;
  void occluded_coherent(std::span<const scene::Ray> rays,
                         std::span<std::uint8_t> blocked) const noexcept;
  /// Records occlusion queries in the query log, when one is set.
  void log_occlusions(std::span<const scene::Ray> rays) const noexcept;
  /// Per scene material at the carrier: specular model, sigma0 row (issue 4's models, "total":
  /// surface + volume), conductor flag; resolved once here.
  SurfaceSet surfaces_;
  /// The part of a target's angular box (its box and ground image seen from the radar, in the
  /// antenna's azimuth and elevation) that lies inside the field of view, as fractions of the
  /// box along each: [az0, az1] x [el0, el1], the whole box [0, 1] x [0, 1].
  struct ViewShare {
    double az0 = 0.0, az1 = 1.0, el0 = 0.0, el1 = 1.0;
  };
  struct Bundle {
    std::uint32_t object_id = 0;
    double spacing_m = 0;  ///< the configured (or knob) spacing at the target, before coarsening
    double az0_rad = 0, el0_rad = 0, daz_rad = 0, del_rad = 0;
    std::size_t n_az = 0, n_el = 0, first_ray = 0;
    std::size_t first_facet = 0;   ///< in this frame's run over the bundled targets' facets
    std::size_t first_edge = 0;    ///< in this frame's run over the bundled targets' edges
    std::size_t first_pair = 0;    ///< the same for their edge pairs (double diffraction)
    std::size_t first_column = 0;  ///< in column_cos_ / column_sin_ this frame (or none)
    /// Its box (with the ground image) reached past the field of view and was cut to it (a kept
    /// target: its box's grid, less the rows and columns out of view; bundle_for).
    bool clipped = false;
    /// Its box straddles the antenna's plane: its grid covers the whole field of view.
    bool behind = false;
    /// The part of its box's angular extent inside the field of view (ViewShare), and half a ray
    /// tube in those units along azimuth and elevation (the coverage rule's tolerance).
    ViewShare view;
    double half_tube_az = 0.0, half_tube_el = 0.0;
    /// Static path reuse (SbrConfig::reuse_static_paths, choose_reuse): traced this frame, whole
    /// or one slice (else its kept paths are re-evaluated), and its paths kept once traced.
    bool trace = true;
    bool keep = false;
    bool refreshed = false;  ///< traced (static, its kept paths valid) to refresh them
    bool still = false;      ///< static, no mover near: its facets may keep their answers
    std::uint8_t memo = 0;   ///< kMemoNone, kMemoRecord, kMemoReplay or kMemoRolling
    /// kMemoRolling (a mover): bit g set: its facets t with t % memo_groups_ == g read their
    /// answers back this frame; the others' ask and record.
    std::uint32_t memo_replay_groups = 0;
    /// kMemoRolling, the groups that do not read everything back: bit g set: their facets read
    /// back what the mover's own body blocks (facet_self_memo_) and ask the rest of the scene
    /// (its motion moved a shadow cast by the scene too far, its aspect not its own shadows).
    std::uint32_t memo_self_groups = 0;
    /// kMemoRolling: another mover is near (SbrTracer::mover_near): only the self groups read
    /// back, and what its groups record now is never read back whole.
    bool mover_near = false;
    double kept_fraction = 0.0;  ///< its aspect change over its limit, when kept paths are used
    /// Static path reuse, per kept slice: its aspect change (or the antenna's turn) since it was
    /// traced, over its limit (choose_reuse; 0 for a bundle without valid kept paths).
    std::array<double, SbrConfig::kMaxKeptSlices> slice_fraction{};
    /// The rows traced this frame (all of them, or those of slices [slice, slice_end): one for
    /// the refresh, those past the aspect limit and any between them) and those slices
    /// (kAllSlices: the whole bundle).
    std::size_t row_lo = 0, row_hi = 0;
    std::uint8_t slice = kAllSlices, slice_end = kAllSlices;
    /// Its rows' spans of columns in row_spans_ (n_el + 1 entries from here), or kNoMask: every
    /// column of every row.
    std::size_t mask = kNoMask;
    /// Traced this frame, every row of it.
    void trace_whole() noexcept {
      trace = true;
      row_lo = 0;
      row_hi = n_el;
      slice = slice_end = kAllSlices;
    }
    /// Rows of the box's grid (slice_rows' rule), and the first of them in this grid: the grid
    /// has rows [row_offset, row_offset + n_el) of them (a target cut by the view: bundle_for).
    std::size_t n_el_full = 0, row_offset = 0;
    /// This grid's rows [lo, hi) in slice `s` of `slices` (those of the box's rows in view).
    void grid_slice_rows(int slices, int s, std::size_t& lo, std::size_t& hi) const noexcept {
      slice_rows(n_el_full, slices, s, lo, hi);
      lo = std::clamp(lo, row_offset, row_offset + n_el) - row_offset;
      hi = std::clamp(hi, row_offset, row_offset + n_el) - row_offset;
    }
    /// Traced this frame, slices [first, end) of `slices` (rows [row_lo, row_hi)).
    void trace_slices(int first, int end, int slices) noexcept {
      std::size_t lo = 0, hi = 0;
      trace = true;
      grid_slice_rows(slices, first, row_lo, hi);
      grid_slice_rows(slices, end - 1, lo, row_hi);
      slice = static_cast<std::uint8_t>(first);
      slice_end = static_cast<std::uint8_t>(end);
    }
    /// Whether slice `s`'s rays are traced this frame (a whole bundle's are).
    [[nodiscard]] bool traces_slice(int s) const noexcept {
      return trace && (slice == kAllSlices || (s >= slice && s < slice_end));
    }
  };
  static constexpr std::size_t kNoMask = static_cast<std::size_t>(-1);
  /// The columns [lo, hi) of one row of a bundle's grid where its target's facets or their
  /// ground images project (mask_rows), and the rays of the rows before it.
  struct RowSpan {
    std::uint32_t lo = 0, hi = 0;
    std::size_t first = 0;
  };
  /// Rays of `b`'s rows [lo, hi) (those its mask leaves), of those it traces this frame, and of
  /// all its rows.
  [[nodiscard]] std::size_t rays_in_rows(const Bundle& b, std::size_t lo,
                                         std::size_t hi) const noexcept;
  [[nodiscard]] std::size_t traced_rays(const Bundle& b) const noexcept {
    return b.trace ? rays_in_rows(b, b.row_lo, b.row_hi) : 0;
  }
  [[nodiscard]] std::size_t all_rays(const Bundle& b) const noexcept {
    return rays_in_rows(b, 0, b.n_el);
  }
  /// The columns [c0, c1) of row `r` of `b` that are shot.
  void row_columns(const Bundle& b, std::size_t r, std::size_t& c0, std::size_t& c1) const noexcept;
  /// The grid cell (column, row) of the j-th ray `b` traces this frame.
  void ray_cell(const Bundle& b, std::size_t j, std::size_t& ia, std::size_t& ie) const noexcept;
  /// Fills `b`'s mask (SbrConfig::mask_target_rays) for `pose`, or leaves it kNoMask.
  void mask_rows(const RadarPose& pose, std::uint32_t id, Bundle& b) const noexcept;
  /// A part of a target's facets (mask_rows): the box of their corners, body frame.
  struct PartBox {
    glm::dvec3 lo_m, hi_m;
  };
  static constexpr std::size_t kMaskParts = 16;
  void split_parts(const scene::Mesh& mesh);
  std::vector<PartBox> part_boxes_;
  std::vector<std::size_t> part_first_;  ///< per object, into part_boxes_ (+1 entry)
  /// Per object: the planes its ground image is taken in (mask_rows), and its box then.
  struct GroundPlanes {
    bool valid = false;
    glm::dvec3 bounds_min_m{0.0}, bounds_max_m{0.0};
    std::array<double, 2> mirror_z{};  ///< twice the ground's height
    int n_images = 0;
  };
  mutable std::vector<GroundPlanes> ground_planes_;
  /// Target `id`'s GroundPlanes, found again when its box has moved.
  [[nodiscard]] const GroundPlanes& ground_under(std::uint32_t id) const noexcept;
  mutable std::vector<RowSpan> row_spans_;  ///< this frame's masks (capacity set at setup)
  mutable std::size_t row_spans_used_ = 0;
  static constexpr std::uint8_t kAllSlices = 0xff;
  /// A kept target's grid keeps the rows its paths were traced with while it asks for no more
  /// than this fraction of them more or fewer (bundle_for).
  static constexpr double kKeptRowsSlack = 0.02;
  /// Rows [lo, hi) of slice `s` of `slices` in a grid of `n_el` rows: those whose centre lies in
  /// the slice's band, (ie + 1/2) / n_el in [s / slices, (s + 1) / slices).
  static void slice_rows(std::size_t n_el, int slices, int s, std::size_t& lo,
                         std::size_t& hi) noexcept;
  struct Frame {  // per-frame quantities shared by every ray
    double terrain_daz_rad = 0, terrain_del_rad = 0;
    std::size_t terrain_n_az = 0, terrain_n_el = 0;
    int max_bounces = 1;
    /// Targets in range without a bundle this frame: what terrain rays may still reach.
    std::span<const std::uint32_t> unbundled_in_range{};
  };
  [[nodiscard]] Frame frame_for(const TraceKnobs& knobs, TraceStats* stats) const noexcept;
  /// The bundle of target `id` for `pose` at `spacing_m`; false when it is out of view.
  [[nodiscard]] bool bundle_for(const RadarPose& pose, std::uint32_t id, double spacing_m,
                                Bundle& b, bool& coarsened) const noexcept;
  [[nodiscard]] double target_spacing(const TraceKnobs& knobs, std::uint32_t id,
                                      TraceStats* stats) const noexcept;
  /// Static path reuse (SbrConfig::reuse_static_paths): per bundle, whether it is traced this
  /// frame or re-evaluates its kept paths, and whether it keeps its paths once traced (the rule
  /// at SbrConfig::reuse_static_paths, then the refresh of the longest kept, paid from `credit`
  /// [rays], which it updates). The rule's last condition, the same facets left to the rays as
  /// when the paths were kept, needs this frame's facet pass: trace() checks it after
  /// (same_facets_by_rays); plan() cannot know it.
  void choose_reuse(const RadarPose& pose, int max_bounces, std::span<Bundle> bundles,
                    double& credit, bool defer_refresh) const noexcept;
  /// Whether target `id`'s facets left to the rays this frame (facet_light_) are those of when
  /// its paths were kept.
  [[nodiscard]] bool same_facets_by_rays(std::uint32_t id) const noexcept;
  /// Whether kept bundle `b`'s slices may be traced apart this frame: it has the rows (of its
  /// box's grid) its slices were kept with, so that they are each of its rows once, and does not
  /// straddle the antenna's plane (SbrConfig::reuse_static_paths).
  [[nodiscard]] bool slices_apart(const Bundle& b) const noexcept {
    return config_.reuse_refresh_slices > 1 && b.n_el_full == kept_[b.object_id].n_el && !b.behind;
  }
  /// The frame's reuse figures of `bundles` (those not traced re-evaluate kept paths).
  void count_reuse(std::span<const Bundle> bundles, TraceStats& stats) const noexcept;
  /// A kept target cut by the field of view (choose_reuse): its kept paths whose first hit has
  /// left the view are left out for good (a trace now would not shoot them), counted in
  /// stats.kept_paths_left_view, and its slices' coverage becomes the part in view now.
  void prune_outside_view(const RadarPose& pose, std::span<const Bundle> bundles,
                          TraceStats& stats) noexcept;
  /// The frame the longest kept slice of static target `id` was traced in.
  [[nodiscard]] std::uint64_t oldest_kept_at(std::uint32_t id) const noexcept;
  /// Kept returns of `b`'s slices not traced this frame (re-evaluated).
  [[nodiscard]] std::size_t untraced_kept(const Bundle& b) const noexcept;
  double refresh_credit_ = 0.0;  ///< the refresh's credit [rays] (choose_reuse)
  /// Whether a moving object other than `id` is near target `id` or its line of sight to the
  /// radar.
  [[nodiscard]] bool mover_near(const RadarPose& pose, std::uint32_t id) const noexcept;
  /// One kept return of a static target's rays (trivial: the pool is left uninitialised).
  struct KeptPath {
    glm::dvec3 first_hit_m;                 ///< the path's first hit (P1)
    glm::dvec3 last_hit_m;                  ///< the hit that radiates (Pn)
    double inner_m;                         ///< path length from P1 to Pn
    double amplitude_re_m, amplitude_im_m;  ///< the amplitude without the path phase
    std::uint8_t bounces;
    bool radiated_by_owner;
  };
  /// Per object: its kept paths, per slice of its rows (SbrConfig::reuse_refresh_slices), and
  /// the frame each slice was traced in.
  struct KeptSlice {
    glm::dvec3 radar_m{0.0};
    glm::dmat3 world_from_antenna{1.0};
    /// The part of the target its paths cover: in view when traced, less what has left the
    /// view since (prune_outside_view).
    ViewShare view;
    std::size_t count = 0;        ///< kept returns, at the front of the slice's region
    std::uint64_t traced_at = 0;  ///< frame_count_ then
  };
  struct Kept {
    bool valid = false;
    double spacing_m = 0.0;  ///< the bundle's spacing (before coarsening) and bounces then
    int max_bounces = 0;
    std::size_t n_el = 0;  ///< the bundle's rows then
    std::array<KeptSlice, SbrConfig::kMaxKeptSlices> slices{};
  };
  std::vector<Kept> kept_;
  /// Each static target's region of kept_paths_: reuse_refresh_slices regions of
  /// max_rays_per_target x max_bounces slots (a slice's rays write their returns' paths at
  /// their slots, compacted after the trace); kNoRegion for the others. Allocated at setup with
  /// reuse on, left uninitialised (pages touched as used).
  std::vector<std::size_t> kept_region_;
  /// Slots of one slice's region (max_rays_per_target x max_bounces).
  [[nodiscard]] std::size_t kept_slice_slots() const noexcept {
    return config_.max_rays_per_target * static_cast<std::size_t>(config_.max_bounces);
  }
  /// Where the ray of column ia, row ie of `bd` writes its kept paths: its slot in its slice's
  /// region.
  [[nodiscard]] KeptPath* kept_slot(const Bundle& bd, std::size_t ia, std::size_t ie,
                                    std::size_t per_ray) const noexcept;
  /// A run of kept returns evaluated this frame: one slice of a target, from `first` in the run.
  struct KeptRun {
    std::size_t first;
    std::uint32_t object_id;
    std::uint8_t slice;
  };
  std::vector<KeptRun> kept_runs_;
  std::unique_ptr<KeptPath[]> kept_paths_;
  /// Per facet of a kept target: left to the rays (kLightByRays) when its paths were kept.
  std::vector<std::uint8_t> kept_facet_by_rays_;
  /// Per facet of a static target, with reuse on: the answers of its bounce-1 occlusion queries
  /// (facet_finish: its visibility samples toward the radar, then its sub-triangles', in the
  /// order asked; bit i set: query i blocked), recorded when choose_memo says so. Later frames
  /// read the answers back instead of asking the scene again while the aspect change since
  /// bounds how far a shadow boundary can have moved across the target (at most half a ray
  /// tube, D dtheta <= spacing / 2, as for kept paths), so the facets' light is kept to the
  /// rays' own resolution; the facets' PO integrals, phases and angles are still computed for
  /// the pose. This holds whether the target's rays are kept or traced (a target cut by the
  /// field of view). A query beyond the recorded ones (a facet that was turned away then) asks
  /// the scene.
  struct FacetMemo {
    static constexpr std::size_t kBits = 320;  ///< >= kFacetSamples + kMaxFacetSubdivisions^2
    std::uint64_t blocked[kBits / 64];
    std::uint16_t count;  ///< answers recorded
  };
  std::vector<FacetMemo> facet_memo_;
  /// Per object: when and how its facets' answers were recorded.
  struct MemoState {
    bool valid = false;
    glm::dvec3 radar_m{0.0};
    double spacing_m = 0.0;
    bool centroid_only = false;
    std::uint64_t recorded_at = 0;  ///< frame_count_ then
    /// Movers: the target's region centre and placement then, and the reach of its region from
    /// its body origin (|origin - centre| + half the region's diagonal).
    glm::dvec3 centre_m{0.0};
    glm::dmat4 world_from_body{1.0};
    double reach_m = 0.0;
    /// Movers: another mover was near when recorded (its shadows in the answers): only the
    /// mover's own answers may be read back.
    bool mover_near = false;
  };
  std::vector<MemoState> memo_state_;
  static constexpr std::uint8_t kMemoNone = 0, kMemoRecord = 1, kMemoReplay = 2, kMemoRolling = 3;
  /// The facet memo of a moving target (with another mover near it or across its line of
  /// sight, only its own body's answers, facet_self_memo_), in
  /// memo_groups_ groups of its facets (facet t in group t % memo_groups_), each with its own
  /// MemoState: every frame one group (frame_count_ % memo_groups_) asks the scene again and
  /// records, so a mover's queries are spread over the frames instead of all asked in one; a
  /// group reads its answers back while recorded at this spacing and facet knob fewer than
  /// reuse_refresh_frames frames ago, and the target's motion since keeps every shadow boundary
  /// on it within half a ray tube (mover_memo_fraction <= 1). Per mover (movers_ order):
  /// memo_groups_ states from mover_memo_first_[id] (kNoRegion: not a mover).
  static constexpr std::size_t kMaxMemoGroups = 16;
  std::size_t memo_groups_ = 0;  ///< min(reuse_refresh_frames, kMaxMemoGroups); 0: reuse off
  std::vector<MemoState> mover_memo_;
  std::vector<std::size_t> mover_memo_first_;
  /// Per facet of a mover, recorded with its group's answers (mover_memo_): which of its up to
  /// kFacetSamples visibility samples the mover's own body blocked (bit i: sample i), and
  /// kSelfRecorded once recorded. Its own shadows move with its aspect only (the self fraction of
  /// mover_memo_fraction): a group whose motion since has moved the scene's shadows too far, but
  /// not its own, reads these back and asks the rest of the scene (Bundle::memo_self_groups).
  static constexpr std::uint8_t kSelfRecorded = 0x80;
  std::vector<std::uint8_t> facet_self_memo_;
  /// A mover's motion since `m` was recorded, as a fraction of what keeps its facets' answers
  /// within half a ray tube (<= 1: they may be read back); `self_fraction`: the same for the
  /// shadows its own body casts on it (its aspect change alone, the first term below).
  [[nodiscard]] double mover_memo_fraction(const RadarPose& pose, const Bundle& b,
                                           const MemoState& m,
                                           double* self_fraction = nullptr) const noexcept;
  /// The record of a mover's memo groups that asked the scene this frame (kMemoRolling).
  void record_mover_memo(const RadarPose& pose, const TraceKnobs& knobs,
                         TraceStats& stats) noexcept;
  /// Where facet t of bundle `bd` writes or reads its answers this frame (FacetMemo; null: not).
  [[nodiscard]] FacetMemo* memo_record(const Bundle& bd, std::size_t slot, std::size_t t) noexcept;
  [[nodiscard]] const FacetMemo* memo_replay(const Bundle& bd, std::size_t slot,
                                             std::size_t t) const noexcept;
  /// Per bundle: whether its facets record their answers this frame (a still target traced to
  /// keep its paths, or whose answers are out of date) or read them back (recorded at this
  /// spacing and facet knob, fewer than reuse_refresh_frames frames ago, the aspect changed by
  /// no more than half a tube across the target since), or neither (a static target with a
  /// mover near); a mover: kMemoRolling (mover_memo_; with another mover near, its own body's
  /// answers only).
  void choose_memo(const RadarPose& pose, const TraceKnobs& knobs,
                   std::span<Bundle> bundles) const noexcept;
  /// The change dtheta in the direction from target `b`'s region to the radar since the radar
  /// was at `then_m`, the limit that keeps its hit points within half a tube (spacing / 2D) and
  /// the region's extent D.
  void aspect_change(const RadarPose& pose, const Bundle& b, const glm::dvec3& then_m,
                     double& dtheta_rad, double& limit_rad, double& extent_m) const noexcept;
  /// Per object, this frame: a kept bundle's path met a moving object (not kept then).
  std::unique_ptr<std::atomic<std::uint8_t>[]> met_mover_;
  std::vector<std::uint32_t> movers_;  ///< the scene's moving objects
  std::uint64_t frame_count_ = 0;      ///< trace() calls
  /// plan()'s bundles (scratch, capacity n_targets_).
  mutable std::vector<Bundle> plan_bundles_;
  /// One ray of a batch between its hits (defined in sbr.cpp): trace_batch follows a batch of
  /// neighbouring rays hit by hit, each segment of all of them as one coherent scene query, and
  /// the shadow rays of their returns likewise.
  struct RayState;
  void trace_batch(const RadarPose& pose, const Frame& frame, std::span<RayState> rays,
                   TraceStats& stats) const noexcept;
  /// Per frame: cos and sin of every grid column's azimuth (the terrain grid's from 0, bundle
  /// b's from its first_column), computed once per column instead of once per ray; capacity
  /// for the terrain grid and 4096 columns per target (a bundle beyond it computes them per
  /// ray: the same values).
  std::vector<double> column_cos_, column_sin_;
  /// Per object, this frame: its world box padded for scene::ray_crosses_box (targets only).
  std::vector<scene::PaddedBox> frame_box_;

  /// The bounce-1 light (FacetLight, or kLightByRays) of triangle t of target `id` this frame,
  /// and its contribution when lit or partly lit, at facet_first_[id] + t;
  /// facet_first_[id + 1] - facet_first_[id] is the object's triangle count for targets, 0
  /// otherwise.
  static constexpr std::uint8_t kLightByRays = 255;  ///< near field or out of view: the rays'
  std::vector<std::size_t> facet_first_;
  /// Per facet: +1 / -1 when its wound normal points out of / into its closed part, 0: open part
  /// (sbr_core.hpp, closed parts; body frame).
  std::vector<std::int8_t> facet_outward_;
  std::vector<std::uint8_t> facet_light_;
  std::vector<Contribution> facet_out_;
  /// tan of the field of view's limits: azimuth min, max, elevation min, max (setup).
  std::array<double, 4> fov_tan_{};
  std::vector<glm::dmat4> frame_world_from_body_;  ///< per object, this frame (bundled targets)
  /// The facet pass: bounce 1 of each triangle of the bundled targets for a radar at `pose`
  /// (header), its light and its contribution when lit or partly lit, in three steps so that
  /// neighbouring facets ask their occlusion queries together. Partly lit facets are cut to
  /// their bundle's spacing (sbr_core.hpp, facet_subdivisions). A facet's answers are recorded
  /// into or replayed from its FacetMemo as memo_record / memo_replay say. What the first step
  /// (facet_geometry) found, for the last (facet_finish), world frame:
  /// (No initialisers: facet_batch keeps kFacetBatch of them on the stack per batch, each
  /// written by facet_geometry before it is read.)
  struct FacetGeometry {
    glm::dvec3 v0_m, v1_m, v2_m, centroid_m;
    glm::dvec3 n;        ///< unit normal of the lit side
    glm::dvec3 s;        ///< unit, centroid to radar
    glm::dvec3 arrival;  ///< -s in the antenna frame
    double range_m, cos_i, offset_m;
    int m;  ///< facet_subdivisions at the resolution
    std::uint32_t id;
    std::uint16_t material;
  };
  /// Triangle t of target `id`: its light when it is decided without a query (dark, or
  /// kLightByRays), or kFacetNeedsLight, `g` then filled for facet_finish.
  static constexpr std::uint8_t kFacetNeedsLight = 254;
  [[nodiscard]] std::uint8_t facet_geometry(const RadarPose& pose, std::uint32_t id, std::size_t t,
                                            double resolution_m, FacetGeometry& g) const noexcept;
  /// The facet's up-front queries, the samples its light is judged by (the centroid's alone
  /// for centroid_only or m == 1, else the seven of facet_samples): their count, and in
  /// rays[q - replayed] for q >= `replayed` (the answers a replay memo holds are not asked) the
  /// ray of query q. `rays` holds kFacetSamples.
  [[nodiscard]] std::size_t facet_sample_rays(const RadarPose& pose, const FacetGeometry& g,
                                              bool centroid_only, std::size_t replayed,
                                              std::span<scene::Ray> rays) const noexcept;
  /// The facet's light and return; its occlusion queries (counted in `queries`) are numbered in
  /// the order the rule asks them (FacetMemo). `answered`: the answers of queries
  /// first_answered, first_answered + 1, ... asked beforehand (facet_sample_rays' rays, in
  /// order); a partly lit facet's sub-triangles are asked as one batch here.
  [[nodiscard]] std::uint8_t facet_finish(const RadarPose& pose, const FacetGeometry& g,
                                          bool centroid_only, Contribution& out,
                                          std::uint64_t& queries, FacetMemo* record,
                                          const FacetMemo* replay,
                                          std::span<const std::uint8_t> answered,
                                          std::size_t first_answered) const noexcept;
  /// Items [begin, end) (at most kFacetBatch) of the frame's run of facets (trace): their
  /// geometry, then every facet's samples as one coherent batch (occluded_coherent), then each
  /// facet finished with those answers; light in facet_light_, return in facet_out_.
  /// `b`: run_item's cursor.
  static constexpr std::size_t kFacetBatch = 64;
  void facet_batch(const RadarPose& pose, const TraceKnobs& knobs, std::size_t begin,
                   std::size_t end, std::size_t& b, std::uint64_t& queries) noexcept;

  /// Diffracting edges of the targets, body frame (SbrConfig::edges): object id's are
  /// edges_body_[edge_first_[id] .. edge_first_[id + 1]); per frame, each edge's state (0 used,
  /// 1 shadowed, 2 no term) and contribution.
  std::vector<std::size_t> edge_first_;
  std::vector<WedgeEdge> edges_body_;
  std::vector<std::uint8_t> edge_state_;
  std::vector<Contribution> edge_out_;
  /// Edge `e` of target `id` for a radar at `pose` (SbrConfig::edges): its state, and its
  /// contribution in `out` when used. Adds its occlusion query to `queries`.
  [[nodiscard]] std::uint8_t edge_pass(const RadarPose& pose, std::uint32_t id, std::size_t e,
                                       Contribution& out, std::uint64_t& queries) const noexcept;
  /// Edge `e` of target `id` in the world this frame.
  [[nodiscard]] WedgeEdge world_edge(std::uint32_t id, std::size_t e) const noexcept;
  /// Edge pairs of the targets for double diffraction (SbrConfig::edge_order 2), indices into
  /// edges_body_: object id's are pairs_[pair_first_[id] .. pair_first_[id + 1]); per frame,
  /// whether each gave a contribution, and the contribution.
  std::vector<std::size_t> pair_first_;
  std::vector<EdgePair> pairs_;
  std::vector<std::uint8_t> pair_used_;
  std::vector<Contribution> pair_out_;
  /// Pair `p` of target `id` when both its edges radiate this frame (edge_state_ 0): whether it
  /// gives a term, and the term in `out`.
  [[nodiscard]] bool pair_pass(const RadarPose& pose, std::uint32_t id, std::size_t p,
                               Contribution& out) const noexcept;
  std::vector<std::uint8_t> is_target_;  ///< per object: has a conducting triangle
  std::size_t n_targets_ = 0;
  std::size_t n_az_ = 0, n_el_ = 0;                ///< terrain grid
  std::vector<Bundle> bundles_;                    ///< per frame, capacity n_targets_
  std::vector<std::uint8_t> counts_;               ///< contributions per ray slot
  std::vector<std::uint8_t> bundled_;              ///< per object, per frame: has a bundle
  std::vector<std::uint32_t> unbundled_in_range_;  ///< per frame, capacity n_targets_
  /// Whether a segment that has met no target yet can still reach one it may count (header).
  [[nodiscard]] bool may_reach_owner(const scene::Ray& ray, const Frame& frame, std::uint32_t owner,
                                     bool terrain) const noexcept;
};

}  // namespace radar_emu::radar
