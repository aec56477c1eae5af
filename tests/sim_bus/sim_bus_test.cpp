// Tests of sim_bus/: loopback delivery, the scripted aircraft-state player (schedule and values
// decoded by the independent-of-the-player CANaerospace decoder) and the avionics sink.

#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "common/units.hpp"
#include "io/canaerospace.hpp"
#include "io/detection_icd.hpp"
#include "sim_bus/aircraft_player.hpp"
#include "sim_bus/avionics_sink.hpp"
#include "sim_bus/loopback_can.hpp"

namespace sb = radar_emu::sim_bus;
namespace io = radar_emu::io;
namespace canas = radar_emu::io::canas;

namespace {
io::CanFrame frame_with_id(std::uint32_t id) {
  io::CanFrame f;
  f.id = id;
  f.len = 1;
  f.data[0] = static_cast<std::uint8_t>(id);
  return f;
}
namespace common = radar_emu::common;
}  // namespace

TEST(LoopbackCanBus, EveryOtherEndpointReceivesInSendOrder) {
  sb::LoopbackCanBus bus;
  auto& a = bus.add_endpoint("a");
  auto& b = bus.add_endpoint("b");
  auto& c = bus.add_endpoint("c");
  ASSERT_TRUE(a.send(frame_with_id(1)));
  ASSERT_TRUE(b.send(frame_with_id(2)));
  ASSERT_TRUE(a.send(frame_with_id(3)));
  io::CanFrame f;
  // a sees only b's frame; b sees a's two; c sees all three in bus order.
  ASSERT_TRUE(a.receive(f));
  EXPECT_EQ(f.id, 2u);
  EXPECT_FALSE(a.receive(f));
  std::vector<std::uint32_t> got_b, got_c;
  while (b.receive(f))
    got_b.push_back(f.id);
  while (c.receive(f))
    got_c.push_back(f.id);
  EXPECT_EQ(got_b, (std::vector<std::uint32_t>{1, 3}));
  EXPECT_EQ(got_c, (std::vector<std::uint32_t>{1, 2, 3}));
  EXPECT_EQ(bus.frames_carried(), 3u);
}

TEST(LoopbackCanBus, FullQueueCountsOverflowAndKeepsOldest) {
  sb::LoopbackCanBus bus;
  auto& tx = bus.add_endpoint("tx");
  auto& rx = bus.add_endpoint("rx", 2);
  for (std::uint32_t i = 0; i < 5; ++i)
    ASSERT_TRUE(tx.send(frame_with_id(i)));
  EXPECT_EQ(rx.rx_overflows(), 3u);
  io::CanFrame f;
  ASSERT_TRUE(rx.receive(f));
  EXPECT_EQ(f.id, 0u);
  ASSERT_TRUE(rx.receive(f));
  EXPECT_EQ(f.id, 1u);
  EXPECT_FALSE(rx.receive(f));
  EXPECT_THROW(bus.add_endpoint("bad", 0), std::invalid_argument);
}

TEST(Trajectory, InterpolatesLinearlyAndHeadingAlongShorterArc) {
  sb::AircraftState a, b;
  a.time_s = 0.0;
  b.time_s = 10.0;
  a.height_m = 100.0;
  b.height_m = 200.0;
  a.true_heading_rad = common::radians(350.0);
  b.true_heading_rad = common::radians(10.0);  // shorter arc passes through north
  sb::Trajectory traj({a, b});
  const sb::AircraftState m = traj.at(2.5);
  EXPECT_DOUBLE_EQ(m.height_m, 125.0);
  EXPECT_NEAR(m.true_heading_rad, common::radians(355.0), 1e-12);
  EXPECT_NEAR(traj.at(7.5).true_heading_rad, common::radians(5.0), 1e-12);
  EXPECT_DOUBLE_EQ(traj.at(-5.0).height_m, 100.0);  // held before the first waypoint
  EXPECT_DOUBLE_EQ(traj.at(50.0).height_m, 200.0);
  EXPECT_THROW(sb::Trajectory({b, a}), std::invalid_argument);
  EXPECT_THROW(sb::Trajectory(std::vector<sb::AircraftState>{}), std::invalid_argument);
}

TEST(AircraftStatePlayer, BaselineScheduleAndDecodedValues) {
  sb::AircraftState a;
  a.time_s = 0.0;
  a.latitude_rad = common::radians(43.6);
  a.longitude_rad = common::radians(1.4);
  a.height_m = 500.0;
  a.pitch_rad = common::radians(2.0);
  a.roll_rad = common::radians(-1.0);
  a.true_heading_rad = common::radians(90.0);
  a.vel_east_mps = 70.0;
  a.vel_north_mps = 0.0;
  a.vel_up_mps = -3.5;
  sb::AircraftState b = a;
  b.time_s = 100.0;
  b.longitude_rad = common::radians(1.5);
  b.height_m = 150.0;

  sb::LoopbackCanBus bus;
  auto& player_ep = bus.add_endpoint("ins", 1 << 16);
  auto& radar_ep = bus.add_endpoint("radar", 1 << 16);
  sb::PlayerConfig cfg;
  cfg.node_id = 7;
  sb::AircraftStatePlayer player(sb::Trajectory({a, b}), cfg);

  // One second at the baseline: attitude 3 ids x 80 Hz, navigation (2 doubles = 4 frames,
  // plus 4 floats) x 10 Hz. Times 0 .. 1.0 s inclusive: 81 attitude and 11 navigation slots.
  const std::size_t sent = player.publish_until(1.0, player_ep);
  EXPECT_EQ(sent, 81u * 3u + 11u * 8u);
  EXPECT_EQ(player.publish_until(1.0, player_ep), 0u);  // nothing is sent twice

  canas::Decoder dec;
  io::CanFrame f;
  std::size_t n = 0;
  while (radar_ep.receive(f)) {
    ASSERT_EQ(f.data[0], 7);  // node-ID
    const auto st = dec.decode(f, f.timestamp_ns);
    ASSERT_TRUE(st == canas::DecodeStatus::kAccepted ||
                st == canas::DecodeStatus::kPendingDoubleLow)
        << "frame " << n;
    ++n;
  }
  EXPECT_EQ(n, sent);
  EXPECT_EQ(dec.counters().rejected(), 0u);
  EXPECT_EQ(dec.counters().message_code_gaps, 0u);
  const auto& st = dec.state();
  // Values at t = 1.0 s (last navigation and attitude slot), by linear interpolation.
  const double f_t = 1.0 / 100.0;
  EXPECT_NEAR(st[canas::Field::kLongitude].value, common::radians(1.4 + 0.1 * f_t),
              1e-15);  // double
  EXPECT_NEAR(st[canas::Field::kLatitude].value, common::radians(43.6), 1e-15);
  EXPECT_NEAR(st[canas::Field::kHeight].value, 500.0 - 350.0 * f_t, 1e-4);  // float on the bus
  EXPECT_NEAR(st[canas::Field::kPitch].value, common::radians(2.0), 1e-7);
  EXPECT_NEAR(st[canas::Field::kRoll].value, common::radians(-1.0), 1e-7);
  EXPECT_NEAR(st[canas::Field::kTrueHeading].value, common::radians(90.0), 1e-7);
  EXPECT_NEAR(st[canas::Field::kVelEast].value, 70.0, 1e-5);
  EXPECT_NEAR(st[canas::Field::kVelUp].value, -3.5, 1e-6);
  EXPECT_EQ(st[canas::Field::kHeight].updated_ns, 1'000'000'000);
}

TEST(AvionicsSink, ReassemblesEncodedLists) {
  sb::LoopbackCanBus bus;
  auto& radar = bus.add_endpoint("radar");
  auto& avionics = bus.add_endpoint("avionics");
  sb::AvionicsSink sink(8);
  std::vector<io::icd::Detection> dets(3);
  for (std::size_t i = 0; i < dets.size(); ++i) {
    dets[i].range_m = 1000.0 + 10.0 * static_cast<double>(i);
    dets[i].azimuth_deg = -5.0 + static_cast<double>(i);
    dets[i].elevation_deg = -2.0;
    dets[i].radial_velocity_mps = -60.0;
    dets[i].snr_db = 20.0;
    dets[i].rcs_dbsm = 10.0;
  }
  std::vector<io::CanFrame> frames(io::icd::frames_for(dets.size()));
  for (std::uint16_t frame_counter = 0; frame_counter < 2; ++frame_counter) {
    io::icd::Header h;
    h.frame_counter = frame_counter;
    const auto res = io::icd::encode(h, dets, frames);
    ASSERT_EQ(res.frames, 7u);
    for (std::size_t i = 0; i < res.frames; ++i)
      ASSERT_TRUE(radar.send(frames[i]));
  }
  EXPECT_EQ(sink.poll(avionics), 2u);
  ASSERT_EQ(sink.lists().size(), 2u);
  EXPECT_EQ(sink.lists()[1].header.frame_counter, 1u);
  ASSERT_EQ(sink.lists()[1].count, 3u);
  EXPECT_NEAR(sink.lists()[1].detections[2].range_m, 1020.0, 0.005);
  EXPECT_NEAR(sink.lists()[1].detections[2].azimuth_deg, -3.0, 0.005);
}
