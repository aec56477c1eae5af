// Scenario parsing: the embedded default is complete and consistent, a user file overrides only
// what it names, and every kind of bad input fails with a message that says where and why.

#include "loop/scenario.hpp"

#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <numbers>
#include <sstream>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "common/units.hpp"
#include "loop/closed_loop.hpp"
#include "tools/sar_case.hpp"

namespace loop = radar_emu::loop;

namespace {
std::string error_of(const std::string& text) {
  try {
    (void)loop::parse_scenario(text, "test.toml");
  } catch (const std::runtime_error& e) {
    return e.what();
  }
  return "";
}
namespace common = radar_emu::common;
}  // namespace

TEST(Scenario, DefaultValuesAreTheDocumentedOnes) {
  const loop::Scenario s =
      loop::parse_scenario(loop::default_scenario_toml(), "<default scenario>");
  EXPECT_EQ(s.frames, 200u);
  EXPECT_DOUBLE_EQ(s.rate_hz, 20.0);
  EXPECT_DOUBLE_EQ(s.sensor.processing.waveform.carrier_hz, 94e9);
  EXPECT_DOUBLE_EQ(s.sbr.carrier_hz, s.sensor.processing.waveform.carrier_hz);
  // Terrain clutter from the terrain engine ([radar] terrain = "engine"), the tracer's terrain
  // rays off.
  EXPECT_TRUE(s.terrain_engine);
  EXPECT_FALSE(s.sbr.terrain_rays);
  // Edge diffraction on in the loop, wedges turning by more than 30 deg; no corner reflectors.
  EXPECT_TRUE(s.sbr.edges);
  EXPECT_NEAR(s.sbr.edge_min_turn_rad, common::radians(30.0), 1e-12);
  EXPECT_FALSE(s.scene_corner_reflectors);
  EXPECT_NEAR(s.sensor.noise_figure, std::pow(10.0, 0.5), 1e-12);  // 5 dB
  EXPECT_NEAR(s.antenna_depression_rad, common::radians(5.0), 1e-15);
  // 16 beams of 1 deg across -8..8 deg; PRI from the PRF; the range gate from 1500 m.
  ASSERT_EQ(s.sensor.antenna.beam_azimuth_rad.size(), 16u);
  EXPECT_NEAR(s.sensor.antenna.beam_azimuth_rad.front(), common::radians(-7.5), 1e-12);
  EXPECT_NEAR(s.sensor.processing.waveform.pri_s, 50e-6, 1e-15);
  EXPECT_NEAR(s.sensor.processing.waveform.swath_start_m, 1500.0, 1e-9);
  EXPECT_EQ(s.sensor.processing.waveform.range_bins, 1502);  // ceil(4500 / 2.9979) = ceil(1501.04)
  EXPECT_DOUBLE_EQ(s.ownship_start_enu_m.y, -4000.0);
  EXPECT_EQ(s.scene_builtin, "airport");  // issue 7: the closed loop flies over the airport
  EXPECT_EQ(s.scene_seed, 1u);
  EXPECT_TRUE(s.scene_file.empty());
  // Issue 6: CANaerospace v1.7 appendix A identifiers, any node, classic lists, no faults.
  EXPECT_EQ(s.input[radar_emu::io::canas::Field::kLatitude].can_id, 1036);
  EXPECT_EQ(s.input[radar_emu::io::canas::Field::kTrueHeading].can_id, 1133);
  EXPECT_FALSE(s.input.node_id.has_value());
  EXPECT_FALSE(s.can_fd);
  EXPECT_FALSE(s.stale_output_silent);
  EXPECT_TRUE(radar_emu::sim_bus::no_faults(s.link_faults));
  EXPECT_FALSE(s.stale_sender);
  EXPECT_FALSE(s.babbling_node);
}

TEST(Scenario, BusInputOutputAndFaultKeys) {
  const loop::Scenario s = loop::parse_scenario(
      "[run]\nstale_output = \"silent\"\n[input]\nnode_id = 7\nlatitude_id = 1049\n"
      "[output]\ncan_fd = true\n[faults]\ndrop_probability = 0.1\ndelay_s = 0.02\n"
      "jitter_s = 0.01\nstale_mode = \"frozen\"\nstale_start_s = 2\nstale_end_s = 3\n"
      "babble_rate_hz = 500\nbabble_id = 5\n[scene]\nbuiltin = \"terrain\"\nseed = 9\n",
      "bus.toml");
  EXPECT_TRUE(s.stale_output_silent);
  EXPECT_EQ(s.input.node_id, std::optional<std::uint8_t>(7));
  EXPECT_EQ(s.input[radar_emu::io::canas::Field::kLatitude].can_id, 1049);
  EXPECT_TRUE(s.can_fd);
  EXPECT_DOUBLE_EQ(s.link_faults.drop_probability, 0.1);
  EXPECT_DOUBLE_EQ(s.link_faults.jitter_s, 0.01);
  EXPECT_TRUE(s.stale_sender);
  EXPECT_EQ(s.stale.mode, radar_emu::sim_bus::StaleMode::kFrozen);
  EXPECT_DOUBLE_EQ(s.stale.end_s, 3.0);
  EXPECT_TRUE(s.babbling_node);
  EXPECT_EQ(s.babble.id, 5u);
  EXPECT_EQ(s.scene_builtin, "terrain");
  EXPECT_EQ(s.scene_seed, 9u);
  // Errors name the table, the key and what was expected.
  EXPECT_NE(error_of("[input]\nlatitude_id = 311\n").find("[input]"), std::string::npos);
  EXPECT_NE(error_of("[input]\nnode_id = 300\n").find("[input] node_id"), std::string::npos);
  EXPECT_NE(error_of("[faults]\ndelay_s = 0.01\njitter_s = 0.02\n").find("[faults] jitter_s"),
            std::string::npos);
  EXPECT_NE(error_of("[faults]\nstale_mode = \"sleepy\"\n").find("[faults] stale_mode"),
            std::string::npos);
  EXPECT_NE(error_of("[run]\nstale_output = \"mute\"\n").find("[run] stale_output"),
            std::string::npos);
  EXPECT_NE(error_of("[scene]\nbuiltin = \"moon\"\n").find("known: airport, default, terrain"),
            std::string::npos);
}

TEST(Scenario, AntennaPolarisationKey) {
  // Default VV (the tracer's behaviour before the key existed); receive first as in the RCS
  // tool: "HV" = receive H, transmit V.
  EXPECT_EQ(loop::parse_scenario(loop::default_scenario_toml(), "<default>").sbr.polarisation,
            radar_emu::radar::Polarisation::kVV);
  EXPECT_EQ(loop::parse_scenario("[antenna]\npolarisation = \"HH\"\n", "p.toml").sbr.polarisation,
            radar_emu::radar::Polarisation::kHH);
  EXPECT_EQ(loop::parse_scenario("[antenna]\npolarisation = \"HV\"\n", "p.toml").sbr.polarisation,
            radar_emu::radar::Polarisation::kHV);
  EXPECT_EQ(loop::parse_scenario("[antenna]\npolarisation = \"VH\"\n", "p.toml").sbr.polarisation,
            radar_emu::radar::Polarisation::kVH);
  EXPECT_NE(error_of("[antenna]\npolarisation = \"RHC\"\n").find("[antenna] polarisation"),
            std::string::npos);
  // Either case, as --pol (common/polarisation.hpp), and its refusal.
  EXPECT_EQ(loop::parse_scenario("[antenna]\npolarisation = \"vh\"\n", "p.toml").sbr.polarisation,
            radar_emu::radar::Polarisation::kVH);
  EXPECT_NE(error_of("[antenna]\npolarisation = \"RHC\"\n")
                .find("polarisation: 'RHC' is not one of HH, HV, VH, VV"),
            std::string::npos);
}

TEST(Scenario, UserFileOverridesOnlyWhatItNames) {
  const loop::Scenario s =
      loop::parse_scenario("[run]\nframes = 7\n[radar]\ncarrier_hz = 35.0e9\n", "user.toml");
  EXPECT_EQ(s.frames, 7u);
  EXPECT_DOUBLE_EQ(s.sensor.processing.waveform.carrier_hz, 35e9);
  EXPECT_DOUBLE_EQ(s.sbr.carrier_hz, 35e9);
  EXPECT_DOUBLE_EQ(s.rate_hz, 20.0);  // from the default
}

TEST(Scenario, BadInputFailsWithLocationAndReason) {
  EXPECT_NE(error_of("[run]\nframez = 3\n").find("test.toml: [run] framez: unknown key"),
            std::string::npos);
  EXPECT_EQ(error_of("[rn]\n").rfind("test.toml: rn: unknown table (known: name, run, ", 0), 0u);
  EXPECT_EQ(error_of("[run]\nframes = \"many\"\n"),
            "test.toml: [run] frames: expected an integer, got a string");
  EXPECT_EQ(error_of("[run]\nframes = 0\n"),
            "test.toml: [run] frames: 0 is outside [1, 100000000]");
  EXPECT_NE(error_of("[run]\nrate_hz = nan\n").find("rate_hz"), std::string::npos);
  EXPECT_EQ(error_of("[ownship]\nstart_enu_m = [1.0, 2.0]\n"),
            "test.toml: [ownship] start_enu_m: expected an array of 3 numbers, got an array of 2");
  EXPECT_NE(
      error_of("[antenna]\nazimuth_min_deg = 10.0\nazimuth_max_deg = 5.0\n").find("greater than"),
      std::string::npos);
  EXPECT_EQ(
      error_of("[scene]\nbuiltin = \"moon\"\n"),
      "test.toml: [scene] builtin: unknown value \"moon\" (known: airport, default, terrain)");
  EXPECT_NE(error_of("[scene]\nbuiltin = \"default\"\ncorner_reflectors = true\n")
                .find("[scene] corner_reflectors: applies to builtin = \"airport\" only"),
            std::string::npos);
  EXPECT_NE(error_of("[radar]\nedges = false\nedge_turn_deg = 20.0\n")
                .find("[radar] edge_turn_deg: is read with edges = true only"),
            std::string::npos);
  EXPECT_NE(error_of("[radar]\nreuse_static_paths = false\nreuse_refresh_frames = 8\n")
                .find("[radar] reuse_refresh_frames: is read with reuse_static_paths = true only"),
            std::string::npos);
  EXPECT_NE(error_of("[radar]\nreuse_refresh_frames = 0\n").find("[radar] reuse_refresh_frames"),
            std::string::npos);
  EXPECT_EQ(error_of("[radar]\nreuse_max_phase_deg = 10.0\n"), "");  // reuse is the default
  EXPECT_NE(error_of("[radar]\nreuse_refresh_slices = 9\n").find("[radar] reuse_refresh_slices"),
            std::string::npos);
  EXPECT_EQ(error_of("[radar]\nreuse_refresh_slices = 1\n"), "");
  EXPECT_EQ(error_of("[radar]\nterrain = \"dem\"\n"),
            "test.toml: [radar] terrain: unknown value \"dem\" (known: rays, engine)");
  EXPECT_NE(error_of("[radar]\nterrain = \"rays\"\nterrain_cell_range_bins = 4\n")
                .find("[radar] terrain_cell_range_bins: is read with terrain = \"engine\" only"),
            std::string::npos);
  EXPECT_EQ(error_of("[radar]\nterrain = \"engine\"\nterrain_cell_azimuth_deg = 0.5\n"), "");
  EXPECT_EQ(error_of("[radar]\nterrain_cell_range_bins = 4\n"), "");  // the default engine
  EXPECT_EQ(error_of("[radar]\nwaveform = \"cw\"\n"),
            "test.toml: [radar] waveform: unknown value \"cw\" (known: pulsed_lfm, fmcw)");
  EXPECT_EQ(error_of("[radar]\nrange_window = \"kaiser\"\n"),
            "test.toml: [radar] range_window: unknown value \"kaiser\" (known: rectangular, hann, "
            "hamming, blackman, taylor)");
  EXPECT_NE(error_of("[antenna]\npattern = \"table\"\n").find("pattern_file"), std::string::npos);
  EXPECT_NE(error_of("[radar]\npulse_width_s = 60e-6\n").find("[radar]"), std::string::npos);
  // Syntax errors carry line and column.
  EXPECT_EQ(error_of("[run]\nframes = = 3\n").rfind("test.toml:2:10: ", 0), 0u);
  // Found by fuzzing (tests/fuzz/regressions/scenario_toml/): a range-Doppler map of 1502 x
  // 65536 cells took 0.8 GB and seconds to check; above 2^24 cells it is a clear error.
  EXPECT_NE(error_of("[radar]\npulses = 65536\n")
                .find("test.toml: [radar] range_bins x pulses = 1502 x 65536 cells per beam "
                      "exceeds 16777216"),
            std::string::npos);
  // 12.3 M cells: allowed (in a frame long enough for the 6.55 s timeline, under a limit that
  // admits its 7.9 GB whatever the machine's memory).
  ASSERT_EQ(setenv("RADAR_EMU_MAX_MEMORY_MIB", "1000000", 1), 0);
  EXPECT_EQ(error_of("[run]\nrate_hz = 0.1\n[radar]\npulses = 8192\n"), "");
  ASSERT_EQ(unsetenv("RADAR_EMU_MAX_MEMORY_MIB"), 0);
}

// Issue 32: the radar's timeline, beam positions x pulses x PRI, must fit the frame period.
// The default scan: 16 beam positions at 20 kHz (PRI 50 us) in 50 ms frames (20 Hz), so 62
// pulses (49.6 ms) fit and 63 (50.4 ms) do not; 5 s per 50 ms frame (6250 pulses) was accepted.
TEST(Scenario, RadarTimelineLongerThanTheFrameIsRefusedWithItsNumbers) {
  EXPECT_EQ(error_of("[radar]\npulses = 62\n"), "");
  EXPECT_EQ(
      error_of("[radar]\npulses = 63\n"),
      "test.toml: [radar] pulses: the radar timeline, 16 beam positions x 63 pulses x 0.05 ms "
      "PRI = 50.4 ms, is longer than the frame period 1 / [run] rate_hz 20 Hz = 50 ms: fewer "
      "pulses or beam positions, a higher prf_hz or a lower rate_hz");
  EXPECT_EQ(error_of("[run]\nrate_hz = 19.0\n[radar]\npulses = 63\n"), "");  // 52.6 ms frames
  EXPECT_NE(error_of("[radar]\npulses = 6250\n").find("= 5 s, is longer than the frame period"),
            std::string::npos);
}

// Issue 32: the sensor's workspaces (one range-Doppler map a beam position, 40 B a cell) are
// estimated before they are allocated and refused past the limit: 16 x 1502 x 512 cells x 40 B
// = 492 175 360 B over 100 MiB = 104 857 600 B.
TEST(Scenario, SensorMemoryPastTheLimitIsRefusedWithItsEstimate) {
  ASSERT_EQ(setenv("RADAR_EMU_MAX_MEMORY_MIB", "100", 1), 0);
  const std::string cube = "[run]\nrate_hz = 2.0\n[radar]\npulses = 512\n";
  EXPECT_EQ(error_of(cube),
            "test.toml: [radar] pulses: the sensor needs about 492 MB of memory (16 beam positions "
            "x 1502 range bins x 512 pulses, about 40 B a cell for the range-Doppler maps and the "
            "CFAR), over the limit of 105 MB (RADAR_EMU_MAX_MEMORY_MIB=100; set it higher to allow "
            "more)");
  ASSERT_EQ(setenv("RADAR_EMU_MAX_MEMORY_MIB", "470", 1), 0);  // 492.8 MB: just over
  EXPECT_EQ(error_of(cube), "");
  ASSERT_EQ(setenv("RADAR_EMU_MAX_MEMORY_MIB", "-5", 1), 0);
  EXPECT_EQ(error_of(cube), "RADAR_EMU_MAX_MEMORY_MIB: '-5' is not a number of MiB > 0");
  ASSERT_EQ(unsetenv("RADAR_EMU_MAX_MEMORY_MIB"), 0);
}

TEST(Scenario, MissingFileNamesThePath) {
  try {
    (void)loop::load_scenario("/nonexistent/dir/s.toml");
    FAIL() << "no error";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("/nonexistent/dir/s.toml"), std::string::npos);
  }
}

// Data cubes out (docs/cube.md): [output] cube and cube_frames, the path relative to the
// scenario file, and the CLI's / Python's options replacing each key (loop::choose_cube).
TEST(Scenario, CubeKeysAndTheCallersOptionsReplacingThem) {
  const auto dir = std::filesystem::temp_directory_path() / "radar_emu_cube_key_test";
  std::filesystem::create_directories(dir);
  {
    std::ofstream toml(dir / "s.toml");
    toml << "[output]\ncube = \"out/c.h5\"\ncube_frames = \"2:4\"\n";
  }
  const loop::Scenario s = loop::load_scenario(dir / "s.toml");
  EXPECT_EQ(s.cube_file, dir / "out/c.h5");  // beside the scenario, as its other paths
  EXPECT_EQ(s.cube_first_frame, 2u);
  EXPECT_EQ(s.cube_last_frame, 4u);
  loop::RunOptions o;
  loop::choose_cube(s, "", "", o);  // nothing on the command line: the scenario's
  EXPECT_EQ(o.cube_file, dir / "out/c.h5");
  EXPECT_EQ(o.cube_first_frame, 2u);
  EXPECT_EQ(o.cube_last_frame, 4u);
  EXPECT_NE(o.cube_file_source.find("s.toml: [output] cube"), std::string::npos);
  loop::choose_cube(s, "cli.h5", "", o);  // --cube wins, the scenario's range stays
  EXPECT_EQ(o.cube_file, "cli.h5");
  EXPECT_EQ(o.cube_file_source, "--cube");
  EXPECT_EQ(o.cube_last_frame, 4u);
  loop::choose_cube(s, "", "0:1", o);  // --cube-frames wins, the scenario's file stays
  EXPECT_EQ(o.cube_file, dir / "out/c.h5");
  EXPECT_EQ(o.cube_first_frame, 0u);
  EXPECT_EQ(o.cube_last_frame, 1u);
  EXPECT_EQ(o.cube_frames_source, "--cube-frames");
  // No cube anywhere: none, and a range alone is refused.
  const loop::Scenario plain = loop::parse_scenario("", "p.toml");
  EXPECT_TRUE(plain.cube_file.empty());
  loop::RunOptions none;
  loop::choose_cube(plain, "", "", none);
  EXPECT_TRUE(none.cube_file.empty());
  EXPECT_THROW(loop::choose_cube(plain, "", "0:3", none), std::runtime_error);
  EXPECT_THROW(loop::choose_cube(plain, "x.txt", "", none), std::runtime_error);
  EXPECT_THROW(loop::choose_cube(plain, "x.h5", "3", none), std::runtime_error);
  // Bad keys: one line naming the table and the key.
  EXPECT_NE(
      error_of("[output]\ncube = \"c.txt\"\n").find("[output] cube: \"c.txt\" is not an HDF5"),
      std::string::npos);
  EXPECT_NE(error_of("[output]\ncube = 3\n").find("[output] cube"), std::string::npos);
  EXPECT_NE(error_of("[output]\ncube_frames = \"0:3\"\n").find("[output] cube_frames: needs cube"),
            std::string::npos);
  EXPECT_NE(error_of("[output]\ncube = \"c.h5\"\ncube_frames = \"4:2\"\n")
                .find("[output] cube_frames: '4:2': LAST is before FIRST"),
            std::string::npos);
  EXPECT_NE(error_of("[output]\ncube = \"c.h5\"\ncube_frames = \"a:b\"\n")
                .find("[output] cube_frames: 'a:b' is not FIRST:LAST"),
            std::string::npos);
  EXPECT_NE(error_of("[output]\ncubes = \"c.h5\"\n").find("[output] cubes: unknown key"),
            std::string::npos);
  std::filesystem::remove_all(dir);
}

TEST(Scenario, TabulatedAntennaPatternFromCsvBesideTheScenario) {
  const auto dir = std::filesystem::temp_directory_path() / "radar_emu_pattern_test";
  std::filesystem::create_directories(dir);
  {
    std::ofstream csv(dir / "az.csv");
    csv << "angle_deg,gain_db\n# a 2 deg beam: -3 dB at +-1 deg\n-5,-30\n-1,-3\n0,0\n1,-3\n5,-30\n";
    std::ofstream toml(dir / "s.toml");
    toml << "[antenna]\npattern = \"table\"\npattern_file = \"az.csv\"\nmonopulse = false\n";
  }
  const loop::Scenario s = loop::load_scenario(dir / "s.toml");
  ASSERT_EQ(s.sensor.antenna.azimuth.table_angle_rad.size(), 5u);
  EXPECT_NEAR(s.sensor.antenna.azimuth.table_angle_rad[1], -common::kRadPerDeg, 1e-15);
  EXPECT_DOUBLE_EQ(s.sensor.antenna.azimuth.table_gain_db[1], -3.0);
  {
    std::ofstream csv(dir / "az.csv");
    csv << "angle_deg,gain_db\n-5,-30\n-1;-3\n";
  }
  try {
    (void)loop::load_scenario(dir / "s.toml");
    FAIL() << "accepted a malformed row";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("az.csv:3"), std::string::npos) << e.what();
  }
  std::filesystem::remove_all(dir);
}

TEST(Scenario, TheSeedsEnhancedVisionRadarExampleLoads) {
  // examples/ev_radar_94ghz.toml: the seed's 30 x 10 deg field of 0.15 x 10 deg beams.
  const char* root = std::getenv("RADAR_EMU_SOURCE_DIR");
  if (root == nullptr)
    GTEST_SKIP() << "RADAR_EMU_SOURCE_DIR is not set (ctest sets it)";
  const loop::Scenario s =
      loop::load_scenario(std::filesystem::path(root) / "examples" / "ev_radar_94ghz.toml");
  ASSERT_EQ(s.sensor.antenna.beam_azimuth_rad.size(), 200u);
  EXPECT_NEAR(s.sensor.antenna.beam_azimuth_rad.front(), common::radians(-15.0 + 0.075), 1e-12);
  EXPECT_NEAR(s.sensor.antenna.azimuth.beamwidth_rad, common::radians(0.15), 1e-15);
  EXPECT_NEAR(s.sensor.antenna.elevation.beamwidth_rad, common::radians(10.0), 1e-15);
  EXPECT_FALSE(s.sensor.antenna.monopulse);
  // The scan fits the frame: 200 beams x 8 pulses x 50 us = 80 ms of radar time at 10 Hz.
  EXPECT_LE(200.0 * s.sensor.processing.waveform.pulses * s.sensor.processing.waveform.pri_s,
            1.0 / s.rate_hz);
}

TEST(Scenario, WeatherTableDefaultsAndRangeChecks) {
  // No [weather] table: free space. A table: gases always, precipitation by condition, with the
  // documented typical amounts when not given.
  const loop::Scenario none = loop::parse_scenario(loop::default_scenario_toml(), "<default>");
  EXPECT_FALSE(none.weather.enabled);
  const loop::Scenario clear = loop::parse_scenario("[weather]\n", "test.toml");
  EXPECT_TRUE(clear.weather.enabled);
  EXPECT_EQ(clear.weather.condition, "clear");
  EXPECT_EQ(clear.weather.rain_mm_per_h, 0.0);
  EXPECT_EQ(clear.weather.fog_water_gm3, 0.0);
  EXPECT_DOUBLE_EQ(clear.weather.humidity_gm3, 7.5);
  EXPECT_DOUBLE_EQ(clear.weather.temperature_k, 288.15);
  EXPECT_DOUBLE_EQ(clear.weather.pressure_hpa, 1013.25);
  const loop::Scenario fog = loop::parse_scenario("[weather]\ncondition = \"fog\"\n", "test.toml");
  EXPECT_DOUBLE_EQ(fog.weather.fog_water_gm3, 0.05);
  const loop::Scenario both = loop::parse_scenario(
      "[weather]\ncondition = \"rain_fog\"\nrain_rate_mmph = 12.5\ntemperature_c = -5\n",
      "test.toml");
  EXPECT_DOUBLE_EQ(both.weather.rain_mm_per_h, 12.5);
  EXPECT_DOUBLE_EQ(both.weather.fog_water_gm3, 0.05);
  EXPECT_NEAR(both.weather.temperature_k, 268.15, 1e-12);
  EXPECT_NE(error_of("[weather]\ncondition = \"snow\"\n")
                .find("test.toml: [weather] condition: unknown value \"snow\" (known: clear, "
                      "rain, fog, rain_fog)"),
            std::string::npos);
  EXPECT_NE(
      error_of("[weather]\nrain_rate_mmph = 5.0\n").find("[weather] rain_rate_mmph: must be 0"),
      std::string::npos);
  EXPECT_NE(error_of("[weather]\ncondition = \"rain\"\nrain_rate_mmph = 0\n")
                .find("rain_rate_mmph: must be > 0"),
            std::string::npos);
  EXPECT_NE(error_of("[weather]\ncondition = \"fog\"\nfog_water_gpm3 = 9\n")
                .find("[weather] fog_water_gpm3"),
            std::string::npos);
  EXPECT_NE(error_of("[weather]\nhumidity_gpm3 = -1\n").find("[weather] humidity_gpm3"),
            std::string::npos);
  EXPECT_NE(error_of("[weather]\npressure_hpa = 5000\n").find("[weather] pressure_hpa"),
            std::string::npos);
  EXPECT_NE(error_of("[weather]\ntemperature_c = 80\n").find("[weather] temperature_c"),
            std::string::npos);
  EXPECT_NE(error_of("[weather]\nvisibility_m = 50\n").find("unknown key"), std::string::npos);
}

TEST(Scenario, TheFogApproachExampleLoads) {
  const char* root = std::getenv("RADAR_EMU_SOURCE_DIR");
  if (root == nullptr)
    GTEST_SKIP() << "RADAR_EMU_SOURCE_DIR is not set (ctest sets it)";
  const loop::Scenario s =
      loop::load_scenario(std::filesystem::path(root) / "examples" / "fog_approach.toml");
  EXPECT_TRUE(s.weather.enabled);
  EXPECT_EQ(s.weather.condition, "fog");
  EXPECT_DOUBLE_EQ(s.weather.fog_water_gm3, 0.5);
}

// [[target]] tables (docs/scene_format.md): what each key becomes, and one error per way to get
// a table wrong, each naming the file, the table's number (from 1) and the key.
TEST(ScenarioTargets, TablesBecomePlacementsInSiUnits) {
  namespace sc = radar_emu::scene;
  EXPECT_TRUE(loop::parse_scenario(loop::default_scenario_toml(), "<default scenario>")
                  .targets.empty());  // the default's example is commented out
  {
    // The default's commented-out example, uncommented, is a valid table.
    const std::string text(loop::default_scenario_toml());
    const std::size_t at = text.find("# [[target]]");
    ASSERT_NE(at, std::string::npos);
    std::istringstream lines(text.substr(at));
    std::string uncommented, line;
    while (std::getline(lines, line))
      uncommented += line.substr(std::min<std::size_t>(2, line.size())) + "\n";
    const loop::Scenario ex = loop::parse_scenario(uncommented, "example.toml");
    ASSERT_EQ(ex.targets.size(), 1u);
    EXPECT_EQ(ex.targets[0].name, "fuel_truck");
    EXPECT_EQ(ex.targets[0].speed_mps, 5.0);
    EXPECT_NEAR(ex.targets[0].course_rad, 1.5 * std::numbers::pi, 1e-15);
    const auto d = loop::scene_description(ex);  // the airport, plus the truck on its ground
    EXPECT_EQ(d.objects.back().name, "fuel_truck");
  }
  const loop::Scenario s = loop::parse_scenario(R"(
[scene]
builtin = "terrain"

[[target]]
builtin = "truck"
position_enu_m = [100.0, -200.0, 0.0]
heading_deg = 90.0
on_ground = true

[[target]]
name = "corner"
builtin = "trihedral-square"
size_m = 0.5
material = "steel"
facet_m = 0.05
position_enu_m = [1, 2, 3]

[[target]]
name = "crab"
builtin = "box"
size_m = [4, 2, 1.5]
position_enu_m = [0, 0, 0]
speed_mps = 5
course_deg = 0
heading_deg = 270

[[target]]
name = "patrol"
builtin = "helicopter"
waypoints_enu_m = [[0, 0, 50], [500, 0, 50], [500, 500, 60]]
speed_mps = 30
turn_radius_m = 100
closed = true
bank = true

[[target]]
name = "east"
builtin = "jeep"
position_enu_m = [0, 0, 0]
speed_mps = 12
heading_deg = 90
)",
                                                "t.toml");
  ASSERT_EQ(s.targets.size(), 5u);
  const sc::TargetPlacement& a = s.targets[0];
  EXPECT_EQ(a.name, "target_1");  // the default name counts tables from 1
  EXPECT_EQ(a.context, "t.toml: [[target]] #1");
  ASSERT_TRUE(a.builtin.has_value());
  EXPECT_EQ(a.builtin->kind, sc::TargetKind::kTruck);
  // The documented default size of a truck (scene/targets.hpp's example).
  EXPECT_EQ(a.builtin->a_m, 8.0);
  EXPECT_EQ(a.builtin->b_m, 2.5);
  EXPECT_EQ(a.builtin->c_m, 3.4);
  EXPECT_EQ(a.position_m, glm::dvec3(100, -200, 0));
  EXPECT_NEAR(a.heading_rad, std::numbers::pi / 2, 1e-15);
  EXPECT_TRUE(a.on_ground);
  EXPECT_EQ(a.speed_mps, 0.0);
  EXPECT_TRUE(a.material.empty());  // metal
  const sc::TargetPlacement& b = s.targets[1];
  EXPECT_EQ(b.name, "corner");
  EXPECT_EQ(b.builtin->kind, sc::TargetKind::kTrihedralSquare);
  EXPECT_EQ(b.builtin->a_m, 0.5);
  EXPECT_EQ(b.facet_m, 0.05);
  EXPECT_EQ(b.material, "steel");
  EXPECT_FALSE(b.on_ground);
  const sc::TargetPlacement& c = s.targets[2];
  EXPECT_EQ(c.builtin->c_m, 1.5);
  EXPECT_EQ(c.speed_mps, 5.0);
  EXPECT_EQ(c.course_rad, 0.0);
  EXPECT_NEAR(c.heading_rad, common::radians(270.0), 1e-15);
  const sc::TargetPlacement& d = s.targets[3];
  ASSERT_EQ(d.waypoints_m.size(), 3u);
  EXPECT_EQ(d.waypoints_m[2], glm::dvec3(500, 500, 60));
  EXPECT_EQ(d.speed_mps, 30.0);
  EXPECT_EQ(d.turn_radius_m, 100.0);
  EXPECT_TRUE(d.closed);
  EXPECT_TRUE(d.bank);
  // A straight-line mover with a heading only faces its velocity: course = heading.
  const sc::TargetPlacement& e = s.targets[4];
  EXPECT_NEAR(e.heading_rad, std::numbers::pi / 2, 1e-15);
  EXPECT_EQ(e.course_rad, e.heading_rad);
}

TEST(ScenarioTargets, MeshFilesAreFoundBesideTheScenario) {
  const auto dir = std::filesystem::temp_directory_path() /
                   ("radar_emu_target_mesh_test_" + std::to_string(::getpid()));
  std::filesystem::create_directories(dir / "meshes");
  {
    std::ofstream obj(dir / "meshes" / "tri.obj");
    obj << "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n";
    std::ofstream toml(dir / "s.toml");
    toml << "[[target]]\nmesh_file = \"meshes/tri.obj\"\nmesh_scale = 0.001\n"
            "mesh_front_axis = \"-y\"\nmesh_up_axis = \"+z\"\nposition_enu_m = [0, 0, 0]\n"
            "[[target]]\nmesh_file = \"meshes/none.stl\"\nposition_enu_m = [0, 0, 0]\n";
  }
  try {
    (void)loop::load_scenario(dir / "s.toml");
    FAIL() << "a missing mesh file was accepted";
  } catch (const std::runtime_error& e) {
    EXPECT_EQ(std::string(e.what()), (dir / "s.toml").string() +
                                         ": [[target]] #2 mesh_file: cannot open " +
                                         (dir / "meshes" / "none.stl").string());
  }
  {
    std::ofstream toml(dir / "s.toml");
    toml << "[[target]]\nmesh_file = \"meshes/tri.obj\"\nmesh_scale = 0.001\n"
            "mesh_front_axis = \"-y\"\nmesh_up_axis = \"+z\"\nposition_enu_m = [0, 0, 0]\n";
  }
  const loop::Scenario s = loop::load_scenario(dir / "s.toml");
  ASSERT_EQ(s.targets.size(), 1u);
  EXPECT_EQ(s.targets[0].mesh_file, dir / "meshes" / "tri.obj");
  EXPECT_EQ(s.targets[0].mesh_scale, 0.001);
  EXPECT_EQ(s.targets[0].mesh_front_axis, radar_emu::scene::MeshAxis::kMinusY);
  EXPECT_EQ(s.targets[0].mesh_up_axis, radar_emu::scene::MeshAxis::kPlusZ);
  EXPECT_FALSE(s.targets[0].builtin.has_value());
  // The loop's scene: the database's objects, then the targets. The OBJ has no usemtl, so its
  // triangles take the loader's default, metal.
  const auto plain = loop::scene_description(loop::parse_scenario("", "p.toml"));
  const auto with = loop::scene_description(s);
  ASSERT_EQ(with.objects.size(), plain.objects.size() + 1);
  EXPECT_EQ(with.objects.back().name, "target_1");
  EXPECT_EQ(with.objects.back().area, "target");
  // A mesh file's own material names must be radar materials, unless the table sets one.
  {
    std::ofstream obj(dir / "meshes" / "tri.obj");
    obj << "v 0 0 0\nv 1 0 0\nv 0 1 0\nusemtl unobtainium\nf 1 2 3\n";
  }
  try {
    (void)loop::scene_description(loop::load_scenario(dir / "s.toml"));
    FAIL() << "an unknown material in a mesh file was accepted";
  } catch (const std::runtime_error& e) {
    EXPECT_EQ(std::string(e.what()).rfind((dir / "s.toml").string() +
                                              ": [[target]] #1: mesh_file material "
                                              "'unobtainium' is not a radar material (known: ",
                                          0),
              0u)
        << e.what();
    EXPECT_NE(std::string(e.what()).find("; set material = \"NAME\" in the table"),
              std::string::npos);
  }
  {
    std::ofstream toml(dir / "s.toml", std::ios::app);
    toml << "material = \"aluminium\"\n";
  }
  const auto fixed = loop::scene_description(loop::load_scenario(dir / "s.toml"));
  EXPECT_EQ(fixed.materials[fixed.objects.back().mesh.triangle_material[0]].name, "aluminium");
  std::filesystem::remove_all(dir);
}

TEST(ScenarioTargets, EveryBadTableIsOneLineNamingTheTableAndTheKey) {
  // Table #1 is always good, so the messages must count to #2.
  const std::string good =
      "[[target]]\nbuiltin = \"sphere\"\nsize_m = 1\nposition_enu_m = [0, 0, 0]\n";
  const auto second = [&](const std::string& body) {
    return error_of(good + "[[target]]\n" + body);
  };
  const std::string pos = "position_enu_m = [0, 0, 0]\n";
  const std::vector<std::pair<std::string, std::string>> cases = {
      {"builtin = \"box\"\nsize_m = [1, -1, 2]\n" + pos,
       "test.toml: [[target]] #2 size_m: -1 is outside (0, 10000]"},
      {"builtin = \"box\"\nsize_m = [1, 2]\n" + pos,
       "test.toml: [[target]] #2 size_m: a box takes 3 dimensions [length, width, height] in "
       "metres, got 2"},
      {"builtin = \"sphere\"\n" + pos,
       "test.toml: [[target]] #2 size_m: is required for a sphere: [radius] in metres"},
      {"builtin = \"sphere\"\nsize_m = nan\n" + pos,
       "test.toml: [[target]] #2 size_m: nan is outside (0, 10000]"},
      {"builtin = \"sphere\"\nsize_m = \"big\"\n" + pos,
       "test.toml: [[target]] #2 size_m: expected a number or an array of numbers, got a string"},
      {"builtin = \"tank\"\n" + pos,
       "test.toml: [[target]] #2 builtin: unknown value \"tank\" "
       "(known: plate|dihedral|trihedral-square|trihedral-tri|"
       "sphere|cylinder|box|vehicle|truck|jeep|helicopter|"
       "transport_aircraft)"},
      {pos, "test.toml: [[target]] #2 needs builtin = \"KIND\" ("},
      {"builtin = \"jeep\"\nmesh_file = \"a.obj\"\n" + pos,
       "test.toml: [[target]] #2 mesh_file: builtin and mesh_file exclude each other (give one)"},
      {"builtin = \"jeep\"\nsize = [4, 2, 2]\n" + pos,
       "test.toml: [[target]] #2 size: unknown key (known: name, builtin, size_m, "},
      {"builtin = \"jeep\"\nmaterial = \"kryptonite\"\n" + pos,
       "test.toml: [[target]] #2 material: unknown value \"kryptonite\" (known: "},
      {"builtin = \"jeep\"\nfacet_m = -0.1\n" + pos,
       "test.toml: [[target]] #2 facet_m: -0.1 is outside [0, 10000]"},
      {"builtin = \"jeep\"\nmesh_scale = 2\n" + pos,
       "test.toml: [[target]] #2 mesh_scale: applies to mesh_file only"},
      {"mesh_file = \"a.obj\"\nsize_m = 2\n" + pos,
       "test.toml: [[target]] #2 size_m: applies to builtin targets only"},
      {"mesh_file = \"a.obj\"\nmesh_scale = 0\n" + pos,
       "test.toml: [[target]] #2 mesh_scale: 0 is outside (0, 1e+06]"},
      {"mesh_file = \"a.obj\"\nmesh_front_axis = \"forward\"\n" + pos,
       "test.toml: [[target]] #2 mesh_front_axis: unknown value \"forward\" (known: +x, -x, +y, "
       "-y, +z, -z)"},
      {"mesh_file = \"a.obj\"\nmesh_front_axis = \"+y\"\nmesh_up_axis = \"-y\"\n" + pos,
       "test.toml: [[target]] #2 mesh_up_axis: must be another axis than mesh_front_axis"},
      {"builtin = \"jeep\"\n",
       "test.toml: [[target]] #2 needs position_enu_m = [e, n, u] or waypoints_enu_m = "
       "[[e, n, u], ...]"},
      {"builtin = \"jeep\"\nposition_enu_m = [0, 0]\n",
       "test.toml: [[target]] #2 position_enu_m: expected an array of 3 numbers, got an array "
       "of 2"},
      {"builtin = \"jeep\"\nposition_enu_m = [0, inf, 0]\n",
       "test.toml: [[target]] #2 position_enu_m[1]: inf is outside [-1e+06, 1e+06]"},
      {"builtin = \"jeep\"\nspeed_mps = -3\n" + pos,
       "test.toml: [[target]] #2 speed_mps: -3 is outside [0, 1000]"},
      {"builtin = \"jeep\"\nheading_deg = 400\n" + pos,
       "test.toml: [[target]] #2 heading_deg: 400 is outside [-360, 360]"},
      {"builtin = \"jeep\"\ncourse_deg = 90\n" + pos,
       "test.toml: [[target]] #2 course_deg: needs speed_mps > 0 (a fixed target has a "
       "heading_deg only)"},
      {"builtin = \"jeep\"\nclosed = true\n" + pos,
       "test.toml: [[target]] #2 closed: applies to waypoints_enu_m only"},
      {"builtin = \"jeep\"\non_ground = 1\n" + pos,
       "test.toml: [[target]] #2 on_ground: expected true or false, got an integer"},
      {"builtin = \"jeep\"\nname = \"\"\n" + pos,
       "test.toml: [[target]] #2 name: must not be empty"},
      {"builtin = \"jeep\"\nname = \"target_1\"\n" + pos,
       "test.toml: [[target]] #2 name: \"target_1\" is already used by another [[target]]"},
      {"builtin = \"jeep\"\nwaypoints_enu_m = [[0, 0, 0]]\nspeed_mps = 5\n",
       "test.toml: [[target]] #2 waypoints_enu_m: expected at least 2 [e, n, u] points, got 1"},
      {"builtin = \"jeep\"\nwaypoints_enu_m = [[0, 0, 0], [0, 0, 5]]\nspeed_mps = 5\n",
       "test.toml: [[target]] #2 waypoints_enu_m: points 0 and 1 are at the same (e, n): "
       "waypoints must be distinct (no vertical legs)"},
      {"builtin = \"jeep\"\nwaypoints_enu_m = [[0, 0, 0], [10, 0, 0]]\n",
       "test.toml: [[target]] #2 speed_mps: is required with waypoints_enu_m"},
      {"builtin = \"jeep\"\nwaypoints_enu_m = [[0, 0, 0], [10, 0, 0]]\nspeed_mps = 0\n",
       "test.toml: [[target]] #2 speed_mps: must be > 0 with waypoints_enu_m (got 0)"},
      {"builtin = \"jeep\"\nwaypoints_enu_m = [[0, 0, 0], [10, 0, 0]]\nspeed_mps = 5\n" + pos,
       "test.toml: [[target]] #2 position_enu_m: does not go with waypoints_enu_m"},
      {"builtin = \"jeep\"\nwaypoints_enu_m = [[0, 0, 0], [10, 0, 0]]\nspeed_mps = 5\n"
       "heading_deg = 3\n",
       "test.toml: [[target]] #2 heading_deg: does not go with waypoints_enu_m"},
      {"builtin = \"jeep\"\nwaypoints_enu_m = [[0, 0, 0], [10, 0, 0], [10, 10, 0]]\n"
       "speed_mps = 5\nturn_radius_m = 20\n",
       "test.toml: [[target]] #2 waypoints_enu_m: trajectory: leg 0"},
      {"builtin = \"jeep\"\nwaypoints_enu_m = [[0, 0, 0], [10, 0]]\nspeed_mps = 5\n",
       "test.toml: [[target]] #2 waypoints_enu_m[1]: expected an array of 3 numbers, got an "
       "array of 2"},
      {"builtin = \"jeep\"\nwaypoints_enu_m = [[0, 0, 0], [10, 0, 2e6]]\nspeed_mps = 5\n",
       "test.toml: [[target]] #2 waypoints_enu_m[1][2]: 2e+06 is outside [-1e+06, 1e+06]"},
  };
  for (const auto& [body, expected] : cases) {
    const std::string e = second(body);
    EXPECT_EQ(e.rfind(expected, 0), 0u) << "table:\n"
                                        << body << "expected: " << expected << "\ngot:      " << e;
    EXPECT_EQ(e.find('\n'), std::string::npos) << e;
  }
  // [target] as a single table, or a plain key, is not the array of tables.
  EXPECT_EQ(error_of("[target]\nbuiltin = \"jeep\"\n"),
            "test.toml: target: expected [[target]] tables (an array of tables), got a table");
  EXPECT_EQ(error_of("target = 3\n"),
            "test.toml: target: expected [[target]] tables (an array of tables), got an integer");
  EXPECT_EQ(error_of("target = [1]\n"),
            "test.toml: target: expected [[target]] tables (an array of tables), got an array "
            "holding an integer");
}

TEST(ScenarioTargets, TheExamplesLoad) {
  const char* root = std::getenv("RADAR_EMU_SOURCE_DIR");
  if (root == nullptr)
    GTEST_SKIP() << "RADAR_EMU_SOURCE_DIR is not set (ctest sets it)";
  const std::filesystem::path examples = std::filesystem::path(root) / "examples";
  // examples/terrain_movers.toml: three vehicles on the terrain's roads (the loop run and its
  // detections are checked by the terrain_movers_example test).
  const loop::Scenario movers = loop::load_scenario(examples / "terrain_movers.toml");
  EXPECT_EQ(movers.scene_builtin, "terrain");
  ASSERT_EQ(movers.targets.size(), 3u);
  for (const auto& t : movers.targets) {
    EXPECT_TRUE(t.on_ground) << t.name;
    EXPECT_GE(t.waypoints_m.size(), 3u) << t.name;
  }
  EXPECT_EQ(movers.targets[0].name, "truck_road_1");
  EXPECT_EQ(movers.targets[1].name, "tank_road_1");
  EXPECT_EQ(movers.targets[2].name, "jeep_road_1");

  // examples/gltf_targets.toml on examples/scene_extras.gltf: the file's nodes with their extras
  // (the schema of docs/scene_format.md), then the two tables' targets.
  const loop::Scenario g = loop::load_scenario(examples / "gltf_targets.toml");
  EXPECT_EQ(g.scene_file, examples / "scene_extras.gltf");
  const radar_emu::scene::SceneDescription d = loop::scene_description(g);
  ASSERT_EQ(d.objects.size(), 6u);
  EXPECT_EQ(d.objects[0].name, "ground");
  EXPECT_EQ(d.objects[0].area, "airport");
  EXPECT_EQ(d.objects[1].name, "hangar");
  EXPECT_EQ(glm::dvec3(d.objects[1].world_from_body[3]), glm::dvec3(150, 900, 0));
  ASSERT_TRUE(d.objects[2].motion.has_value());
  EXPECT_EQ(d.objects[2].motion->velocity_mps, glm::dvec3(-5, 0, 0));
  EXPECT_EQ(d.objects[2].motion->start_position_m, glm::dvec3(100, 600, 0));
  ASSERT_TRUE(d.objects[3].trajectory.has_value());
  EXPECT_TRUE(d.objects[3].trajectory->loop);
  EXPECT_EQ(d.objects[3].trajectory->turn_radius_m, 20.0);
  // "yellow paint" is metal by its radar_material extras.
  EXPECT_EQ(d.materials[d.objects[2].mesh.triangle_material[0]].name, "metal");
  EXPECT_NEAR(d.anchor.latitude_rad, common::radians(43.6), 1e-12);
  EXPECT_EQ(d.objects[4].name, "parked_a320");
  EXPECT_EQ(d.objects[5].name, "westbound_jeep");
  ASSERT_TRUE(d.objects[5].motion.has_value());
  EXPECT_NEAR(d.objects[5].motion->velocity_mps.x, -8.0, 1e-12);  // west
  // on_ground on the file's flat ground (z = 0): the jeep's wheels (its lowest point) at z = 0.
  EXPECT_NEAR(d.objects[5].motion->start_position_m.z, 0.0, 1e-6);
}

// The case of `radar-emu sar` reads through the same reader as the scenario: the same message
// format, std::invalid_argument as its contract says (tools/sar_case.hpp).
TEST(SarCase, ErrorsAreOneLineInTheScenariosFormat) {
  const auto sar_error = [](const std::string& text) -> std::string {
    try {
      (void)radar_emu::tools::parse_sar_case(text, "case.toml");
    } catch (const std::invalid_argument& e) {
      return e.what();
    }
    return "";
  };
  EXPECT_EQ(sar_error(""), "");  // every key has a default
  EXPECT_EQ(sar_error("[radar]\ncarrier = 1\n"),
            "case.toml: [radar] carrier: unknown key (known: carrier_hz, bandwidth_hz, "
            "sample_rate_hz, pulse_duration_s, prf_hz, transmit_power_w, peak_gain_db, "
            "polarisation)");
  EXPECT_EQ(sar_error("[radr]\n"),
            "case.toml: radr: unknown table (known: radar, platform, antenna, processing, scene)");
  EXPECT_EQ(sar_error("[platform]\nheading_deg = 400\n"),
            "case.toml: [platform] heading_deg: 400 is outside [-360, 360]");
  EXPECT_EQ(sar_error("[antenna]\nazimuth_beamwidth_deg = 0.001\n"),
            "case.toml: [antenna] azimuth_beamwidth_deg: 0.001 is outside (0.001, 30]");
  EXPECT_EQ(sar_error("[radar]\nprf_hz = \"fast\"\n"),
            "case.toml: [radar] prf_hz: expected a number, got a string");
  EXPECT_EQ(sar_error("[radar]\npolarisation = \"RHC\"\n"),
            "case.toml: [radar] polarisation: 'RHC' is not one of HH, HV, VH, VV");
  EXPECT_EQ(sar_error("[[scene.target]]\nposition_m = [0, 0, 0]\n[[scene.target]]\nsize = 1\n"),
            "case.toml: [[scene.target]] #2 size: unknown key (known: name, kind, a_m, b_m, c_m, "
            "position_m, velocity_mps, heading_deg)");
  EXPECT_EQ(sar_error("[scene]\ntarget = 3\n"),
            "case.toml: [scene] target: expected [[scene.target]] tables (an array of tables), "
            "got an integer");
  EXPECT_EQ(sar_error("[radar\n").rfind("case.toml:1:7: ", 0), 0u);
  // Degrees at the edge: the heading and the beams in radians.
  const radar_emu::tools::SarCase c = radar_emu::tools::parse_sar_case(
      "[platform]\nheading_deg = 45\n[antenna]\nincidence_deg = 60\n", "case.toml");
  EXPECT_EQ(c.heading_rad, common::radians(45.0));
  EXPECT_EQ(c.p.incidence_rad, common::radians(60.0));
}
