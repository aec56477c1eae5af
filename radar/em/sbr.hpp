#pragma once
// First shooting-and-bouncing-rays pass (Ling, Chou & Lee, IEEE TAP 37(2), 1989): ray tubes are
// shot across the antenna field of view from the radar, bounced specularly off conductors
// (geometrical optics, up to max_bounces), and at every hit the tube's footprint radiates back
// to the radar through the physical-optics integral; diffuse terrain returns sigma0 x footprint.
// Pure computation: no I/O, clocks or threads of its own.

#include <complex>
#include <cstddef>
#include <cstdint>
#include <glm/glm.hpp>
#include <span>
#include <vector>

#include "radar/clutter/terrain.hpp"
#include "radar/materials.hpp"
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
/// in metres at its range. A coarse ray that first hits a target, and a bundle ray that first hits
/// anything but its own target, returns nothing (each surface is counted once, by the grid that
/// owns it); both still shadow what lies behind.
struct SbrConfig {
  double carrier_hz = 94e9;
  double azimuth_min_rad = -0.1745;  ///< field of view, antenna frame
  double azimuth_max_rad = 0.1745;
  double elevation_min_rad = -0.0873;
  double elevation_max_rad = 0.0873;
  double terrain_ray_spacing_rad = 1e-3;    ///< angular spacing of the terrain grid (az and el)
  double target_ray_spacing_m = 0.25;       ///< bundle spacing at the target's nearest range
  std::size_t max_rays_per_target = 50000;  ///< bundles coarsen beyond this (counted)
  double max_range_m = 6000.0;              ///< rays end here (one-way)
  int max_bounces = 3;                      ///< GO bounces off conductors (>= 1)
};

/// One return: a ray tube's contribution at one hit point, as seen by the radar.
struct Contribution {
  /// Complex scattering amplitude [m]: sigma = |A|^2 (m^2), phase exp(-j k L) over the whole
  /// path L (time convention exp(+j w t)). For diffuse clutter (coherent == false) only |A|^2
  /// is meaningful and is summed as power.
  std::complex<double> amplitude{0.0, 0.0};
  double range_m = 0.0;  ///< half the total path length [m]
  /// Extent along range of a diffuse footprint [m] (the sensor spreads its power uniformly over
  /// [range_m - spread/2, range_m + spread/2]); 0 for coherent returns.
  double range_spread_m = 0.0;
  double radial_velocity_mps = 0.0;  ///< half the rate of change of the path [m/s], + receding
  double azimuth_rad = 0.0;          ///< direction of arrival at the radar, antenna frame
  double elevation_rad = 0.0;
  std::uint32_t object_id = 0;  ///< object of the last hit
  std::uint8_t bounces = 0;     ///< 1 = single bounce
  bool coherent = true;         ///< false: diffuse clutter power
};

struct TraceStats {
  std::uint64_t rays = 0;
  std::uint64_t target_bundles = 0;     ///< targets inside the field of view
  std::uint64_t coarsened_bundles = 0;  ///< bundles that hit max_rays_per_target
  std::uint64_t hits = 0;
  std::uint64_t contributions = 0;
  std::uint64_t dropped_contributions = 0;  ///< output span full
  std::uint64_t grazing_skipped = 0;        ///< footprints skipped at |cos(theta_i)| < 1e-3
};

class SbrTracer {
 public:
  /// Setup: validates the configuration (throws std::invalid_argument with the field name) and
  /// resolves scene materials to radar materials.
  SbrTracer(const scene::Scene& scene, const SbrConfig& config);

  /// Upper bound on the contributions one trace() can produce for this scene and config (size
  /// the output span with it).
  [[nodiscard]] std::size_t max_contributions() const noexcept;
  /// Shoots all rays for `pose` against the scene at its current time and writes contributions
  /// to `out` (in a deterministic order, whatever the threading). Returns the number written.
  /// `stats` is added to, not reset, so one TraceStats can total a run.
  /// Real-time safe apart from the worker threads it uses (TBB): no allocation per call. `out`
  /// must hold max_contributions() elements (fewer: the excess is dropped and counted).
  [[nodiscard]] std::size_t trace(const RadarPose& pose, std::span<Contribution> out,
                                  TraceStats& stats) noexcept;

  [[nodiscard]] const SbrConfig& config() const noexcept { return config_; }

 private:
  const scene::Scene* scene_;
  SbrConfig config_;
  std::vector<RadarMaterial> materials_;
  /// sigma0 of the terrain-catalogue materials at the carrier (issue 4's models, model "total":
  /// surface + volume), built once here; row per scene material in sigma0_row_ (-1: none).
  clutter::Sigma0Table sigma0_;
  std::vector<int> sigma0_row_;
  struct Bundle {
    std::uint32_t object_id = 0;
    double az0_rad = 0, el0_rad = 0, daz_rad = 0, del_rad = 0;
    std::size_t n_az = 0, n_el = 0, first_ray = 0;
  };
  void trace_ray(const RadarPose& pose, double az, double el, double daz, double del,
                 std::uint32_t owner, bool terrain, Contribution* slot, std::uint8_t& count,
                 TraceStats& stats) const noexcept;

  std::vector<std::uint8_t> is_target_;  ///< per object: has a conducting triangle
  std::size_t n_targets_ = 0;
  std::size_t n_az_ = 0, n_el_ = 0;   ///< terrain grid
  std::vector<Bundle> bundles_;       ///< per frame, capacity n_targets_
  std::vector<std::uint8_t> counts_;  ///< contributions per ray slot
};

}  // namespace radar_emu::radar
