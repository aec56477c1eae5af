#pragma once
// The case of `radar-emu sar` (tools/sar.hpp): its TOML parser, apart from the tool so
// that the fuzz harness (tests/fuzz/fuzz_sar_case.cpp) and tests can call it on text.

#include <cstdint>
#include <glm/glm.hpp>
#include <string>
#include <string_view>
#include <vector>

#include "common/units.hpp"
#include "loop/scenario.hpp"
#include "radar/constants.hpp"
#include "radar/em/sbr_core.hpp"
#include "radar/products/sar.hpp"
#include "scene/targets.hpp"

namespace radar_emu::tools {

/// One target of a case ([[scene.target]]).
struct TargetCase {
  std::string name;
  scene::TargetSpec spec;
  glm::dvec3 position_m{0.0};
  glm::dvec3 velocity_mps{0.0};
  double heading_rad = 0.0;  ///< non-trihedrals: body +x toward this heading (0 north, cw)
};

/// A `radar-emu sar` case (examples/sar_seed.toml documents every key), SI units; the fields
/// marked derived, the spacings and the clutter cell left 0 in the file, and p.pulses,
/// p.near_range_m, p.start_position_m and p.velocity_mps are set by parse_sar_case.
struct SarCase {
  radar::SarParams p;
  double altitude_m = 2000.0;
  double speed_mps = 100.0;
  double heading_rad = common::radians(90.0);
  double synthetic_beamwidth_rad = common::radians(0.032);
  radar::SarTaper taper = radar::SarTaper::kNone;
  std::size_t upsample = 16;
  double image_width_m = 2000.0;
  double azimuth_spacing_m = 0.0, ground_range_spacing_m = 0.0;  ///< 0: from the resolution
  double theta_rad = 0.0;                                        ///< derived
  double ground_centre_m = 0.0;                                  ///< derived
  radar::Polarisation pol = radar::Polarisation::kVV;
  std::string pol_name = "VV";
  /// [scene] builtin, file or [scene.import]: a scene database (the scenario's [scene] keys, read
  /// by loop::read_scene_source) instead of the flat ground_material plane; its anchor then
  /// georeferences the outputs (latitude_deg, longitude_deg are refused).
  bool database = false;
  loop::SceneSource source;
  /// [processing] centre_east_m, centre_north_m: the image centre (world ENU) [m].
  double centre_east_m = 0.0, centre_north_m = 0.0;
  std::string ground_material = "grass";
  bool clutter = true;
  double clutter_cell_m = 0.0;  ///< terrain engine patch size [m]; 0: half the finer pixel spacing
  std::uint64_t speckle_seed = 20261124;
  double target_ray_spacing_m = 0.05;
  int max_bounces = 3;
  double latitude_deg = 43.6, longitude_deg = 1.4;
  /// Ellipsoidal height of the scene's anchor [m] (its ENU origin): 0 for the flat ground, the
  /// database's otherwise (set by run_sar_tool); scales the GeoTIFF's transverse Mercator.
  double anchor_height_m = 0.0;
  std::vector<TargetCase> targets;
};

/// Parses a case from TOML text; `origin` (a file name) starts every error message, in the one
/// format of config/toml_reader.hpp ("ORIGIN: [table] key: what", "ORIGIN:LINE:COL: what"). Throws
/// std::invalid_argument (a TOML syntax error with its line, an unknown table or key, a value of
/// the wrong type or outside its documented range, a geometry the processing cannot use: too
/// narrow an azimuth beam for the synthetic one, a swath reaching nadir, too low a PRF, over
/// 200000 pulses); what it returns passed radar::validate() and has every derived value set.
[[nodiscard]] SarCase parse_sar_case(std::string_view text, const std::string& origin);

}  // namespace radar_emu::tools
