// Detection ICD (docs/icd/detections.md): bytes worked out by hand for one list, round trips at
// a fixed seed within half a quantisation step, range checks, and list reassembly under
// corruption.

#include "io/detection_icd.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <random>
#include <vector>

namespace io = radar_emu::io;
namespace icd = radar_emu::io::icd;

namespace {
icd::Detection make(double r, double az, double el, double vr, double snr, double rcs) {
  icd::Detection d;
  d.range_m = r;
  d.azimuth_deg = az;
  d.elevation_deg = el;
  d.radial_velocity_mps = vr;
  d.snr_db = snr;
  d.rcs_dbsm = rcs;
  return d;
}
std::vector<std::uint8_t> bytes(const io::CanFrame& f) {
  return std::vector<std::uint8_t>(f.data.begin(), f.data.begin() + f.len);
}
}  // namespace

TEST(DetectionIcdByHand, OneDetection) {
  // Header: frame counter 0x1234 -> 34 12; count 1; status 0x02 (overrun); time 5000 ms =
  // 0x00001388 -> 88 13 00 00 (little-endian, DBC @1).
  // A: index 0; counter low byte 0x34; range 1234.56 m / 0.01 = 123456 = 0x01E240 -> 40 E2 01;
  //    vr -55.5 m/s / 0.02 = -2775 = 0xF529 (two's complement) -> 29 F5; SNR 25.5 / 0.5 = 51 =
  //    0x33.
  // B: index 0; 0x34; az -3.21 deg / 0.01 = -321 = 0xFEBF -> BF FE; el 1.5 / 0.01 = 150 -> 96 00;
  //    RCS 20.25 / 0.01 = 2025 = 0x07E9 -> E9 07.
  icd::Header h;
  h.frame_counter = 0x1234;
  h.status = icd::status::kOverrun;
  h.time_ms = 5000;
  const icd::Detection d = make(1234.56, -3.21, 1.5, -55.5, 25.5, 20.25);
  std::vector<io::CanFrame> out(3);
  const icd::EncodeResult r = icd::encode(h, std::span(&d, 1), out);
  ASSERT_EQ(r.frames, 3u);
  EXPECT_EQ(r.encoded, 1u);
  EXPECT_EQ(out[0].id, 0x708u);
  EXPECT_EQ(bytes(out[0]),
            (std::vector<std::uint8_t>{0x34, 0x12, 0x01, 0x02, 0x88, 0x13, 0x00, 0x00}));
  EXPECT_EQ(out[1].id, 0x709u);
  EXPECT_EQ(bytes(out[1]),
            (std::vector<std::uint8_t>{0x00, 0x34, 0x40, 0xE2, 0x01, 0x29, 0xF5, 0x33}));
  EXPECT_EQ(out[2].id, 0x70Au);
  EXPECT_EQ(bytes(out[2]),
            (std::vector<std::uint8_t>{0x00, 0x34, 0xBF, 0xFE, 0x96, 0x00, 0xE9, 0x07}));

  icd::ListDecoder dec;
  EXPECT_EQ(dec.feed(out[0]), icd::FeedStatus::kConsumed);
  EXPECT_EQ(dec.feed(out[1]), icd::FeedStatus::kConsumed);
  EXPECT_EQ(dec.feed(out[2]), icd::FeedStatus::kComplete);
  const icd::DetectionList& l = dec.list();
  EXPECT_EQ(l.header.frame_counter, 0x1234);
  EXPECT_EQ(l.header.status, icd::status::kOverrun);
  EXPECT_EQ(l.header.time_ms, 5000u);
  ASSERT_EQ(l.count, 1u);
  EXPECT_NEAR(l.detections[0].range_m, 1234.56, 1e-9);
  EXPECT_NEAR(l.detections[0].azimuth_deg, -3.21, 1e-9);
  EXPECT_NEAR(l.detections[0].radial_velocity_mps, -55.5, 1e-9);
  EXPECT_NEAR(l.detections[0].rcs_dbsm, 20.25, 1e-9);
}

TEST(DetectionIcd, ResolutionsMeetTheAircraftRequirement) {
  // Issue 2: range to at least 20 km in 0.1 m steps or finer, angles to +-90 deg in 0.05 deg
  // steps or finer, radial velocity +-500 m/s in 0.1 m/s steps or finer.
  EXPECT_GE(icd::kMaxRange_m, 20000.0);
  EXPECT_LE(icd::kRangeScale_m, 0.1);
  EXPECT_GE(32767 * icd::kAngleScale_deg, 90.0);
  EXPECT_LE(icd::kAngleScale_deg, 0.05);
  EXPECT_GE(32767 * icd::kRadialVelocityScale_mps, 500.0);
  EXPECT_LE(icd::kRadialVelocityScale_mps, 0.1);
}

TEST(DetectionIcd, RoundTripWithinHalfAStepAtFixedSeed) {
  const std::uint32_t seed = 4242;
  std::cout << "seed " << seed << "\n";
  std::mt19937 rng(seed);
  auto u = [&](double lo, double hi) {
    return std::uniform_real_distribution<double>(lo, hi)(rng);
  };
  std::vector<io::CanFrame> out(icd::frames_for(icd::kMaxDetectionsPerFrame));
  icd::ListDecoder dec;
  for (int trial = 0; trial < 300; ++trial) {
    const std::size_t n = rng() % 40;
    std::vector<icd::Detection> in(n);
    for (auto& d : in) {
      d = make(u(0, 167000), u(-90, 90), u(-90, 90), u(-650, 650), u(0, 127), u(-300, 300));
    }
    icd::Header h;
    h.frame_counter = static_cast<std::uint16_t>(trial * 977);
    h.time_ms = static_cast<std::uint32_t>(trial * 50);
    const icd::EncodeResult r = icd::encode(h, in, out);
    ASSERT_EQ(r.encoded, n);
    ASSERT_EQ(r.dropped, 0u);
    icd::FeedStatus last = icd::FeedStatus::kIgnored;
    for (std::size_t i = 0; i < r.frames; ++i)
      last = dec.feed(out[i]);
    ASSERT_EQ(last, icd::FeedStatus::kComplete);
    const icd::DetectionList& l = dec.list();
    ASSERT_EQ(l.count, n);
    ASSERT_EQ(l.header.frame_counter, h.frame_counter);
    for (std::size_t i = 0; i < n; ++i) {
      ASSERT_NEAR(l.detections[i].range_m, in[i].range_m, icd::kRangeScale_m / 2 + 1e-9);
      ASSERT_NEAR(l.detections[i].azimuth_deg, in[i].azimuth_deg, icd::kAngleScale_deg / 2 + 1e-9);
      ASSERT_NEAR(l.detections[i].elevation_deg, in[i].elevation_deg,
                  icd::kAngleScale_deg / 2 + 1e-9);
      ASSERT_NEAR(l.detections[i].radial_velocity_mps, in[i].radial_velocity_mps,
                  icd::kRadialVelocityScale_mps / 2 + 1e-9);
      ASSERT_NEAR(l.detections[i].snr_db, in[i].snr_db, icd::kSnrScale_db / 2 + 1e-9);
      ASSERT_NEAR(l.detections[i].rcs_dbsm, in[i].rcs_dbsm, icd::kRcsScale_dbsm / 2 + 1e-9);
    }
  }
  EXPECT_EQ(dec.malformed(), 0u);
}

TEST(DetectionIcd, OutOfRangeDetectionsAreDroppedAndFlagged) {
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const std::vector<icd::Detection> in = {
      make(100, 0, 0, 0, 20, 0),     // ok
      make(-1, 0, 0, 0, 20, 0),      // negative range
      make(200000, 0, 0, 0, 20, 0),  // beyond 167772.15 m
      make(100, 91, 0, 0, 20, 0),    // azimuth beyond 90 deg
      make(100, 0, 0, 700, 20, 0),   // radial velocity beyond 655.34 m/s
      make(nan, 0, 0, 0, 20, 0),     // NaN
      make(100, 0, 0, 0, 20, 400),   // RCS beyond 327.67 dBsm
      make(300, 0, 0, 0, 200, 0),    // SNR above the field: saturated, kept
  };
  std::vector<io::CanFrame> out(icd::frames_for(in.size()));
  const icd::EncodeResult r = icd::encode({}, in, out);
  EXPECT_EQ(r.encoded, 2u);
  EXPECT_EQ(r.dropped, 6u);
  icd::ListDecoder dec;
  for (std::size_t i = 0; i < r.frames; ++i)
    (void)dec.feed(out[i]);
  EXPECT_EQ(dec.list().header.status & icd::status::kDropped, icd::status::kDropped);
  EXPECT_EQ(dec.list().count, 2u);
  EXPECT_DOUBLE_EQ(dec.list().detections[1].snr_db, 127.5);
}

TEST(DetectionIcd, TooSmallOutputTruncatesAndFlags) {
  const std::vector<icd::Detection> in(5, make(100, 0, 0, 0, 20, 0));
  std::vector<io::CanFrame> out(icd::frames_for(3));
  const icd::EncodeResult r = icd::encode({}, in, out);
  EXPECT_EQ(r.encoded, 3u);
  EXPECT_EQ(r.truncated, 2u);
  EXPECT_EQ(r.frames, 7u);
  EXPECT_EQ(out[0].data[2], 3);  // count
  EXPECT_EQ(out[0].data[3] & icd::status::kTruncated, icd::status::kTruncated);
  std::vector<io::CanFrame> none;
  EXPECT_EQ(icd::encode({}, in, none).frames, 0u);
}

TEST(DetectionIcd, DecoderRejectsCorruptionAndCountsIt) {
  const std::vector<icd::Detection> in(2, make(100, 1, 2, 3, 20, 0));
  std::vector<io::CanFrame> f(icd::frames_for(2));
  icd::Header h;
  h.frame_counter = 7;
  ASSERT_EQ(icd::encode(h, in, f).frames, 5u);
  icd::ListDecoder dec;
  EXPECT_EQ(dec.feed(f[1]), icd::FeedStatus::kOrphan);  // detection before any header
  EXPECT_EQ(dec.feed(f[0]), icd::FeedStatus::kConsumed);
  io::CanFrame short_dlc = f[1];
  short_dlc.len = 7;
  EXPECT_EQ(dec.feed(short_dlc), icd::FeedStatus::kMalformed);
  io::CanFrame wrong_counter = f[1];
  wrong_counter.data[1] = 8;
  EXPECT_EQ(dec.feed(wrong_counter), icd::FeedStatus::kMalformed);
  io::CanFrame bad_index = f[1];
  bad_index.data[0] = 2;  // count is 2: valid indices 0, 1
  EXPECT_EQ(dec.feed(bad_index), icd::FeedStatus::kMalformed);
  EXPECT_EQ(dec.feed(f[1]), icd::FeedStatus::kConsumed);
  EXPECT_EQ(dec.feed(f[1]), icd::FeedStatus::kMalformed);  // duplicate
  EXPECT_EQ(dec.feed(f[2]), icd::FeedStatus::kConsumed);
  EXPECT_EQ(dec.feed(f[0]), icd::FeedStatus::kConsumed);  // new header: previous incomplete
  EXPECT_EQ(dec.incomplete_lists(), 1u);
  for (std::size_t i = 1; i < 5; ++i)
    (void)dec.feed(f[i]);
  EXPECT_EQ(dec.malformed(), 4u);
  EXPECT_EQ(dec.orphans(), 1u);
  io::CanFrame other;
  other.id = 0x123;
  EXPECT_EQ(dec.feed(other), icd::FeedStatus::kIgnored);
}

TEST(DetectionIcd, RandomFramesNeverCrashAtFixedSeed) {
  const std::uint32_t seed = 31337;
  std::cout << "seed " << seed << "\n";
  std::mt19937 rng(seed);
  icd::ListDecoder dec;
  std::size_t complete = 0;
  for (int i = 0; i < 200'000; ++i) {
    io::CanFrame f;
    f.id = 0x708u + static_cast<std::uint32_t>(rng() % 3);
    f.len = static_cast<std::uint8_t>(rng() % 10 == 0 ? rng() % 9 : 8);
    for (std::size_t b = 0; b < 8; ++b)
      f.data[b] = static_cast<std::uint8_t>(rng() % 4 == 0 ? rng() : rng() % 3);
    if (dec.feed(f) == icd::FeedStatus::kComplete) {
      ++complete;
      ASSERT_LE(dec.list().count, icd::kMaxDetectionsPerFrame);
    }
  }
  EXPECT_GT(complete, 0u);
  EXPECT_GT(dec.malformed(), 0u);
}
