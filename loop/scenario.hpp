#pragma once
// A scenario: everything one closed-loop run needs, read from TOML (setup only). The embedded
// default (default_scenario_toml()) is what `radar-emu run` runs with no file. Degrees, dB and
// other edge units appear only in the TOML; the struct holds SI.

#include <cstdint>
#include <filesystem>
#include <glm/glm.hpp>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "io/canaerospace.hpp"
#include "loop/governor.hpp"
#include "radar/em/sbr.hpp"
#include "radar/products/terrain_returns.hpp"
#include "radar/sensor/sensor.hpp"
#include "scene/placement.hpp"
#include "sim_bus/fault_injector.hpp"

namespace radar_emu::loop {

/// [weather]: the atmosphere between the radar and the scene (ITU-R P.676 gases, P.838 rain,
/// P.840 fog; radar/propagation/itu.hpp), uniform along every path. Without a [weather] table
/// the paths are free space (no atmospheric loss), as before the table existed.
struct WeatherSpec {
  bool enabled = false;             ///< the scenario has a [weather] table
  std::string condition = "clear";  ///< clear (gases only), rain, fog, rain_fog
  double rain_mm_per_h = 0.0;       ///< rain rate [mm/h] (rain, rain_fog)
  double fog_water_gm3 = 0.0;       ///< cloud/fog liquid water density [g/m^3] (fog, rain_fog)
  double humidity_gm3 = 7.5;        ///< water-vapour density [g/m^3]
  double temperature_k = 288.15;
  double pressure_hpa = 1013.25;  ///< dry-air pressure [hPa]
};

/// [scene.import]: a scene database built at setup from GIS files, by the one import path of
/// `radar-emu scene import` (loop/scene_import.hpp; the layout in scene/geodata/import.hpp).
/// Paths are relative to the scenario file (a SAR case: to the working directory, as its
/// `file`). Each field is the command's option of the same name.
struct GeodataSource {
  std::filesystem::path dem;           ///< any GDAL raster (GeoTIFF, DTED, ...); required
  std::filesystem::path surround_dem;  ///< optional coarser DEM for the surround
  std::filesystem::path landcover;     ///< optional land-cover raster (class codes)
  std::filesystem::path classes;       ///< class table TOML, required with landcover
  std::filesystem::path osm;           ///< optional OpenStreetMap file (.osm / .pbf)
  double anchor_latitude_rad = 0.0;    ///< origin of the scene's ENU frame; required
  double anchor_longitude_rad = 0.0;
  double central_east_m = 5000.0;  ///< central area, centred on the anchor
  double central_north_m = 7000.0;
  double cell_m = 5.0;                          ///< central grid cell side
  double surround_m = 0.0;                      ///< surround square side; 0: none
  double surround_cell_m = 30.0;                ///< surround grid cell side
  std::string datum = "file";                   ///< file | egm96 | ellipsoid
  int tile_cells = 64;                          ///< cells along a tile side
  int lod_levels = 3;                           ///< 1 .. 4
  std::string default_material = "grass";       ///< cells without land cover or OSM area
  std::uint64_t max_memory_bytes = 8ull << 30;  ///< refused past this estimate
};

/// Which scene database a [scene] table names: the one reading of its keys (builtin, file, seed,
/// corner_reflectors, import), shared by the scenario and `radar-emu sar` (tools/sar_case.hpp).
struct SceneSource {
  /// "airport" (scene/airport_gen.hpp), "default" (scene/default_scene.hpp) or "terrain"
  /// (scene/terrain_gen.hpp) when `file` is empty.
  std::string builtin = "airport";
  std::uint64_t seed = 1;               ///< generator seed of the built-in database
  bool corner_reflectors = false;       ///< airport only
  std::filesystem::path file;           ///< a glTF scene instead of a built-in one
  std::optional<GeodataSource> import;  ///< [scene.import]: GIS files instead of both
};
/// The keys read_scene_source() reads, for the caller's refuse_unknown().
inline constexpr std::string_view kSceneSourceKeys[] = {"builtin", "file", "seed",
                                                        "corner_reflectors", "import"};
}  // namespace radar_emu::loop
namespace radar_emu::config {
class Table;
}
namespace radar_emu::loop {
/// Reads the source keys of a [scene] table into `source` (absent keys keep its values). Throws
/// config::ConfigError ("FILE: [scene] key: what"): builtin and file together, seed with a file,
/// corner_reflectors with another scene than the airport, an unknown builtin, import with
/// builtin, file or seed, an import without dem or anchor_deg, a value out of range.
///
///   [scene.import]
///   dem = "dem.tif"                 # required; also surround_dem, landcover, classes, osm
///   anchor_deg = [-8.005, -34.878]  # required: latitude, longitude of the ENU origin
///   central_m = [4000, 4000]        # east, north extent (default 5000, 7000)
///   cell_m = 10                     # and surround_m, surround_cell_m, datum, tile_cells,
///                                   # lod_levels, default_material, max_memory_mib
void read_scene_source(const config::Table& scene, SceneSource& source);

struct Scenario {
  std::string name;
  // [run]
  std::uint64_t frames = 200;
  double rate_hz = 20.0;
  std::int64_t epoch_unix_ns = 1'767'225'600LL * 1'000'000'000LL;  ///< bus time of t = 0
  double state_timeout_s = 0.5;  ///< ownship fields older than this make the output invalid
  /// What the radar sends while its ownship state is stale (docs/icd/detections.md): "flag"
  /// (an empty list whose header has OWNSHIP_INVALID set) or "silent" (no list at all).
  bool stale_output_silent = false;
  // [scene]
  /// Built-in database when scene_file is empty: "airport" (scene/airport_gen.hpp, the
  /// default), "default" (the minimal runway scene of scene/default_scene.hpp) or "terrain"
  /// (the seed paper's 5 x 7 km database, scene/terrain_gen.hpp; its own anchor).
  std::string scene_builtin = "airport";
  std::uint64_t scene_seed = 1;  ///< generator seed of the built-in database
  /// Built-in "airport": its closed-loop objects carry 0.5 m trihedrals (a test range's).
  bool scene_corner_reflectors = false;
  std::filesystem::path scene_file;
  std::optional<GeodataSource> scene_import;  ///< [scene.import] (loop/scene_import.hpp)
  /// [[target]] tables: objects added to whichever scene the [scene] table names
  /// (docs/scene_format.md), in table order, named "target_N" (N from 1) unless named.
  std::vector<scene::TargetPlacement> targets;
  // [ownship]: constant-velocity straight flight in the scene's ENU frame
  glm::dvec3 ownship_start_enu_m{0.0, -4000.0, 230.0};
  glm::dvec3 ownship_velocity_enu_mps{0.0, 70.0, -3.67};
  double ownship_pitch_rad = 0.0;
  double ownship_roll_rad = 0.0;
  double ownship_heading_rad = 0.0;
  std::uint8_t ins_node_id = 1;
  // [input]: how the radar reads CANaerospace (identifier per field, node-ID filter)
  io::canas::DecoderConfig input{};
  double attitude_rate_hz = 80.0;
  double navigation_rate_hz = 10.0;
  // [antenna]
  double antenna_depression_rad = 0.0;   ///< boresight below the body x axis
  double beam_spacing_rad = 0.0175;      ///< azimuth step of the scan's beam positions
  double azimuth_beamwidth_rad = 0.0;    ///< 0: the beam spacing
  double elevation_beamwidth_rad = 0.0;  ///< 0: the elevation field of view
  double antenna_gain = 0.0;             ///< one-way, linear; 0: from beamwidths and efficiency
  double aperture_efficiency = 0.6;
  std::string pattern = "gaussian";    ///< uniform, cosine, gaussian, table
  std::filesystem::path pattern_file;  ///< table: CSV "angle_deg,gain_db" (azimuth cut)
  // [radar]
  double prf_hz = 20e3;
  double swath_start_m = -1.0;  ///< pulsed: first range bin; < 0: the blind range c T / 2
  radar::SbrConfig sbr{};
  /// [radar] terrain = "engine": terrain clutter from the terrain engine per range-azimuth cell
  /// (radar/products/terrain_returns.hpp), the tracer's terrain rays off (sbr.terrain_rays);
  /// "rays" (false): the tracer's terrain rays.
  bool terrain_engine = false;
  /// Engine column width (0.5 deg: half the default beamwidth; the beam's two-way Gaussian
  /// pattern, sigma 0.30 deg, sampled every 1.67 sigma sums its columns within 0.01 dB,
  /// docs/performance.md).
  double terrain_cell_azimuth_rad = 8.726646259971648e-3;
  std::int64_t terrain_cell_range_bins = 2;  ///< engine bin width, sensor range bins
  radar::SensorConfig sensor{};  ///< derived from the tables above once the file is read
  // [output]
  bool can_fd = false;  ///< detection lists as packed CAN FD frames (docs/icd/detections.md)
  /// Data cubes out (docs/cube.md): `cube` (relative to the scenario file), "" = none, and
  /// `cube_frames` FIRST:LAST (frame indices, inclusive). The CLI's --cube / --cube-frames and
  /// the Python Loop's cube= / cube_frames= replace them (loop::choose_cube).
  std::filesystem::path cube_file;
  std::uint64_t cube_first_frame = 0;
  std::uint64_t cube_last_frame = 3;
  std::string cube_source;  ///< "FILE: [output] " when the file set them, for messages
  // [faults] (sim_bus/fault_injector.hpp; seeded, so a run is reproducible from its seed)
  std::uint64_t malformed_every_n_frames = 0;  ///< 0 = no malformed-frame injection
  sim_bus::FaultConfig link_faults{};          ///< on the radar's receiving side of the bus
  bool stale_sender = false;                   ///< the INS goes stale in stale.start_s..end_s
  sim_bus::StaleConfig stale{};
  bool babbling_node = false;  ///< a node floods the bus (babble.rate_hz > 0)
  sim_bus::BabbleConfig babble{};
  WeatherSpec weather{};
  /// [governor]: the fidelity governor (loop/governor.hpp).
  GovernorConfig governor{};
};

/// The embedded default scenario, as TOML text (printed by `radar-emu run --print-scenario`).
[[nodiscard]] std::string_view default_scenario_toml() noexcept;

/// Parses a scenario. `origin` names the source in error messages ("FILE" or "<default>").
/// Throws std::runtime_error in the one format of config/toml_reader.hpp, "ORIGIN: [table] key:
/// what is wrong" ("ORIGIN:LINE:COL: what" for TOML syntax), for missing, mistyped or
/// out-of-range values; unknown keys are errors too (typos must not pass silently).
[[nodiscard]] Scenario parse_scenario(std::string_view toml_text, const std::string& origin);
[[nodiscard]] Scenario load_scenario(const std::filesystem::path& path);

/// The terrain engine's cells for [radar] terrain = "engine": the field of view in columns of
/// terrain_cell_azimuth_rad, the sensor's swath (first range bin to max_range_m) in bins of
/// terrain_cell_range_bins range bins, at the carrier.
[[nodiscard]] radar::TerrainReturnsConfig terrain_returns_config(const Scenario& s);

/// The radar's pose on the scenario's scripted flight at scenario time t_s, read from the
/// scenario alone (no bus): position start + t_s x velocity, the ownship's attitude, the
/// antenna's depression. What the offline tools, benchmarks and tests trace from; the loop takes
/// its pose from the decoded bus state instead.
[[nodiscard]] radar::RadarPose scripted_pose(const Scenario& s, double t_s = 0.0) noexcept;

}  // namespace radar_emu::loop
