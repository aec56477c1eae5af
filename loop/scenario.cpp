#include "loop/scenario.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <limits>
#include <numbers>
#include <set>
#include <sstream>
#include <stdexcept>

#include "common/polarisation.hpp"
#include "common/units.hpp"
#include "config/memory_limit.hpp"
#include "config/toml_reader.hpp"
#include "loop/outputs/cube_writer.hpp"
#include "loop/ownship.hpp"
#include "radar/em/surfaces.hpp"
#include "radar/sensor/waveform.hpp"
#include "scene/targets.hpp"
#include "scene/trajectory.hpp"

namespace radar_emu::loop {

namespace {

// The embedded default: a straight 3-degree approach to the default scene's runway (threshold at
// the ENU origin, runway to the north), a forward-looking 94 GHz radar, 20 Hz frames.
constexpr std::string_view kDefaultScenario =
    R"(# radar-emu default scenario (embedded). Units are in the key names.
name = "default approach, 94 GHz forward-looking radar over the generated airport"

[run]
frames = 200                # bounded run (10 s at 20 Hz)
rate_hz = 20.0              # radar frame rate
epoch_unix_s = 1767225600   # bus time stamp of scenario time 0 (2026-01-01T00:00:00Z)
state_timeout_s = 0.5       # older ownship data marks the output invalid
stale_output = "flag"       # while stale: "flag" (empty list, OWNSHIP_INVALID) or "silent"

[scene]
builtin = "airport"         # "airport" (generated, seed below), "default" (runway only),
                            # "terrain" (the seed paper's 5 x 7 km database), or file = "x.glb"
seed = 1                    # generator seed of the built-in database
corner_reflectors = false   # airport: 0.5 m trihedrals on the closed-loop objects, as on a
                            # test range (off: seen by their own edges and ground coupling)

[ownship]
# Straight flight in the scene's East-North-Up frame: 4 km short of the threshold, on a
# 3-degree glide path (70 m/s ground speed, 3.67 m/s sink rate), nose 2 degrees up.
start_enu_m = [0.0, -4000.0, 230.0]
velocity_enu_mps = [0.0, 70.0, -3.67]
pitch_deg = 2.0
roll_deg = 0.0
heading_deg = 0.0
ins_node_id = 1
attitude_rate_hz = 80.0     # CANaerospace v1.7 baseline schedule
navigation_rate_hz = 10.0

[input]
# CANaerospace input (docs/icd/canaerospace_input.md): accept frames from this node-ID only
# (-1: any node), and the identifier of each field (defaults: CANaerospace v1.7 appendix A).
node_id = -1
pitch_id = 311
roll_id = 312
true_heading_id = 1133      # or 321 (heading angle), 1069 (magnetic heading): another heading!
latitude_id = 1036          # or 1049 (INS latitude)
longitude_id = 1037         # or 1050 (INS longitude)
height_id = 1038            # or 1051 (INS height)
vel_east_id = 1130
vel_north_id = 1131
vel_up_id = 1132

[output]
can_fd = false              # detection lists as packed CAN FD frames (0x70B/0x70C) instead of classic
# cube = "cube.h5"          # data cubes out (docs/cube.md), relative to this file; as --cube
# cube_frames = "0:3"       # frames it holds, FIRST:LAST; as --cube-frames (the CLI wins)

[antenna]
depression_deg = 5.0        # boresight below the body x axis (3 deg below the horizon here)
azimuth_min_deg = -8.0
azimuth_max_deg = 8.0
elevation_min_deg = -4.0
elevation_max_deg = 4.0
azimuth_cell_deg = 1.0      # beam spacing: the scan's beam positions across the field of view
pattern = "gaussian"        # uniform | cosine | gaussian | table (pattern_file, CSV angle_deg,gain_db)
azimuth_beamwidth_deg = 1.0 # one-way 3 dB, each squinted monopulse beam
elevation_beamwidth_deg = 8.0
monopulse = true            # amplitude-comparison sum and difference channels
squint_fraction = 0.5       # squint of the monopulse beams, in beamwidths
efficiency = 0.6            # gain = efficiency x 4 pi / (beamwidth_az x beamwidth_el) unless gain_db
polarisation = "VV"         # VV | HH | HV | VH (receive first; V = antenna up, H = right)

[radar]
waveform = "pulsed_lfm"     # pulsed_lfm | fmcw
carrier_hz = 94.0e9
bandwidth_hz = 50.0e6       # range resolution c/2B = 3.0 m
prf_hz = 20.0e3             # unambiguous range 7.5 km, unambiguous velocity +-15.9 m/s
pulses = 32                 # per beam position: velocity bin 1.0 m/s; 16 beams x 1.6 ms = 25.6 ms
pulse_width_s = 2.0e-6      # B T = 100; blind range 300 m
tx_power_w = 500.0          # peak (4 % duty: 20 W mean)
noise_figure_db = 5.0
system_losses_db = 3.0
swath_start_m = 1500.0      # range gate: the beam's lowest edge meets the ground at 1.9 km
max_range_m = 6000.0        # swath end: 1502 range bins of 3 m
range_window = "hann"       # rectangular | hann | hamming | blackman | taylor
doppler_window = "hann"
max_bounces = 3
terrain = "engine"          # terrain clutter: "engine" (per range-azimuth cell) | "rays" (the
                            # tracer's terrain grid)
terrain_ray_spacing_deg = 0.0573   # 1 mrad: terrain rays' grid; the tracer's terrain detail
target_ray_spacing_m = 0.1
max_rays_per_target = 20000 # bundles of larger targets (the parked transports) coarsen (counted)
mask_target_rays = true     # a target's rays only where its facets (or their ground images) are
edges = true                # edge diffraction (PTD fringe edge currents) of the targets' wedges
edge_turn_deg = 30.0        # shared edges turning by more than this diffract
reuse_static_paths = true   # targets that do not move keep their rays' paths between frames,
                            # re-evaluated for each pose (single bounces exact; multiple bounces
                            # within the phase below); traced again once the aspect has changed
reuse_max_phase_deg = 22.5  # (docs/performance.md, "Static path reuse")
reuse_refresh_frames = 16   # about 1/16 of the kept rays are traced again every frame
reuse_refresh_slices = 4    # a bundle refreshed a quarter of its rows at a time

[detector]
cfar = "ca"                 # ca | os
cfar_training_cells = 12    # per side, along range
cfar_guard_cells = 2
cfar_velocity_training_cells = 0   # range-only: ground clutter is a ridge in velocity, and a 2-D
cfar_velocity_guard_cells = 0      # window would average it with the empty velocity bins
cfar_pfa = 1.0e-6
min_snr_db = 13.0
max_detections = 64
noise_seed = 20261123       # receiver noise and clutter speckle; fixed for reproducible runs
return_floor_db = -60.0     # a return whose peak in a beam is more than 60 dB below a cell's noise
                            # is left out of that beam's image (counted in report.json: sensor
                            # returns_below_floor; a coherent one under it in every beam is left
                            # out before the merge: returns_under_floor); -400: off, every return
                            # kept

[faults]
# Software-bus fault injection (sim_bus/fault_injector.hpp), all off by default. Seeded: a run
# is reproducible from its seed, and bus_in.log holds what the radar received after the faults.
malformed_every_n_frames = 0  # >0: a faulty node sends a malformed CANaerospace frame this often
seed = 20261123               # fault generator seed
drop_probability = 0.0        # radar's receiving side: frames lost
delay_s = 0.0                 # added latency ...
jitter_s = 0.0                # ... +- uniform jitter (<= delay_s)
corrupt_probability = 0.0     # frames with 1..corrupt_max_bits bits flipped
corrupt_max_bits = 1
reorder_probability = 0.0     # a frame swaps with the next one
duplicate_probability = 0.0   # a frame is received twice
stale_mode = "none"           # INS sender: "none", "silent", "frozen", "frozen_value" ...
stale_start_s = 0.0           # ... from this scenario time ...
stale_end_s = 0.0             # ... to this one
babble_rate_hz = 0.0          # >0: a node floods the bus with babble_id at this rate
babble_id = 0
babble_start_s = 0.0
babble_end_s = 0.0            # 0: until the end

[governor]
# The fidelity governor: before each frame is traced it picks the finest level of detail whose
# predicted trace + sensor time fits compute_fraction of the frame period. Each level halves the
# target rays (the weakest targets first) and thins the terrain grid; a frame below the
# scenario's own fidelity is flagged DEGRADED (status 0x10) in the detection list header.
enabled = true
compute_fraction = 0.5      # the rest of the period absorbs the cost model's error and jitter
mode = "auto"               # auto (measured with --realtime, else model) | model | measured
# The cost model, fitted on the project's 2-core machine (scripts/fit-governor-costs.py fits it
# to another): wall time of the trace per frame, per facet of the targets in view (their
# bounce-1 facet pass), per ray traced, per kept path re-evaluated ([radar] reuse_static_paths)
# and per terrain-engine patch (0 here: the engine runs beside the tracer, in the time its
# passes leave a core idle); of the sensor per cell synthesised, per return of the rays, more
# per such return it does not merge into another, and per return of the terrain engine.
trace_ms_per_frame = 1.5
trace_ns_per_facet = 345.0
trace_ns_per_ray = 216.0
trace_ns_per_kept_return = 91.0
terrain_ns_per_patch = 0.0
sensor_ns_per_cell = 12.5
sensor_ns_per_return = 107.0
sensor_ns_per_unmerged_return = 0.0
sensor_ns_per_terrain_return = 0.0
max_level = 12              # coarsest: target rays / 64, terrain grid spacing x 8

# [weather]                   # no table: free space. With one, every return loses the two-way
#                             # attenuation of ITU-R P.676 (gases), P.838 (rain), P.840 (fog)
# condition = "clear"         # clear (gases only) | rain | fog | rain_fog
# rain_rate_mmph = 4.0        # rain, rain_fog (default 4: moderate rain)
# fog_water_gpm3 = 0.05       # fog, rain_fog: liquid water (0.05 medium fog, 0.5 thick)
# humidity_gpm3 = 7.5         # water-vapour density
# temperature_c = 15.0
# pressure_hpa = 1013.25      # dry-air pressure

# [[target]]                  # none by default. Each [[target]] table adds one object to the
#                             # scene above (built-in or file), docs/scene_format.md
# name = "fuel_truck"         # in truth.json and detections.json (default "target_N")
# builtin = "truck"           # plate, dihedral, trihedral-square, trihedral-tri, sphere,
#                             # cylinder, box, vehicle, truck, jeep, helicopter,
#                             # transport_aircraft; or mesh_file = "x.glb" (.gltf, .obj, .stl)
# size_m = [8.0, 2.5, 3.4]    # the kind's dimensions (vehicles and aircraft have defaults)
# material = "metal"          # a radar material (the default)
# position_enu_m = [60.0, 150.0, 0.0]  # scene East-North-Up [m], or waypoints_enu_m = [[e, n, u],
#                             # ...] with speed_mps, turn_radius_m, closed (nose along the path)
# on_ground = true            # u: height of its lowest point above the ground below it
# heading_deg = 270.0         # nose, clockwise from north (90 = east)
# speed_mps = 5.0             # 0: fixed; > 0: straight line along course_deg (default heading_deg)
)";

// The largest built-in [[target]] mesh (triangles): about 4 GB while made (scene/targets.hpp).
constexpr double kMaxTargetTriangles = 20e6;

using config::Range;
using config::Table;

// [ownship] start_enu_m and friends: three numbers, each within +-limit.
// [weather]: the condition picks which precipitation is present; its amount defaults to a
// typical value: moderate rain 4 mm/h, medium fog 0.05 g/m^3 (visibility about 300 m; ITU-R
// P.840-4 sec. 2 gives 0.05 g/m^3 for medium and 0.5 g/m^3 for thick fog, about 50 m).
void apply_weather(Scenario& s, const Table& root) {
  if (!root.has("weather"))
    return;
  WeatherSpec& w = s.weather;
  w.enabled = true;
  const Table t = root.table("weather");
  t.refuse_unknown({"condition", "rain_rate_mmph", "fog_water_gpm3", "humidity_gpm3",
                    "temperature_c", "pressure_hpa"});
  t.choice("condition", w.condition, {"clear", "rain", "fog", "rain_fog"});
  const bool rain = w.condition == "rain" || w.condition == "rain_fog";
  const bool fog = w.condition == "fog" || w.condition == "rain_fog";
  double rain_mmph = -1.0, fog_gpm3 = -1.0;  // < 0: not given
  t.number("rain_rate_mmph", rain_mmph, {0.0, 300.0});
  t.number("fog_water_gpm3", fog_gpm3, {0.0, 5.0});
  if (rain && rain_mmph == 0.0)
    t.fail("rain_rate_mmph", "must be > 0 with condition \"" + w.condition + "\"");
  if (!rain && rain_mmph > 0.0)
    t.fail("rain_rate_mmph", "must be 0 with condition \"" + w.condition + "\" (or use \"rain\")");
  if (fog && fog_gpm3 == 0.0)
    t.fail("fog_water_gpm3", "must be > 0 with condition \"" + w.condition + "\"");
  if (!fog && fog_gpm3 > 0.0)
    t.fail("fog_water_gpm3", "must be 0 with condition \"" + w.condition + "\" (or use \"fog\")");
  w.rain_mm_per_h = rain ? (rain_mmph > 0.0 ? rain_mmph : 4.0) : 0.0;
  w.fog_water_gm3 = fog ? (fog_gpm3 > 0.0 ? fog_gpm3 : 0.05) : 0.0;
  t.number("humidity_gpm3", w.humidity_gm3, {0.0, 50.0});
  double temperature_c = w.temperature_k - 273.15;
  t.number("temperature_c", temperature_c, {-40.0, 50.0});
  w.temperature_k = temperature_c + 273.15;
  t.number("pressure_hpa", w.pressure_hpa, {300.0, 1100.0});
}

// [governor] (loop/governor.hpp).
void apply_governor(Scenario& s, const Table& root) {
  GovernorConfig& g = s.governor;
  const Table t = root.table("governor");
  t.refuse_unknown({"enabled", "compute_fraction", "mode", "trace_ms_per_frame",
                    "trace_ns_per_facet", "trace_ns_per_ray", "trace_ns_per_kept_return",
                    "sensor_ns_per_cell", "sensor_ns_per_return", "sensor_ns_per_unmerged_return",
                    "sensor_ns_per_terrain_return", "terrain_ns_per_patch", "max_level"});
  t.boolean("enabled", g.enabled);
  t.number("compute_fraction", g.compute_fraction, {0.01, 1.0});
  std::string mode;
  t.choice("mode", mode, {"auto", "model", "measured"});
  if (mode == "auto")
    g.mode = GovernorConfig::Mode::kAuto;
  else if (mode == "model")
    g.mode = GovernorConfig::Mode::kModel;
  else if (mode == "measured")
    g.mode = GovernorConfig::Mode::kMeasured;
  t.number("trace_ns_per_ray", g.trace_ns_per_ray, {1e-3, 1e6});
  t.number("trace_ms_per_frame", g.trace_ms_per_frame, {0.0, 1e6});
  t.number("trace_ns_per_facet", g.trace_ns_per_facet, {0.0, 1e6});
  t.number("trace_ns_per_kept_return", g.trace_ns_per_kept_return, {0.0, 1e6});
  t.number("sensor_ns_per_cell", g.sensor_ns_per_cell, {0.0, 1e6});
  t.number("sensor_ns_per_return", g.sensor_ns_per_return, {0.0, 1e6});
  t.number("sensor_ns_per_unmerged_return", g.sensor_ns_per_unmerged_return, {0.0, 1e6});
  t.number("sensor_ns_per_terrain_return", g.sensor_ns_per_terrain_return, {0.0, 1e6});
  t.number("terrain_ns_per_patch", g.terrain_ns_per_patch, {0.0, 1e6});
  t.integer("max_level", g.max_level, 0, FidelityGovernor::kMaxLevel);
}

// [[target]] tables (docs/scene_format.md): objects added to the scene, named "[[target]] #N"
// in messages, N counted from 1 in file order.

std::string show(double v) {
  std::ostringstream os;
  os << v;
  return os.str();
}

constexpr std::array<std::string_view, 18> kTargetKeys{
    "name",          "builtin",         "size_m",       "facet_m",   "mesh_file",
    "mesh_scale",    "mesh_front_axis", "mesh_up_axis", "material",  "position_enu_m",
    "on_ground",     "heading_deg",     "course_deg",   "speed_mps", "waypoints_enu_m",
    "turn_radius_m", "closed",          "bank"};

// The radar material resolver decides which names exist (radar/em/surfaces.hpp).
void check_material(const Table& r, const std::string& name) {
  if (!radar::is_surface_material(name)) {
    r.fail("material",
           "unknown value \"" + name + "\" (known: " + radar::surface_material_names() + ")");
  }
}

// A built-in target: its kind, size and facet size (refused past the memory limit).
void read_target_builtin(const Table& r, const std::string& builtin, scene::TargetPlacement& t) {
  const std::optional<scene::TargetKind> kind = scene::target_kind_from_name(builtin);
  if (!kind)
    r.unknown_value("builtin", builtin, scene::target_names());
  scene::TargetSpec spec;
  spec.kind = *kind;
  // The kind's dimensions and default size: the one table `scene target` reads too.
  const scene::TargetKindSize ks = scene::target_kind_size(*kind);
  const auto dims = static_cast<std::size_t>(ks.dims);
  std::vector<double> size;
  if (std::optional<std::vector<double>> given = r.numbers("size_m")) {
    size = std::move(*given);
    if (size.size() != dims) {
      r.fail("size_m", "a " + builtin + " takes " + std::to_string(dims) + " dimension" +
                           (dims > 1 ? "s " : " ") + std::string(ks.meaning) + " in metres, got " +
                           std::to_string(size.size()));
    }
    for (double v : size)
      r.check("size_m", v, {0.0, 1e4, true});
  } else if (ks.default_m) {
    size.assign(ks.default_m->begin(), ks.default_m->begin() + ks.dims);
  } else {
    r.fail("size_m",
           "is required for a " + builtin + ": " + std::string(ks.meaning) + " in metres");
  }
  spec.a_m = size[0];
  spec.b_m = size.size() > 1 ? size[1] : 1.0;
  spec.c_m = size.size() > 2 ? size[2] : 1.0;
  t.builtin = spec;
  r.number("facet_m", t.facet_m, {0.0, 1e4});
  {
    // The mesh past the memory limit is refused with its estimate, before it is made (the
    // same limit as `scene target`'s default --max-triangles).
    scene::TargetSpec sized = spec;
    sized.facet_m = t.facet_m;
    const double triangles = scene::target_triangle_estimate(sized);
    if (triangles > kMaxTargetTriangles) {
      std::ostringstream os;
      os.precision(3);
      os << "a " << builtin << " with " << t.facet_m << " m facets would have about " << triangles
         << " triangles (about " << triangles * scene::kTargetBytesPerTriangle * 1e-9
         << " GB of memory), over the limit of " << kMaxTargetTriangles << " triangles";
      r.fail("facet_m", os.str());
    }
  }
  for (const char* key : {"mesh_scale", "mesh_front_axis", "mesh_up_axis"}) {
    if (r.has(key))
      r.fail(key, "applies to mesh_file only");
  }
}

// A target from a mesh file: its scale and axes.
void read_target_mesh(const Table& r, const std::string& mesh_file, scene::TargetPlacement& t) {
  if (mesh_file.empty())
    r.fail("mesh_file", "must not be empty");
  t.mesh_file = mesh_file;
  r.number("mesh_scale", t.mesh_scale, {0.0, 1e6, true});
  for (auto [key, out] : {std::pair{"mesh_front_axis", &t.mesh_front_axis},
                          std::pair{"mesh_up_axis", &t.mesh_up_axis}}) {
    std::string axis;
    if (r.choice(key, axis, {"+x", "-x", "+y", "-y", "+z", "-z"}))
      *out = scene::mesh_axis_from_name(axis);
  }
  if (t.mesh_front_axis && t.mesh_up_axis &&
      static_cast<int>(*t.mesh_front_axis) / 2 == static_cast<int>(*t.mesh_up_axis) / 2) {
    r.fail("mesh_up_axis", "must be another axis than mesh_front_axis");
  }
  for (const char* key : {"size_m", "facet_m"}) {
    if (r.has(key))
      r.fail(key, "applies to builtin targets only");
  }
}

// A target moving along waypoints at a speed.
void read_target_path(const Table& r, scene::TargetPlacement& t) {
  for (const char* key : {"position_enu_m", "heading_deg", "course_deg"}) {
    if (r.has(key)) {
      r.fail(key,
             "does not go with waypoints_enu_m (the path places the target and turns its nose "
             "along the velocity)");
    }
  }
  const std::vector<std::vector<double>> points = *r.vectors("waypoints_enu_m", 3, {-1e6, 1e6});
  if (points.size() < 2) {
    r.fail("waypoints_enu_m",
           "expected at least 2 [e, n, u] points, got " + std::to_string(points.size()));
  }
  for (const std::vector<double>& p : points)
    t.waypoints_m.emplace_back(p[0], p[1], p[2]);
  for (std::size_t i = 0; i + 1 < t.waypoints_m.size(); ++i) {
    const glm::dvec3 d = t.waypoints_m[i + 1] - t.waypoints_m[i];
    if (std::hypot(d.x, d.y) < 1e-6) {
      r.fail("waypoints_enu_m", "points " + std::to_string(i) + " and " + std::to_string(i + 1) +
                                    " are at the same (e, n): waypoints must be distinct (no "
                                    "vertical legs)");
    }
  }
  r.require("speed_mps", "with waypoints_enu_m");
  if (!(t.speed_mps > 0.0))
    r.fail("speed_mps", "must be > 0 with waypoints_enu_m (got " + show(t.speed_mps) + ")");
  r.number("turn_radius_m", t.turn_radius_m, {0.0, 1e5});
  r.boolean("closed", t.closed);
  r.boolean("bank", t.bank);
  scene::Trajectory tr;
  tr.waypoints_m = t.waypoints_m;
  tr.speed_mps = t.speed_mps;
  tr.turn_radius_m = t.turn_radius_m;
  tr.loop = t.closed;
  try {
    (void)scene::TrajectoryPath(tr);
  } catch (const std::invalid_argument& e) {
    r.fail("waypoints_enu_m", e.what());
  }
}

// A target at a position, fixed or moving straight on a course.
void read_target_fixed(const Table& r, scene::TargetPlacement& t) {
  for (const char* key : {"turn_radius_m", "closed", "bank"}) {
    if (r.has(key))
      r.fail(key, "applies to waypoints_enu_m only");
  }
  if (!r.has("position_enu_m"))
    r.fail("", "needs position_enu_m = [e, n, u] or waypoints_enu_m = [[e, n, u], ...]");
  r.vec3("position_enu_m", t.position_m, 1e6);
  double heading_deg = 0.0, course_deg = 0.0;
  const bool has_heading = r.number("heading_deg", heading_deg, {-360.0, 360.0});
  const bool has_course = r.number("course_deg", course_deg, {-360.0, 360.0});
  if (has_course && !(t.speed_mps > 0.0))
    r.fail("course_deg", "needs speed_mps > 0 (a fixed target has a heading_deg only)");
  // A moving target faces its velocity unless both angles are given.
  t.heading_rad = common::radians(has_heading ? heading_deg : course_deg);
  t.course_rad = common::radians(has_course ? course_deg : heading_deg);
}

scene::TargetPlacement parse_target(const Table& r, std::size_t number) {
  r.refuse_unknown(kTargetKeys);
  scene::TargetPlacement t;
  t.context = r.file() + ": " + r.name();
  t.name = "target_" + std::to_string(number);
  if (r.string("name", t.name) && t.name.empty())
    r.fail("name", "must not be empty");

  // What it is: a built-in target or a mesh file.
  std::string builtin, mesh_file;
  const bool has_builtin = r.string("builtin", builtin);
  const bool has_mesh = r.string("mesh_file", mesh_file);
  if (has_builtin && has_mesh)
    r.fail("mesh_file", "builtin and mesh_file exclude each other (give one)");
  if (!has_builtin && !has_mesh) {
    r.fail("", "needs builtin = \"KIND\" (" + scene::target_names() +
                   ") or mesh_file = \"FILE\" (.glb, .gltf, .obj, .stl)");
  }
  if (has_builtin)
    read_target_builtin(r, builtin, t);
  else
    read_target_mesh(r, mesh_file, t);
  if (r.string("material", t.material)) {
    if (t.material.empty())
      r.fail("material", "must not be empty");
    check_material(r, t.material);
  }

  // Where and how it moves.
  r.boolean("on_ground", t.on_ground);
  r.number("speed_mps", t.speed_mps, {0.0, 1000.0});
  if (r.has("waypoints_enu_m"))
    read_target_path(r, t);
  else
    read_target_fixed(r, t);
  return t;
}

void apply_targets(Scenario& s, const Table& root) {
  if (!root.has("target"))
    return;
  s.targets.clear();
  std::set<std::string> names;
  for (const Table& r : root.tables("target")) {
    scene::TargetPlacement t = parse_target(r, s.targets.size() + 1);
    if (!names.insert(t.name).second)
      r.fail("name", "\"" + t.name + "\" is already used by another [[target]]");
    s.targets.push_back(std::move(t));
  }
}

// [run]: frames, rate, epoch, state freshness.
void read_run(Scenario& s, const Table& root) {
  const Table run = root.table("run");
  run.refuse_unknown({"frames", "rate_hz", "epoch_unix_s", "state_timeout_s", "stale_output"});
  run.integer("frames", s.frames, 1, 100'000'000);
  run.number("rate_hz", s.rate_hz, {0.1, 10'000.0});
  std::int64_t epoch_s = s.epoch_unix_ns / 1'000'000'000LL;
  run.integer("epoch_unix_s", epoch_s, 0, 4'000'000'000LL);
  s.epoch_unix_ns = epoch_s * 1'000'000'000LL;
  run.number("state_timeout_s", s.state_timeout_s, {0.001, 3600.0});
  std::string stale_output = s.stale_output_silent ? "silent" : "flag";
  run.choice("stale_output", stale_output, {"flag", "silent"});
  s.stale_output_silent = stale_output == "silent";
}

// [scene.import]: the GIS inputs and the options of `radar-emu scene import`, SI inside.
GeodataSource read_import(const Table& im) {
  im.refuse_unknown({"dem", "surround_dem", "landcover", "classes", "osm", "anchor_deg",
                     "central_m", "cell_m", "surround_m", "surround_cell_m", "datum", "tile_cells",
                     "lod_levels", "default_material", "max_memory_mib"});
  im.require("dem");
  im.require("anchor_deg");
  GeodataSource g;
  std::string path;
  const auto read_path = [&](std::string_view key, std::filesystem::path& out) {
    if (im.string(key, path)) {
      if (path.empty())
        im.fail(key, "is empty (leave the key out instead)");
      out = path;
    }
  };
  read_path("dem", g.dem);
  read_path("surround_dem", g.surround_dem);
  read_path("landcover", g.landcover);
  read_path("classes", g.classes);
  read_path("osm", g.osm);
  if (!g.landcover.empty() && g.classes.empty())
    im.fail("landcover", "needs classes = \"TABLE.toml\" (examples/landcover/)");
  double anchor_deg[2] = {0.0, 0.0};
  im.vector("anchor_deg", anchor_deg, {-180.0, 180.0});
  if (!(std::abs(anchor_deg[0]) < 89.0))
    im.fail("anchor_deg", "latitude within +-89 deg");
  g.anchor_latitude_rad = common::radians(anchor_deg[0]);
  g.anchor_longitude_rad = common::radians(anchor_deg[1]);
  double central_m[2] = {g.central_east_m, g.central_north_m};
  im.vector("central_m", central_m, {0.0, 1e6, true});
  g.central_east_m = central_m[0];
  g.central_north_m = central_m[1];
  im.number("cell_m", g.cell_m, {0.0, 1e4, true});
  im.number("surround_m", g.surround_m, {0.0, 1e7});
  im.number("surround_cell_m", g.surround_cell_m, {0.0, 1e5, true});
  im.choice("datum", g.datum, {"file", "egm96", "ellipsoid"});
  im.integer("tile_cells", g.tile_cells, 1, 4096);
  im.integer("lod_levels", g.lod_levels, 1, 4);
  im.string("default_material", g.default_material);
  if (!radar::is_surface_material(g.default_material))
    im.unknown_value("default_material", g.default_material, radar::surface_material_names());
  double max_mib = static_cast<double>(g.max_memory_bytes) / 1048576.0;
  im.number("max_memory_mib", max_mib, {1.0, 1048576.0});
  g.max_memory_bytes = static_cast<std::uint64_t>(max_mib * 1048576.0);
  return g;
}

}  // namespace

void read_scene_source(const Table& scene, SceneSource& src) {
  // One source of the scene: a table that names both would silently use the file.
  if (scene.has("builtin") && scene.has("file"))
    scene.fail("file", "builtin and file exclude each other (give one)");
  if (scene.has("import")) {
    for (const char* other : {"builtin", "file", "seed", "corner_reflectors"})
      if (scene.has(other))
        scene.fail(other, "excludes [scene.import] (the database is built from its GIS files)");
    src.import = read_import(scene.table("import"));
    src.file.clear();
    return;
  }
  if (scene.has("builtin") || scene.has("file"))
    src.import.reset();
  if (scene.has("seed") && scene.has("file"))
    scene.fail("seed", "seeds a built-in scene, not a file");
  scene.choice("builtin", src.builtin, {"airport", "default", "terrain"});
  std::int64_t scene_seed = static_cast<std::int64_t>(src.seed & 0x7fffffffffffffffull);
  scene.integer("seed", scene_seed, 0, std::numeric_limits<std::int64_t>::max());
  src.seed = static_cast<std::uint64_t>(scene_seed);
  scene.boolean("corner_reflectors", src.corner_reflectors);
  std::string file;
  scene.string("file", file);
  if (!file.empty())
    src.file = file;
  if (scene.has("corner_reflectors") && (src.builtin != "airport" || !src.file.empty()))
    scene.fail("corner_reflectors",
               "applies to builtin = \"airport\" only (the runway scene "
               "\"default\" is a test range: it always has them)");
}

namespace {

// [scene]: which scene database, its seed.
void read_scene(Scenario& s, const Table& root) {
  const Table scene = root.table("scene");
  scene.refuse_unknown(kSceneSourceKeys);
  SceneSource src{s.scene_builtin, s.scene_seed, s.scene_corner_reflectors, s.scene_file,
                  s.scene_import};
  read_scene_source(scene, src);
  s.scene_builtin = src.builtin;
  s.scene_seed = src.seed;
  s.scene_corner_reflectors = src.corner_reflectors;
  s.scene_file = src.file;
  s.scene_import = src.import;
}

// [ownship]: the scripted start state and the INS rates.
void read_ownship(Scenario& s, const Table& root) {
  const Table own = root.table("ownship");
  own.refuse_unknown({"start_enu_m", "velocity_enu_mps", "pitch_deg", "roll_deg", "heading_deg",
                      "ins_node_id", "attitude_rate_hz", "navigation_rate_hz"});
  own.vec3("start_enu_m", s.ownship_start_enu_m, 1e6);
  own.vec3("velocity_enu_mps", s.ownship_velocity_enu_mps, 1500.0);
  own.degrees("pitch_deg", s.ownship_pitch_rad, {-90.0, 90.0});
  own.degrees("roll_deg", s.ownship_roll_rad, {-180.0, 180.0});
  own.degrees("heading_deg", s.ownship_heading_rad, {-360.0, 360.0});
  own.integer("ins_node_id", s.ins_node_id, 0, 255);
  own.number("attitude_rate_hz", s.attitude_rate_hz, {0.1, 1000.0});
  own.number("navigation_rate_hz", s.navigation_rate_hz, {0.1, 1000.0});
}

// [antenna]: the scan, the pattern, the gain and the polarisation.
void read_antenna(Scenario& s, const Table& root) {
  const Table ant = root.table("antenna");
  ant.refuse_unknown({"depression_deg", "azimuth_min_deg", "azimuth_max_deg", "elevation_min_deg",
                      "elevation_max_deg", "azimuth_cell_deg", "gain_db", "pattern", "pattern_file",
                      "azimuth_beamwidth_deg", "elevation_beamwidth_deg", "monopulse",
                      "squint_fraction", "efficiency", "polarisation"});
  ant.degrees("depression_deg", s.antenna_depression_rad, {-90.0, 90.0});
  ant.degrees("azimuth_min_deg", s.sbr.azimuth_min_rad, {-89.0, 89.0});
  ant.degrees("azimuth_max_deg", s.sbr.azimuth_max_rad, {-89.0, 89.0});
  ant.degrees("elevation_min_deg", s.sbr.elevation_min_rad, {-89.0, 89.0});
  ant.degrees("elevation_max_deg", s.sbr.elevation_max_rad, {-89.0, 89.0});
  ant.degrees("azimuth_cell_deg", s.beam_spacing_rad, {0.01, 90.0});
  ant.degrees("azimuth_beamwidth_deg", s.azimuth_beamwidth_rad, {0.01, 60.0});
  ant.degrees("elevation_beamwidth_deg", s.elevation_beamwidth_rad, {0.01, 60.0});
  ant.decibels("gain_db", s.antenna_gain, {0.0, 80.0});
  ant.number("efficiency", s.aperture_efficiency, {0.01, 1.0});
  ant.choice("pattern", s.pattern, {"uniform", "cosine", "gaussian", "table"});
  std::string pattern_file;
  ant.string("pattern_file", pattern_file);
  if (!pattern_file.empty())
    s.pattern_file = pattern_file;
  {
    // Receive first, as the RCS tool: "HV" = receive H, transmit V (radar/em/sbr.hpp).
    // The one polarisation parser (common/polarisation.hpp): either case, as --pol.
    std::string pol(common::polarisation_name(s.sbr.polarisation));
    ant.string("polarisation", pol);
    try {
      s.sbr.polarisation = common::parse_polarisation(pol);
    } catch (const std::invalid_argument& e) {
      ant.fail("polarisation", e.what());
    }
  }
  ant.boolean("monopulse", s.sensor.antenna.monopulse);
  ant.number("squint_fraction", s.sensor.antenna.squint_fraction, {0.05, 0.95});
  radar::PatternKind kind{};
  if (!radar::parse_pattern_kind(s.pattern, kind))
    ant.unknown_value("pattern", s.pattern, "uniform, cosine, gaussian, table");
  if (kind == radar::PatternKind::kTable && s.pattern_file.empty())
    ant.fail("pattern_file", "is required with pattern = \"table\"");
  if (kind != radar::PatternKind::kTable && ant.has("pattern_file"))
    ant.fail("pattern_file",
             "is read with pattern = \"table\" only (pattern is \"" + s.pattern + "\")");
  if (ant.has("gain_db") && ant.has("efficiency"))
    ant.fail("efficiency", "unused when gain_db is given (give one)");
  if (!(s.sbr.azimuth_min_rad < s.sbr.azimuth_max_rad)) {
    ant.fail("azimuth_max_deg", "must be greater than azimuth_min_deg");
  }
  if (!(s.sbr.elevation_min_rad < s.sbr.elevation_max_rad)) {
    ant.fail("elevation_max_deg", "must be greater than elevation_min_deg");
  }
}

// [radar]: waveform, receiver, windows and the tracer's fidelity.
void read_radar(Scenario& s, const Table& root) {
  radar::Waveform& w = s.sensor.processing.waveform;
  const Table rad = root.table("radar");
  rad.refuse_unknown({"waveform",
                      "carrier_hz",
                      "bandwidth_hz",
                      "prf_hz",
                      "pulses",
                      "pulse_width_s",
                      "sample_rate_hz",
                      "swath_start_m",
                      "tx_power_w",
                      "noise_figure_db",
                      "system_losses_db",
                      "max_range_m",
                      "range_window",
                      "doppler_window",
                      "taylor_sidelobe_db",
                      "taylor_nbar",
                      "max_speed_mps",
                      "max_bounces",
                      "terrain",
                      "terrain_ray_spacing_deg",
                      "terrain_cell_azimuth_deg",
                      "terrain_cell_range_bins",
                      "target_ray_spacing_m",
                      "max_rays_per_target",
                      "mask_target_rays",
                      "edges",
                      "edge_turn_deg",
                      "reuse_static_paths",
                      "reuse_max_phase_deg",
                      "reuse_refresh_frames",
                      "reuse_refresh_slices"});
  std::string waveform = radar::waveform_name(w.kind);
  rad.string("waveform", waveform);
  if (!radar::parse_waveform_kind(waveform, w.kind))
    rad.unknown_value("waveform", waveform, "pulsed_lfm, fmcw");
  rad.number("carrier_hz", w.carrier_hz, {1e8, 1e12});
  s.sbr.carrier_hz = w.carrier_hz;
  rad.number("bandwidth_hz", w.bandwidth_hz, {1e3, 1e10});
  rad.number("prf_hz", s.prf_hz, {1.0, 1e8});
  rad.integer("pulses", w.pulses, 1, 65536);
  rad.number("pulse_width_s", w.pulse_width_s, {1e-10, 1.0});
  rad.number("sample_rate_hz", w.sample_rate_hz, {0.0, 1e11});
  rad.number("swath_start_m", s.swath_start_m, {0.0, 1e7});
  rad.number("tx_power_w", s.sensor.tx_power_w, {1e-6, 1e7});
  rad.decibels("noise_figure_db", s.sensor.noise_figure, {0.0, 30.0});
  rad.decibels("system_losses_db", s.sensor.system_losses, {0.0, 60.0});
  rad.number("max_range_m", s.sensor.max_range_m, {1.0, 1e6});
  s.sbr.max_range_m = s.sensor.max_range_m;
  rad.number("max_speed_mps", s.sensor.processing.max_speed_mps, {1.0, 1e4});
  for (auto [key, spec] : {std::pair{"range_window", &s.sensor.processing.range_window},
                           std::pair{"doppler_window", &s.sensor.processing.doppler_window}}) {
    std::string name = radar::window_name(spec->kind);
    rad.string(key, name);
    const auto kind_w = radar::parse_window_kind(name);
    if (!kind_w)
      rad.unknown_value(key, name, "rectangular, hann, hamming, blackman, taylor");
    spec->kind = *kind_w;
    rad.number("taylor_sidelobe_db", spec->taylor_sidelobe_db, {13.3, 120.0});
    rad.integer("taylor_nbar", spec->taylor_nbar, 1, 63);
  }
  if (s.sensor.processing.range_window.kind != radar::WindowKind::kTaylor &&
      s.sensor.processing.doppler_window.kind != radar::WindowKind::kTaylor) {
    for (const char* key : {"taylor_sidelobe_db", "taylor_nbar"}) {
      if (rad.has(key))
        rad.fail(key, "is read with a \"taylor\" range_window or doppler_window only");
    }
  }
  rad.integer("max_bounces", s.sbr.max_bounces, 1, 16);
  std::string terrain = s.terrain_engine ? "engine" : "rays";
  rad.choice("terrain", terrain, {"rays", "engine"});
  s.terrain_engine = terrain == "engine";
  s.sbr.terrain_rays = !s.terrain_engine;
  rad.degrees("terrain_ray_spacing_deg", s.sbr.terrain_ray_spacing_rad, {1e-4, 10.0});
  rad.degrees("terrain_cell_azimuth_deg", s.terrain_cell_azimuth_rad, {1e-3, 10.0});
  rad.integer("terrain_cell_range_bins", s.terrain_cell_range_bins, 1, 1024);
  if (!s.terrain_engine)
    for (const char* key : {"terrain_cell_azimuth_deg", "terrain_cell_range_bins"})
      if (rad.has(key))
        rad.fail(key, "is read with terrain = \"engine\" only (terrain is \"rays\")");
  rad.number("target_ray_spacing_m", s.sbr.target_ray_spacing_m, {1e-4, 100.0});
  rad.integer("max_rays_per_target", s.sbr.max_rays_per_target, 1, 100'000'000);
  rad.boolean("mask_target_rays", s.sbr.mask_target_rays);
  rad.boolean("edges", s.sbr.edges);
  rad.degrees("edge_turn_deg", s.sbr.edge_min_turn_rad, {0.0, 179.0});
  if (!s.sbr.edges && rad.has("edge_turn_deg"))
    rad.fail("edge_turn_deg", "is read with edges = true only");
  rad.boolean("reuse_static_paths", s.sbr.reuse_static_paths);
  rad.degrees("reuse_max_phase_deg", s.sbr.reuse_max_phase_rad, {0.01, 180.0});
  rad.integer("reuse_refresh_frames", s.sbr.reuse_refresh_frames, 1, 100000);
  rad.integer("reuse_refresh_slices", s.sbr.reuse_refresh_slices, 1,
              radar::SbrConfig::kMaxKeptSlices);
  if (!s.sbr.reuse_static_paths)
    for (const char* key : {"reuse_max_phase_deg", "reuse_refresh_frames", "reuse_refresh_slices"})
      if (rad.has(key))
        rad.fail(key, "is read with reuse_static_paths = true only");
}

// [detector]: CFAR and the detection list.
void read_detector(Scenario& s, const Table& root) {
  radar::CfarConfig& cf = s.sensor.cfar;
  const Table det = root.table("detector");
  det.refuse_unknown({"cfar", "cfar_training_cells", "cfar_guard_cells",
                      "cfar_velocity_training_cells", "cfar_velocity_guard_cells", "cfar_pfa",
                      "os_rank", "min_snr_db", "max_detections", "noise_seed", "thermal_noise",
                      "return_floor_db"});
  std::string cfar = cf.kind == radar::CfarKind::kCellAveraging ? "ca" : "os";
  det.choice("cfar", cfar, {"ca", "os"});
  cf.kind = cfar == "ca" ? radar::CfarKind::kCellAveraging : radar::CfarKind::kOrderStatistic;
  if (cf.kind == radar::CfarKind::kCellAveraging && det.has("os_rank"))
    det.fail("os_rank", "is read with cfar = \"os\" only (cfar is \"ca\")");
  det.integer("cfar_training_cells", cf.range_training, 0, 1024);
  det.integer("cfar_guard_cells", cf.range_guard, 0, 1024);
  det.integer("cfar_velocity_training_cells", cf.velocity_training, 0, 1024);
  det.integer("cfar_velocity_guard_cells", cf.velocity_guard, 0, 1024);
  det.number("cfar_pfa", cf.pfa, {1e-15, 0.5});
  det.number("os_rank", cf.os_rank, {0.01, 1.0});
  det.number("min_snr_db", s.sensor.min_snr_db, {-50.0, 200.0});
  det.integer("max_detections", s.sensor.max_detections, 0, 255);
  std::int64_t seed = static_cast<std::int64_t>(s.sensor.noise_seed & 0x7fffffffffffffffull);
  det.integer("noise_seed", seed, 0, std::numeric_limits<std::int64_t>::max());
  s.sensor.noise_seed = static_cast<std::uint64_t>(seed);
  det.boolean("thermal_noise", s.sensor.thermal_noise);
  det.number("return_floor_db", s.sensor.return_floor_db, {-400.0, -30.0});
}

// [input] (CANaerospace identifiers of the ownship fields) and [output].
void read_input_output(Scenario& s, const Table& root) {
  namespace canas = io::canas;
  std::vector<std::string> keys{"node_id"};
  for (std::size_t k = 0; k < canas::kFieldCount; ++k)
    keys.push_back(std::string(canas::field_name(static_cast<canas::Field>(k))) + "_id");
  const std::vector<std::string_view> known(keys.begin(), keys.end());
  const Table in = root.table("input");
  in.refuse_unknown(known);
  std::int64_t node = s.input.node_id ? *s.input.node_id : -1;
  in.integer("node_id", node, -1, 255);
  s.input.node_id = node < 0 ? std::nullopt : std::optional<std::uint8_t>(node);
  for (std::size_t k = 0; k < canas::kFieldCount; ++k) {
    const std::string key = std::string(canas::field_name(static_cast<canas::Field>(k))) + "_id";
    in.integer(key, s.input.fields[k].can_id, 0, 2047);
  }
  try {
    canas::validate(s.input);
  } catch (const std::invalid_argument& e) {
    in.fail("", e.what());
  }
  const Table out = root.table("output");
  out.refuse_unknown({"can_fd", "cube", "cube_frames"});
  out.boolean("can_fd", s.can_fd);
  std::string cube;
  if (out.string("cube", cube)) {
    const std::string ext = std::filesystem::path(cube).extension().string();
    if (ext != ".h5" && ext != ".hdf5")
      out.fail("cube", "\"" + cube + "\" is not an HDF5 file name (.h5 or .hdf5; docs/cube.md)");
    s.cube_file = cube;
    s.cube_source = out.file() + ": [output] ";
  }
  std::string frames;
  if (out.string("cube_frames", frames)) {
    if (s.cube_file.empty())
      out.fail("cube_frames", "needs cube (the HDF5 file the frames go to)");
    const std::string error = parse_cube_frames(frames, s.cube_first_frame, s.cube_last_frame);
    if (!error.empty())
      out.fail("cube_frames", error);
  }
}

// [faults]: the software bus's fault injection.
void read_faults(Scenario& s, const Table& root) {
  const Table faults = root.table("faults");
  faults.refuse_unknown({"malformed_every_n_frames", "seed", "drop_probability", "delay_s",
                         "jitter_s", "corrupt_probability", "corrupt_max_bits",
                         "reorder_probability", "duplicate_probability", "stale_mode",
                         "stale_start_s", "stale_end_s", "babble_rate_hz", "babble_id",
                         "babble_start_s", "babble_end_s"});
  faults.integer("malformed_every_n_frames", s.malformed_every_n_frames, 0, 1'000'000'000);
  sim_bus::FaultConfig& lf = s.link_faults;
  std::int64_t fault_seed = static_cast<std::int64_t>(lf.seed & 0x7fffffffffffffffull);
  faults.integer("seed", fault_seed, 0, std::numeric_limits<std::int64_t>::max());
  lf.seed = static_cast<std::uint64_t>(fault_seed);
  faults.number("drop_probability", lf.drop_probability, {0.0, 1.0});
  faults.number("delay_s", lf.delay_s, {0.0, 10.0});
  faults.number("jitter_s", lf.jitter_s, {0.0, 10.0});
  if (lf.jitter_s > lf.delay_s)
    faults.fail("jitter_s", "must not exceed delay_s (a frame cannot arrive before it is sent)");
  faults.number("corrupt_probability", lf.corrupt_probability, {0.0, 1.0});
  faults.integer("corrupt_max_bits", lf.corrupt_max_bits, 1, sim_bus::kMaxCorruptBits);
  faults.number("reorder_probability", lf.reorder_probability, {0.0, 1.0});
  faults.number("duplicate_probability", lf.duplicate_probability, {0.0, 1.0});
  std::string stale_mode = !s.stale_sender                               ? "none"
                           : s.stale.mode == sim_bus::StaleMode::kSilent ? "silent"
                           : s.stale.mode == sim_bus::StaleMode::kFrozen ? "frozen"
                                                                         : "frozen_value";
  faults.choice("stale_mode", stale_mode, {"none", "silent", "frozen", "frozen_value"});
  s.stale_sender = stale_mode != "none";
  if (s.stale_sender) {
    s.stale.mode = stale_mode == "silent"   ? sim_bus::StaleMode::kSilent
                   : stale_mode == "frozen" ? sim_bus::StaleMode::kFrozen
                                            : sim_bus::StaleMode::kFrozenValue;
  }
  faults.number("stale_start_s", s.stale.start_s, {0.0, 1e9});
  faults.number("stale_end_s", s.stale.end_s, {0.0, 1e9});
  if (s.stale_sender && s.stale.end_s < s.stale.start_s)
    faults.fail("stale_end_s", "must not be before stale_start_s");
  double babble_rate_hz = s.babbling_node ? s.babble.rate_hz : 0.0;
  faults.number("babble_rate_hz", babble_rate_hz, {0.0, 1e6});
  s.babbling_node = babble_rate_hz > 0.0;
  if (s.babbling_node)
    s.babble.rate_hz = babble_rate_hz;
  faults.integer("babble_id", s.babble.id, 0, 0x7FF);
  faults.number("babble_start_s", s.babble.start_s, {0.0, 1e9});
  double babble_end_s = std::isfinite(s.babble.end_s) ? s.babble.end_s : 0.0;
  faults.number("babble_end_s", babble_end_s, {0.0, 1e9});
  if (babble_end_s > 0.0)
    s.babble.end_s = babble_end_s;
}

void apply_toml(Scenario& s, std::string_view text, const std::string& origin) {
  const config::TomlFile toml = config::TomlFile::parse(text, origin);
  const Table root = toml.root();
  root.refuse_unknown({"name", "run", "scene", "ownship", "input", "output", "antenna", "radar",
                       "detector", "faults", "weather", "governor", "target"});
  root.string("name", s.name);

  read_run(s, root);
  read_scene(s, root);
  read_ownship(s, root);
  read_antenna(s, root);
  read_radar(s, root);
  read_detector(s, root);
  read_input_output(s, root);
  read_faults(s, root);
  apply_weather(s, root);
  apply_governor(s, root);
  apply_targets(s, root);
}

}  // namespace

std::string_view default_scenario_toml() noexcept {
  return kDefaultScenario;
}

namespace {

// Azimuth pattern table: CSV rows "angle_deg,gain_db" (one-way gain relative to the peak), '#'
// comments and one optional header line.
void read_pattern_csv(const std::filesystem::path& path, const std::string& origin,
                      radar::PatternCut& cut) {
  std::ifstream in(path);
  if (!in)
    config::fail(origin, "[antenna]", "pattern_file", "cannot open " + path.string());
  std::string line;
  int line_no = 0;
  while (std::getline(in, line)) {
    ++line_no;
    if (line.empty() || line[0] == '#')
      continue;
    std::istringstream row(line);
    double angle = 0.0, gain = 0.0;
    char comma = 0;
    if (!(row >> angle >> comma >> gain) || comma != ',' || !std::isfinite(angle) ||
        !std::isfinite(gain)) {
      if (cut.table_angle_rad.empty() && line_no == 1)
        continue;  // header
      throw std::runtime_error(path.string() + ":" + std::to_string(line_no) +
                               ": expected 'angle_deg,gain_db'");
    }
    cut.table_angle_rad.push_back(common::radians(angle));
    cut.table_gain_db.push_back(gain);
  }
}

// "25.6 ms", "5.12 s": a duration for the timeline's message.
std::string show_duration(double seconds) {
  char buf[32];
  if (seconds < 1.0)
    std::snprintf(buf, sizeof buf, "%.4g ms", seconds * 1e3);
  else
    std::snprintf(buf, sizeof buf, "%.4g s", seconds);
  return buf;
}

// The radar's timeline must fit its frame: every beam position of the scan dwells `pulses` PRIs,
// one scan a frame. A longer one would be computed as if it fitted (each frame simulating more
// radar time than passes), so it is refused with its numbers. Then the sensor's range-Doppler
// workspaces, one per beam, are estimated before any is allocated: per cell the complex image
// (16 B), the clutter and power maps (8 B each) and the CFAR's running sums (8 B).
void check_timeline_and_memory(const Scenario& s, const std::string& origin, std::size_t beams) {
  const radar::Waveform& w = s.sensor.processing.waveform;
  const double timeline_s = static_cast<double>(beams) * static_cast<double>(w.pulses) * w.pri_s;
  const double frame_s = 1.0 / s.rate_hz;
  if (timeline_s > frame_s * (1.0 + 1e-9)) {
    config::fail(origin, "[radar]", "pulses",
                 "the radar timeline, " + std::to_string(beams) + " beam positions x " +
                     std::to_string(w.pulses) + " pulses x " + show_duration(w.pri_s) +
                     " PRI = " + show_duration(timeline_s) +
                     ", is longer than the frame period 1 / [run] rate_hz " + show(s.rate_hz) +
                     " Hz = " + show_duration(frame_s) +
                     ": fewer pulses or beam positions, a higher prf_hz or a lower rate_hz");
  }
  const double cells = static_cast<double>(w.range_bins) * static_cast<double>(w.pulses);
  const double bytes = static_cast<double>(beams) * cells * 40.0;
  std::optional<std::string> over;
  try {
    over = config::over_memory_limit(
        bytes, std::to_string(beams) + " beam positions x " + std::to_string(w.range_bins) +
                   " range bins x " + std::to_string(w.pulses) +
                   " pulses, about 40 B a cell for the range-Doppler maps and the CFAR");
  } catch (const std::invalid_argument& e) {
    throw std::runtime_error(e.what());  // the variable, not the scenario, is wrong
  }
  if (over)
    config::fail(origin, "[radar]", "pulses", "the sensor " + *over);
}

// The sensor's configuration from the scenario's edge units, once both TOML layers are read.
void derive_sensor(Scenario& s, const std::string& origin) {
  radar::SensorConfig& c = s.sensor;
  radar::Waveform& w = c.processing.waveform;
  w.pri_s = 1.0 / s.prf_hz;
  try {
    if (w.kind == radar::WaveformKind::kPulsedLfm) {
      w.swath_start_m = s.swath_start_m >= 0.0 ? s.swath_start_m : radar::blind_range_m(w);
      const double bins =
          std::ceil((c.max_range_m - w.swath_start_m) / radar::range_bin_m(w) - 1e-9);
      if (!(bins >= 2.0))
        throw std::invalid_argument("max_range_m must exceed the swath start by two range bins");
      w.range_bins = static_cast<int>(std::min(bins, 1048576.0));
    } else if (w.sample_rate_hz > 0.0) {
      w.range_bins = static_cast<int>(std::lround(w.pulse_width_s * w.sample_rate_hz));
    } else {
      w.range_bins = static_cast<int>(
          std::min(std::ceil(c.max_range_m / radar::range_resolution_m(w) - 1e-9), 1048576.0));
    }
    radar::validate(w);
    // One beam's range-Doppler map has range_bins x pulses cells, and the sensor's buffers and
    // the CFAR's running sums grow with it: bounded, so that a scenario cannot ask for
    // gigabytes (found by fuzzing: pulses = 65536 over 1502 bins took 0.8 GB to check).
    constexpr double kMaxMapCells = 16777216.0;  // 2^24 (256 MiB of complex samples)
    const double cells = static_cast<double>(w.range_bins) * static_cast<double>(w.pulses);
    if (cells > kMaxMapCells) {
      throw std::invalid_argument(
          "range_bins x pulses = " + std::to_string(w.range_bins) + " x " +
          std::to_string(w.pulses) + " cells per beam exceeds 16777216 (2^24): fewer pulses, " +
          "or fewer range bins (max_range_m - swath_start_m, bandwidth_hz)");
    }
  } catch (const std::invalid_argument& e) {
    config::fail(origin, "[radar]", "", e.what());
  }
  try {
    const radar::Cfar2d probe(c.cfar, static_cast<std::size_t>(w.range_bins),
                              static_cast<std::size_t>(w.pulses));
  } catch (const std::invalid_argument& e) {
    config::fail(origin, "[detector]", "", e.what());
  }
  radar::AntennaConfig& a = c.antenna;
  radar::PatternKind kind{};
  if (!radar::parse_pattern_kind(s.pattern, kind))
    config::fail(origin, "[antenna]", "pattern", "unknown value \"" + s.pattern + "\"");
  a.azimuth = {};
  a.azimuth.kind = kind;
  a.azimuth.beamwidth_rad =
      s.azimuth_beamwidth_rad > 0.0 ? s.azimuth_beamwidth_rad : s.beam_spacing_rad;
  if (kind == radar::PatternKind::kTable)
    read_pattern_csv(s.pattern_file, origin, a.azimuth);
  a.elevation = {};
  a.elevation.kind = kind == radar::PatternKind::kTable ? radar::PatternKind::kGaussian : kind;
  a.elevation.beamwidth_rad = s.elevation_beamwidth_rad > 0.0
                                  ? s.elevation_beamwidth_rad
                                  : s.sbr.elevation_max_rad - s.sbr.elevation_min_rad;
  const double field = s.sbr.azimuth_max_rad - s.sbr.azimuth_min_rad;
  const auto beams =
      static_cast<std::size_t>(std::max(1.0, std::round(field / s.beam_spacing_rad)));
  const double spacing = field / static_cast<double>(beams);
  a.beam_azimuth_rad.clear();
  for (std::size_t i = 0; i < beams; ++i)
    a.beam_azimuth_rad.push_back(s.sbr.azimuth_min_rad + (static_cast<double>(i) + 0.5) * spacing);
  a.beam_elevation_rad = 0.5 * (s.sbr.elevation_min_rad + s.sbr.elevation_max_rad);
  try {
    if (s.antenna_gain > 0.0) {
      a.peak_gain = s.antenna_gain;
    } else {
      // Gain of the sum beam from its own 3-dB widths (Kraus), times the aperture efficiency.
      radar::AntennaConfig probe = a;
      probe.peak_gain = 1.0;
      const radar::Antenna ant(probe);
      a.peak_gain = radar::gain_from_beamwidths(ant.sum_beamwidth_az_rad(),
                                                ant.sum_beamwidth_el_rad(), s.aperture_efficiency);
    }
    const radar::Antenna check(a);
  } catch (const std::invalid_argument& e) {
    config::fail(origin, "[antenna]", "", e.what());
  }
  check_timeline_and_memory(s, origin, beams);
}

Scenario parse_impl(std::string_view toml_text, const std::string& origin,
                    const std::filesystem::path& base_dir) {
  Scenario s;
  apply_toml(s, kDefaultScenario, "<default scenario>");
  if (origin != "<default scenario>")
    apply_toml(s, toml_text, origin);
  if (!s.scene_file.empty() && s.scene_file.is_relative() && !base_dir.empty())
    s.scene_file = base_dir / s.scene_file;  // relative to the scenario file
  if (s.scene_import && !base_dir.empty()) {
    GeodataSource& g = *s.scene_import;
    for (std::filesystem::path* p : {&g.dem, &g.surround_dem, &g.landcover, &g.classes, &g.osm})
      if (!p->empty() && p->is_relative())
        *p = base_dir / *p;  // relative to the scenario file
  }
  if (!s.pattern_file.empty() && s.pattern_file.is_relative() && !base_dir.empty())
    s.pattern_file = base_dir / s.pattern_file;
  if (!s.cube_file.empty() && s.cube_file.is_relative() && !base_dir.empty())
    s.cube_file = base_dir / s.cube_file;  // relative to the scenario file
  for (scene::TargetPlacement& t : s.targets) {
    if (t.mesh_file.empty())
      continue;
    if (t.mesh_file.is_relative() && !base_dir.empty())
      t.mesh_file = base_dir / t.mesh_file;  // relative to the scenario file
    std::error_code ec;
    if (!std::filesystem::is_regular_file(t.mesh_file, ec))
      throw config::ConfigError(t.context + " mesh_file: cannot open " + t.mesh_file.string());
  }
  derive_sensor(s, origin);
  return s;
}

}  // namespace

Scenario parse_scenario(std::string_view toml_text, const std::string& origin) {
  return parse_impl(toml_text, origin, {});
}

Scenario load_scenario(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in)
    throw std::runtime_error(path.string() + ": cannot open scenario file");
  std::ostringstream text;
  text << in.rdbuf();
  return parse_impl(text.str(), path.string(), path.parent_path());
}

radar::TerrainReturnsConfig terrain_returns_config(const Scenario& s) {
  radar::TerrainReturnsConfig c;
  c.azimuth_min_rad = s.sbr.azimuth_min_rad;
  c.azimuth_max_rad = s.sbr.azimuth_max_rad;
  c.elevation_min_rad = s.sbr.elevation_min_rad;
  c.elevation_max_rad = s.sbr.elevation_max_rad;
  c.azimuth_cell_rad = s.terrain_cell_azimuth_rad;
  const radar::Waveform& w = s.sensor.processing.waveform;
  c.range_cell_m = radar::range_bin_m(w) * static_cast<double>(s.terrain_cell_range_bins);
  c.range_min_m = std::max(0.0, radar::first_range_m(w) - 0.5 * radar::range_bin_m(w));
  c.range_max_m = std::max(s.sensor.max_range_m, c.range_min_m + c.range_cell_m);
  c.carrier_hz = s.sbr.carrier_hz;
  return c;
}

radar::RadarPose scripted_pose(const Scenario& s, double t_s) noexcept {
  radar::RadarPose pose;
  pose.position_m = s.ownship_start_enu_m + t_s * s.ownship_velocity_enu_mps;
  pose.velocity_mps = s.ownship_velocity_enu_mps;
  pose.world_from_antenna =
      enu_from_body(s.ownship_heading_rad, s.ownship_pitch_rad, s.ownship_roll_rad) *
      body_from_antenna(s.antenna_depression_rad);
  return pose;
}

}  // namespace radar_emu::loop
