// Scenario parsing: the embedded default is complete and consistent, a user file overrides only
// what it names, and every kind of bad input fails with a message that says where and why.

#include "emulator/scenario.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <numbers>
#include <stdexcept>
#include <string>

namespace emu = radar_emu::emulator;

namespace {
std::string error_of(const std::string& text) {
  try {
    (void)emu::parse_scenario(text, "test.toml");
  } catch (const std::runtime_error& e) {
    return e.what();
  }
  return "";
}
constexpr double kDeg = std::numbers::pi / 180.0;
}  // namespace

TEST(Scenario, DefaultValuesAreTheDocumentedOnes) {
  const emu::Scenario s = emu::parse_scenario(emu::default_scenario_toml(), "<default scenario>");
  EXPECT_EQ(s.frames, 200u);
  EXPECT_DOUBLE_EQ(s.rate_hz, 20.0);
  EXPECT_DOUBLE_EQ(s.sensor.processing.waveform.carrier_hz, 94e9);
  EXPECT_DOUBLE_EQ(s.sbr.carrier_hz, s.sensor.processing.waveform.carrier_hz);
  EXPECT_NEAR(s.sensor.noise_figure, std::pow(10.0, 0.5), 1e-12);  // 5 dB
  EXPECT_NEAR(s.antenna_depression_rad, 5.0 * kDeg, 1e-15);
  // 16 beams of 1 deg across -8..8 deg; PRI from the PRF; the range gate from 1500 m.
  ASSERT_EQ(s.sensor.antenna.beam_azimuth_rad.size(), 16u);
  EXPECT_NEAR(s.sensor.antenna.beam_azimuth_rad.front(), -7.5 * kDeg, 1e-12);
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
  const emu::Scenario s = emu::parse_scenario(
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
  EXPECT_EQ(emu::parse_scenario(emu::default_scenario_toml(), "<default>").sbr.polarisation,
            radar_emu::radar::Polarisation::kVV);
  EXPECT_EQ(emu::parse_scenario("[antenna]\npolarisation = \"HH\"\n", "p.toml").sbr.polarisation,
            radar_emu::radar::Polarisation::kHH);
  EXPECT_EQ(emu::parse_scenario("[antenna]\npolarisation = \"HV\"\n", "p.toml").sbr.polarisation,
            radar_emu::radar::Polarisation::kHV);
  EXPECT_EQ(emu::parse_scenario("[antenna]\npolarisation = \"VH\"\n", "p.toml").sbr.polarisation,
            radar_emu::radar::Polarisation::kVH);
  EXPECT_NE(error_of("[antenna]\npolarisation = \"RHC\"\n").find("[antenna] polarisation"),
            std::string::npos);
}

TEST(Scenario, UserFileOverridesOnlyWhatItNames) {
  const emu::Scenario s =
      emu::parse_scenario("[run]\nframes = 7\n[radar]\ncarrier_hz = 35.0e9\n", "user.toml");
  EXPECT_EQ(s.frames, 7u);
  EXPECT_DOUBLE_EQ(s.sensor.processing.waveform.carrier_hz, 35e9);
  EXPECT_DOUBLE_EQ(s.sbr.carrier_hz, 35e9);
  EXPECT_DOUBLE_EQ(s.rate_hz, 20.0);  // from the default
}

TEST(Scenario, BadInputFailsWithLocationAndReason) {
  EXPECT_NE(error_of("[run]\nframez = 3\n").find("test.toml: [run] framez: unknown key"),
            std::string::npos);
  EXPECT_NE(error_of("[rn]\n").find("unknown table"), std::string::npos);
  EXPECT_NE(error_of("[run]\nframes = \"many\"\n").find("[run] frames: expected an integer"),
            std::string::npos);
  EXPECT_NE(error_of("[run]\nframes = 0\n").find("outside [1,"), std::string::npos);
  EXPECT_NE(error_of("[run]\nrate_hz = nan\n").find("rate_hz"), std::string::npos);
  EXPECT_NE(error_of("[ownship]\nstart_enu_m = [1.0, 2.0]\n").find("array of 3"),
            std::string::npos);
  EXPECT_NE(
      error_of("[antenna]\nazimuth_min_deg = 10.0\nazimuth_max_deg = 5.0\n").find("greater than"),
      std::string::npos);
  EXPECT_NE(error_of("[scene]\nbuiltin = \"moon\"\n").find("unknown built-in scene"),
            std::string::npos);
  EXPECT_NE(error_of("[radar]\nwaveform = \"cw\"\n").find("[radar] waveform: unknown"),
            std::string::npos);
  EXPECT_NE(error_of("[radar]\nrange_window = \"kaiser\"\n").find("unknown window"),
            std::string::npos);
  EXPECT_NE(error_of("[antenna]\npattern = \"table\"\n").find("pattern_file"), std::string::npos);
  EXPECT_NE(error_of("[radar]\npulse_width_s = 60e-6\n").find("[radar]"), std::string::npos);
  // Syntax errors carry line and column.
  EXPECT_NE(error_of("[run]\nframes = = 3\n").find("test.toml:2:"), std::string::npos);
  // Found by fuzzing (tests/fuzz/regressions/scenario_toml/): a range-Doppler map of 1502 x
  // 65536 cells took 0.8 GB and seconds to check; above 2^24 cells it is a clear error.
  EXPECT_NE(error_of("[radar]\npulses = 65536\n")
                .find("test.toml: [radar] range_bins x pulses = 1502 x 65536 cells per beam "
                      "exceeds 16777216"),
            std::string::npos);
  EXPECT_EQ(error_of("[radar]\npulses = 8192\n"), "");  // 12.3 M cells: allowed
}

TEST(Scenario, MissingFileNamesThePath) {
  try {
    (void)emu::load_scenario("/nonexistent/dir/s.toml");
    FAIL() << "no error";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("/nonexistent/dir/s.toml"), std::string::npos);
  }
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
  const emu::Scenario s = emu::load_scenario(dir / "s.toml");
  ASSERT_EQ(s.sensor.antenna.azimuth.table_angle_rad.size(), 5u);
  EXPECT_NEAR(s.sensor.antenna.azimuth.table_angle_rad[1], -kDeg, 1e-15);
  EXPECT_DOUBLE_EQ(s.sensor.antenna.azimuth.table_gain_db[1], -3.0);
  {
    std::ofstream csv(dir / "az.csv");
    csv << "angle_deg,gain_db\n-5,-30\n-1;-3\n";
  }
  try {
    (void)emu::load_scenario(dir / "s.toml");
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
  const emu::Scenario s =
      emu::load_scenario(std::filesystem::path(root) / "examples" / "ev_radar_94ghz.toml");
  ASSERT_EQ(s.sensor.antenna.beam_azimuth_rad.size(), 200u);
  EXPECT_NEAR(s.sensor.antenna.beam_azimuth_rad.front(), (-15.0 + 0.075) * kDeg, 1e-12);
  EXPECT_NEAR(s.sensor.antenna.azimuth.beamwidth_rad, 0.15 * kDeg, 1e-15);
  EXPECT_NEAR(s.sensor.antenna.elevation.beamwidth_rad, 10.0 * kDeg, 1e-15);
  EXPECT_FALSE(s.sensor.antenna.monopulse);
  // The scan fits the frame: 200 beams x 8 pulses x 50 us = 80 ms of radar time at 10 Hz.
  EXPECT_LE(200.0 * s.sensor.processing.waveform.pulses * s.sensor.processing.waveform.pri_s,
            1.0 / s.rate_hz);
}

TEST(Scenario, WeatherTableDefaultsAndRangeChecks) {
  // No [weather] table: free space. A table: gases always, precipitation by condition, with the
  // documented typical amounts when not given.
  const emu::Scenario none = emu::parse_scenario(emu::default_scenario_toml(), "<default>");
  EXPECT_FALSE(none.weather.enabled);
  const emu::Scenario clear = emu::parse_scenario("[weather]\n", "test.toml");
  EXPECT_TRUE(clear.weather.enabled);
  EXPECT_EQ(clear.weather.condition, "clear");
  EXPECT_EQ(clear.weather.rain_mm_per_h, 0.0);
  EXPECT_EQ(clear.weather.fog_water_gm3, 0.0);
  EXPECT_DOUBLE_EQ(clear.weather.humidity_gm3, 7.5);
  EXPECT_DOUBLE_EQ(clear.weather.temperature_k, 288.15);
  EXPECT_DOUBLE_EQ(clear.weather.pressure_hpa, 1013.25);
  const emu::Scenario fog = emu::parse_scenario("[weather]\ncondition = \"fog\"\n", "test.toml");
  EXPECT_DOUBLE_EQ(fog.weather.fog_water_gm3, 0.05);
  const emu::Scenario both = emu::parse_scenario(
      "[weather]\ncondition = \"rain_fog\"\nrain_rate_mmph = 12.5\ntemperature_c = -5\n",
      "test.toml");
  EXPECT_DOUBLE_EQ(both.weather.rain_mm_per_h, 12.5);
  EXPECT_DOUBLE_EQ(both.weather.fog_water_gm3, 0.05);
  EXPECT_NEAR(both.weather.temperature_k, 268.15, 1e-12);
  EXPECT_NE(error_of("[weather]\ncondition = \"snow\"\n")
                .find("test.toml: [weather] condition: unknown condition 'snow'"),
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
  const emu::Scenario s =
      emu::load_scenario(std::filesystem::path(root) / "examples" / "fog_approach.toml");
  EXPECT_TRUE(s.weather.enabled);
  EXPECT_EQ(s.weather.condition, "fog");
  EXPECT_DOUBLE_EQ(s.weather.fog_water_gm3, 0.5);
}
