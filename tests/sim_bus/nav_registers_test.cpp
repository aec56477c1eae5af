// The in-process register bank and the scripted Modbus navigation device
// (sim_bus/loopback_registers.hpp, sim_bus/nav_register_player.hpp).

#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <numbers>
#include <stdexcept>
#include <vector>

#include "common/units.hpp"
#include "io/modbus_map.hpp"
#include "sim_bus/loopback_registers.hpp"
#include "sim_bus/nav_register_player.hpp"

namespace {

using namespace radar_emu;
using io::RegisterStatus;
using io::canas::Field;

TEST(LoopbackRegisterBank, ChecksQuantityThenAddressLikeAServer) {
  sim_bus::LoopbackRegisterBank bank(100, 10);
  std::array<std::uint16_t, 3> three{1, 2, 3};
  std::vector<std::uint16_t> many(126);
  // Modbus application protocol v1.1b3, fig. 13/26: quantity (exception 3) before address (2).
  EXPECT_EQ(bank.read_holding(0, many), RegisterStatus::kError);
  EXPECT_EQ(bank.read_holding(100, std::span<std::uint16_t>()), RegisterStatus::kError);
  EXPECT_EQ(bank.write_holding(100, std::span(many).first(124)), RegisterStatus::kError);
  EXPECT_EQ(bank.read_holding(99, std::span(three).first(1)), RegisterStatus::kIllegalAddress);
  EXPECT_EQ(bank.read_holding(108, three), RegisterStatus::kIllegalAddress);
  EXPECT_EQ(bank.write_holding(108, three), RegisterStatus::kIllegalAddress);
  EXPECT_EQ(bank.counters().bad_quantity, 3u);
  EXPECT_EQ(bank.counters().illegal_address, 3u);

  ASSERT_EQ(bank.write_holding(107, three), RegisterStatus::kOk);
  std::array<std::uint16_t, 4> out{};
  ASSERT_EQ(bank.read_holding(106, out), RegisterStatus::kOk);
  EXPECT_EQ(out, (std::array<std::uint16_t, 4>{0, 1, 2, 3}));
  EXPECT_EQ(bank.registers()[7], 1);
  EXPECT_EQ(bank.counters().reads, 1u);
  EXPECT_EQ(bank.counters().writes, 1u);
}

TEST(LoopbackRegisterBank, RejectsBadSetup) {
  EXPECT_THROW(sim_bus::LoopbackRegisterBank(0, 0), std::invalid_argument);
  EXPECT_THROW(sim_bus::LoopbackRegisterBank(65535, 2), std::invalid_argument);
  EXPECT_NO_THROW(sim_bus::LoopbackRegisterBank(65535, 1));
}

// Straight and level eastbound at 100 m/s, 10 s; climbing 5 m/s.
sim_bus::Trajectory line() {
  sim_bus::AircraftState a;
  a.latitude_rad = common::radians(48.0);
  a.longitude_rad = common::radians(11.0);
  a.height_m = 1000.0;
  a.true_heading_rad = common::radians(90.0);
  a.vel_east_mps = 100.0;
  a.vel_up_mps = 5.0;
  sim_bus::AircraftState b = a;
  b.time_s = 10.0;
  b.longitude_rad = common::radians(11.01);
  b.height_m = 1050.0;
  return sim_bus::Trajectory({a, b});
}

TEST(NavRegisterPlayer, WritesTheNewestDueUpdateOnly) {
  const io::modbus::NavMapConfig map{.base_address = 40};
  sim_bus::LoopbackRegisterBank bank(40, io::modbus::nav_register_count(map));
  sim_bus::NavRegisterPlayer player(line(), {.map = map, .rate_hz = 50.0});
  io::modbus::NavDecoder decoder(map);

  EXPECT_EQ(player.publish_until(-1.0, bank), 0u);
  ASSERT_EQ(player.publish_until(0.0, bank), 1u);
  ASSERT_EQ(decoder.decode(bank.registers(), 1), io::modbus::NavDecodeStatus::kAccepted);
  EXPECT_EQ(decoder.last_update_counter(), 1);
  EXPECT_EQ(decoder.last_sender_time_ms(), 0u);
  EXPECT_EQ(player.publish_until(0.019, bank), 0u);  // next due at 0.020 s

  ASSERT_EQ(player.publish_until(0.1, bank), 1u);  // due 0.02 .. 0.10: only 0.10 is written
  EXPECT_EQ(player.skipped_updates(), 4u);
  EXPECT_EQ(player.publish_until(0.1, bank), 0u);
  ASSERT_EQ(decoder.decode(bank.registers(), 2), io::modbus::NavDecodeStatus::kAccepted);
  EXPECT_EQ(decoder.last_update_counter(), 2);
  EXPECT_EQ(decoder.last_sender_time_ms(), 100u);
  const auto& s = decoder.state();
  // Linear between the waypoints: 1 % of the way at 0.1 s.
  EXPECT_NEAR(s[Field::kLongitude].value, common::radians(11.0 + 0.01 * 0.01), 1e-15);
  EXPECT_NEAR(s[Field::kLatitude].value, common::radians(48.0), 1e-15);
  EXPECT_NEAR(s[Field::kHeight].value, 1000.5, 1000.5 * 0x1p-24);
  EXPECT_NEAR(s[Field::kTrueHeading].value, std::numbers::pi / 2, 1e-7);
  EXPECT_NEAR(s[Field::kVelEast].value, 100.0, 1e-12);
  EXPECT_EQ(player.updates(), 2u);
}

TEST(NavRegisterPlayer, ClosedLoopGoesStaleWhenThePlayerStops) {
  const io::modbus::NavMapConfig map{.order = io::modbus::WordOrder::kCDAB,
                                     .encoding = io::modbus::NavMapConfig::Encoding::kScaledInt};
  sim_bus::LoopbackRegisterBank bank(0, io::modbus::nav_register_count(map));
  sim_bus::NavRegisterPlayer player(line(), {.map = map, .rate_hz = 50.0});
  io::modbus::NavDecoder decoder(map);
  std::vector<std::uint16_t> regs(decoder.register_count());
  const std::int64_t timeout_ns = 100'000'000;
  // 20 Hz radar frames for 1 s with the device playing, then 1 s with the device frozen.
  for (int frame = 0; frame < 40; ++frame) {
    const double t_s = 0.05 * frame;
    const auto now_ns = static_cast<std::int64_t>(std::llround(t_s * 1e9));
    if (t_s < 1.0)
      (void)player.publish_until(t_s, bank);
    ASSERT_EQ(bank.read_holding(0, regs), RegisterStatus::kOk);
    const auto st = decoder.decode(regs, now_ns);
    if (t_s < 1.0) {
      EXPECT_EQ(st, io::modbus::NavDecodeStatus::kAccepted) << t_s;
      EXPECT_TRUE(decoder.state().all_fresh(now_ns, timeout_ns));
      const double due_s = std::floor(t_s * 50.0 + 1e-9) / 50.0;  // newest 50 Hz update
      EXPECT_NEAR(decoder.state()[Field::kHeight].value, 1000.0 + 5.0 * due_s, 0.5e-3 + 1e-9);
    } else {
      EXPECT_EQ(st, io::modbus::NavDecodeStatus::kStale) << t_s;
      EXPECT_EQ(decoder.state().all_fresh(now_ns, timeout_ns), t_s - 0.95 <= 0.1 + 1e-9) << t_s;
    }
  }
  EXPECT_EQ(decoder.counters().rejected(), 0u);
  EXPECT_EQ(decoder.counters().stale, 20u);
}

TEST(NavRegisterPlayer, CountsWriteFailuresAndRejectsBadSetup) {
  sim_bus::LoopbackRegisterBank small(0, 10);  // shorter than the map
  sim_bus::NavRegisterPlayer player(line(), {});
  EXPECT_EQ(player.publish_until(0.0, small), 0u);
  EXPECT_EQ(player.write_failures(), 1u);
  EXPECT_THROW(sim_bus::NavRegisterPlayer(line(), {.rate_hz = 0.0}), std::invalid_argument);
  EXPECT_THROW(sim_bus::NavRegisterPlayer(line(), {.map = {.base_address = 65520}}),
               std::invalid_argument);
}

}  // namespace
