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

TEST(DetectionIcd, AnglesBeyondTheIcdRangeAreMalformed) {
  // The encoder never sends |angle| > 90 deg (docs/icd/detections.md): a B frame carrying one,
  // here azimuth raw 12000 = 120 deg (bytes 2-3, little-endian), is malformed.
  const std::vector<icd::Detection> in(1, make(100, 1, 2, 3, 20, 0));
  std::vector<io::CanFrame> f(icd::frames_for(1));
  ASSERT_EQ(icd::encode({}, in, f).frames, 3u);
  icd::ListDecoder dec;
  EXPECT_EQ(dec.feed(f[0]), icd::FeedStatus::kConsumed);
  EXPECT_EQ(dec.feed(f[1]), icd::FeedStatus::kConsumed);
  io::CanFrame wide = f[2];
  wide.data[2] = 12000 & 0xFF;
  wide.data[3] = 12000 >> 8;
  EXPECT_EQ(dec.feed(wide), icd::FeedStatus::kMalformed);
  EXPECT_EQ(dec.feed(f[2]), icd::FeedStatus::kComplete);
  EXPECT_EQ(dec.malformed(), 1u);
  // The same on CAN FD: elevation of slot 0 in the header frame (bit 64 of the slot at byte 8,
  // i.e. bytes 16-17) set to -9500 = -95 deg drops the list.
  std::vector<io::CanFrame> g(icd::frames_for_fd(1));
  ASSERT_EQ(icd::encode_fd({}, in, g).frames, 1u);
  io::CanFrame low = g[0];
  const auto raw = static_cast<std::uint16_t>(-9500);
  low.data[16] = raw & 0xFF;
  low.data[17] = raw >> 8;
  icd::ListDecoder fd;
  EXPECT_EQ(fd.feed(low), icd::FeedStatus::kMalformed);
  EXPECT_EQ(fd.feed(g[0]), icd::FeedStatus::kComplete);
  EXPECT_NEAR(fd.list().detections[0].elevation_deg, 2.0, 0.005);
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

// ---- CAN FD (docs/icd/detections.md, "CAN FD") --------------------------------------------

namespace {
// The worked example of docs/icd/detections.md.
icd::Detection fd_example() {
  icd::Detection d = make(1234.56, -3.21, 1.5, -55.5, 25.5, 20.25);
  d.range_std_m = 2.5;
  d.radial_velocity_std_mps = 0.37;
  d.azimuth_std_deg = 0.1;
  d.elevation_std_deg = 1.234;
  d.range_ambiguous = true;
  d.velocity_ambiguous = false;
  return d;
}
// Its 20-byte slot, packed by hand. Classic signals as in DetectionIcdByHand.OneDetection:
//   range 40 E2 01 | vr 29 F5 | SNR 33 | az BF FE | el 96 00 | RCS E9 07.
// Range sigma 2.5 m / 0.01 = 250 = 0x00FA at bits 96-111 -> bytes 12-13 = FA 00.
// Velocity sigma 0.37 / 0.01 = 37 = 0x025 (12 bits) at bits 112-123 -> byte 14 = 0x25, low
//   nibble of byte 15 = 0x0.
// Azimuth sigma 0.1 / 0.002 = 50 = 0x0032 (14 bits) at bits 124-137: its low 4 bits (0x2) are
//   the high nibble of byte 15 -> byte 15 = 0x20; its next 8 bits (0x03) are byte 16; its top 2
//   bits (0) are bits 0-1 of byte 17.
// Elevation sigma 1.234 / 0.002 = 617 = 0x269 (14 bits) at bits 138-151: low 6 bits 0x29 are
//   bits 2-7 of byte 17 -> 0x29 << 2 = 0xA4; the next 8 bits 617 >> 6 = 9 are byte 18 = 0x09.
// Range ambiguous (bit 152) = 1, velocity ambiguous (bit 153) = 0 -> byte 19 = 0x01.
const std::vector<std::uint8_t> kFdExampleSlot = {0x40, 0xE2, 0x01, 0x29, 0xF5, 0x33, 0xBF,
                                                  0xFE, 0x96, 0x00, 0xE9, 0x07, 0xFA, 0x00,
                                                  0x25, 0x20, 0x03, 0xA4, 0x09, 0x01};

std::vector<std::uint8_t> slice(const io::CanFrame& f, std::size_t from, std::size_t n) {
  return std::vector<std::uint8_t>(f.data.begin() + static_cast<std::ptrdiff_t>(from),
                                   f.data.begin() + static_cast<std::ptrdiff_t>(from + n));
}

void expect_fd_example(const icd::Detection& d) {
  EXPECT_NEAR(d.range_m, 1234.56, 1e-9);
  EXPECT_NEAR(d.azimuth_deg, -3.21, 1e-9);
  EXPECT_NEAR(d.elevation_deg, 1.5, 1e-9);
  EXPECT_NEAR(d.radial_velocity_mps, -55.5, 1e-9);
  EXPECT_NEAR(d.snr_db, 25.5, 1e-9);
  EXPECT_NEAR(d.rcs_dbsm, 20.25, 1e-9);
  EXPECT_NEAR(d.range_std_m, 2.5, 1e-9);
  EXPECT_NEAR(d.radial_velocity_std_mps, 0.37, 1e-9);
  EXPECT_NEAR(d.azimuth_std_deg, 0.1, 1e-9);
  EXPECT_NEAR(d.elevation_std_deg, 1.234, 1e-9);
  EXPECT_TRUE(d.range_ambiguous);
  EXPECT_FALSE(d.velocity_ambiguous);
}
}  // namespace

TEST(DetectionIcdFd, FramesForClosedForm) {
  // 1 header frame with 2 slots, then 3 slots per continuation.
  EXPECT_EQ(icd::frames_for_fd(0), 1u);
  EXPECT_EQ(icd::frames_for_fd(2), 1u);
  EXPECT_EQ(icd::frames_for_fd(3), 2u);
  EXPECT_EQ(icd::frames_for_fd(5), 2u);
  EXPECT_EQ(icd::frames_for_fd(6), 3u);
  EXPECT_EQ(icd::frames_for_fd(64), 22u);
  EXPECT_EQ(icd::frames_for_fd(255), 86u);
}

TEST(DetectionIcdFdByHand, HeaderFrameWithOneDetection) {
  // Header as in the classic example: 34 12 | count 01 | status 02 | 88 13 00 00; slot 0 at
  // bytes 8-27, slot 1 (bytes 28-47) zero. 48 bytes, FD, BRS (candump flag 1).
  icd::Header h;
  h.frame_counter = 0x1234;
  h.status = icd::status::kOverrun;
  h.time_ms = 5000;
  const icd::Detection d = fd_example();
  std::vector<io::CanFrame> out(2);
  const icd::EncodeResult r = icd::encode_fd(h, std::span(&d, 1), out);
  ASSERT_EQ(r.frames, 1u);
  EXPECT_EQ(r.encoded, 1u);
  const io::CanFrame& f = out[0];
  EXPECT_EQ(f.id, 0x70Bu);
  EXPECT_FALSE(f.extended);
  EXPECT_TRUE(f.fd);
  EXPECT_EQ(f.fd_flags, 1);
  ASSERT_EQ(f.len, 48);
  EXPECT_EQ(slice(f, 0, 8),
            (std::vector<std::uint8_t>{0x34, 0x12, 0x01, 0x02, 0x88, 0x13, 0x00, 0x00}));
  EXPECT_EQ(slice(f, 8, 20), kFdExampleSlot);
  EXPECT_EQ(slice(f, 28, 20), std::vector<std::uint8_t>(20, 0));

  icd::ListDecoder dec;
  EXPECT_EQ(dec.feed(f), icd::FeedStatus::kComplete);
  const icd::DetectionList& l = dec.list();
  EXPECT_TRUE(l.fd);
  EXPECT_EQ(l.header.frame_counter, 0x1234);
  EXPECT_EQ(l.header.status, icd::status::kOverrun);
  EXPECT_EQ(l.header.time_ms, 5000u);
  ASSERT_EQ(l.count, 1u);
  expect_fd_example(l.detections[0]);
}

TEST(DetectionIcdFdByHand, ContinuationFrames) {
  // Six detections: header (0, 1), continuation FirstIndex 2 (2, 3, 4), continuation
  // FirstIndex 5 (5 only: SlotCount 1, slots 1 and 2 zero). Detection 5 is the worked example.
  std::vector<icd::Detection> in(6, make(10, 0, 0, 0, 0, 0));
  for (std::size_t i = 0; i < 5; ++i)
    in[i].range_m = 100.0 * static_cast<double>(i + 1);
  in[5] = fd_example();
  icd::Header h;
  h.frame_counter = 0x1234;
  std::vector<io::CanFrame> out(icd::frames_for_fd(6));
  const icd::EncodeResult r = icd::encode_fd(h, in, out);
  ASSERT_EQ(r.frames, 3u);
  EXPECT_EQ(out[0].data[2], 6);  // DetectionCount
  for (std::size_t k = 1; k < 3; ++k) {
    EXPECT_EQ(out[k].id, 0x70Cu);
    EXPECT_TRUE(out[k].fd);
    EXPECT_EQ(out[k].fd_flags, 1);
    EXPECT_EQ(out[k].len, 64);
  }
  EXPECT_EQ(slice(out[1], 0, 4), (std::vector<std::uint8_t>{0x34, 0x12, 0x02, 0x03}));
  EXPECT_EQ(slice(out[2], 0, 4), (std::vector<std::uint8_t>{0x34, 0x12, 0x05, 0x01}));
  EXPECT_EQ(slice(out[2], 4, 20), kFdExampleSlot);
  EXPECT_EQ(slice(out[2], 24, 40), std::vector<std::uint8_t>(40, 0));
  // Detection 3 sits in slot 1 of the first continuation (bytes 24-43): range 400 m / 0.01 =
  // 40000 = 0x009C40 -> 40 9C 00.
  EXPECT_EQ(slice(out[1], 24, 3), (std::vector<std::uint8_t>{0x40, 0x9C, 0x00}));

  icd::ListDecoder dec;
  EXPECT_EQ(dec.feed(out[0]), icd::FeedStatus::kConsumed);
  EXPECT_EQ(dec.feed(out[2]), icd::FeedStatus::kConsumed);  // continuations in any order
  EXPECT_EQ(dec.feed(out[1]), icd::FeedStatus::kComplete);
  ASSERT_EQ(dec.list().count, 6u);
  for (std::size_t i = 0; i < 5; ++i)
    EXPECT_NEAR(dec.list().detections[i].range_m, 100.0 * static_cast<double>(i + 1), 1e-9);
  expect_fd_example(dec.list().detections[5]);
  EXPECT_EQ(dec.malformed(), 0u);
}

TEST(DetectionIcdFd, RoundTripWithinHalfAStepAtFixedSeed) {
  const std::uint32_t seed = 6061;
  std::cout << "seed " << seed << "\n";
  std::mt19937 rng(seed);
  auto u = [&](double lo, double hi) {
    return std::uniform_real_distribution<double>(lo, hi)(rng);
  };
  std::vector<io::CanFrame> out(icd::frames_for_fd(icd::kMaxDetectionsPerFrame));
  icd::ListDecoder dec;
  for (int trial = 0; trial < 300; ++trial) {
    const std::size_t n = trial == 0 ? icd::kMaxDetectionsPerFrame : rng() % 60;
    std::vector<icd::Detection> in(n);
    for (auto& d : in) {
      d = make(u(0, 167000), u(-90, 90), u(-90, 90), u(-650, 650), u(0, 127), u(-300, 300));
      d.range_std_m = u(0, 700);  // past 655.35: saturates
      d.radial_velocity_std_mps = u(0, 45);
      d.azimuth_std_deg = u(0, 35);
      d.elevation_std_deg = u(0, 35);
      d.range_ambiguous = rng() % 2 == 0;
      d.velocity_ambiguous = rng() % 2 == 0;
    }
    icd::Header h;
    h.frame_counter = static_cast<std::uint16_t>(trial * 977);
    h.time_ms = static_cast<std::uint32_t>(trial * 50);
    const icd::EncodeResult r = icd::encode_fd(h, in, out);
    ASSERT_EQ(r.encoded, n);
    ASSERT_EQ(r.dropped, 0u);
    ASSERT_EQ(r.frames, icd::frames_for_fd(n));
    icd::FeedStatus last = icd::FeedStatus::kIgnored;
    for (std::size_t i = 0; i < r.frames; ++i)
      last = dec.feed(out[i]);
    ASSERT_EQ(last, icd::FeedStatus::kComplete);
    const icd::DetectionList& l = dec.list();
    ASSERT_TRUE(l.fd);
    ASSERT_EQ(l.count, n);
    ASSERT_EQ(l.header.frame_counter, h.frame_counter);
    for (std::size_t i = 0; i < n; ++i) {
      const icd::Detection& g = l.detections[i];
      const icd::Detection& w = in[i];
      ASSERT_NEAR(g.range_m, w.range_m, icd::kRangeScale_m / 2 + 1e-9);
      ASSERT_NEAR(g.azimuth_deg, w.azimuth_deg, icd::kAngleScale_deg / 2 + 1e-9);
      ASSERT_NEAR(g.elevation_deg, w.elevation_deg, icd::kAngleScale_deg / 2 + 1e-9);
      ASSERT_NEAR(g.radial_velocity_mps, w.radial_velocity_mps,
                  icd::kRadialVelocityScale_mps / 2 + 1e-9);
      ASSERT_NEAR(g.snr_db, w.snr_db, icd::kSnrScale_db / 2 + 1e-9);
      ASSERT_NEAR(g.rcs_dbsm, w.rcs_dbsm, icd::kRcsScale_dbsm / 2 + 1e-9);
      // Saturation at the documented maxima: 655.35 m, 40.95 m/s, 32.766 deg.
      ASSERT_NEAR(g.range_std_m, std::min(w.range_std_m, 655.35), 0.01 / 2 + 1e-9);
      ASSERT_NEAR(g.radial_velocity_std_mps, std::min(w.radial_velocity_std_mps, 40.95),
                  0.01 / 2 + 1e-9);
      ASSERT_NEAR(g.azimuth_std_deg, std::min(w.azimuth_std_deg, 32.766), 0.002 / 2 + 1e-9);
      ASSERT_NEAR(g.elevation_std_deg, std::min(w.elevation_std_deg, 32.766), 0.002 / 2 + 1e-9);
      ASSERT_EQ(g.range_ambiguous, w.range_ambiguous);
      ASSERT_EQ(g.velocity_ambiguous, w.velocity_ambiguous);
    }
  }
  EXPECT_EQ(dec.malformed(), 0u);
  EXPECT_EQ(dec.orphans(), 0u);
  EXPECT_EQ(dec.incomplete_lists(), 0u);
}

TEST(DetectionIcdFd, AccuraciesAreValidatedOnFdOnly) {
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const double inf = std::numeric_limits<double>::infinity();
  std::vector<icd::Detection> in(4, make(100, 0, 0, 0, 20, 0));
  in[1].azimuth_std_deg = nan;    // dropped
  in[2].range_std_m = -0.5;       // dropped
  in[3].elevation_std_deg = inf;  // saturates: 0x3FFF x 0.002 = 32.766 deg
  std::vector<io::CanFrame> out(icd::frames_for_fd(4));
  const icd::EncodeResult r = icd::encode_fd({}, in, out);
  EXPECT_EQ(r.encoded, 2u);
  EXPECT_EQ(r.dropped, 2u);
  EXPECT_EQ(out[0].data[3] & icd::status::kDropped, icd::status::kDropped);
  icd::ListDecoder dec;
  ASSERT_EQ(dec.feed(out[0]), icd::FeedStatus::kComplete);
  EXPECT_DOUBLE_EQ(dec.list().detections[1].elevation_std_deg, 16383 * 0.002);

  // The classic encoder ignores the FD-only fields: the same frames as without them.
  std::vector<io::CanFrame> classic(icd::frames_for(4)), plain(icd::frames_for(4));
  const std::vector<icd::Detection> bare(4, make(100, 0, 0, 0, 20, 0));
  in[0].range_ambiguous = in[0].velocity_ambiguous = true;
  ASSERT_EQ(icd::encode({}, in, classic).encoded, 4u);
  ASSERT_EQ(icd::encode({}, bare, plain).encoded, 4u);
  for (std::size_t i = 0; i < classic.size(); ++i)
    EXPECT_EQ(bytes(classic[i]), bytes(plain[i])) << i;
  for (std::size_t i = 0; i < classic.size(); ++i)
    (void)dec.feed(classic[i]);
  EXPECT_FALSE(dec.list().fd);
  EXPECT_EQ(dec.list().detections[0].range_std_m, 0.0);
  EXPECT_FALSE(dec.list().detections[0].range_ambiguous);
}

TEST(DetectionIcdFd, TooSmallOutputTruncatesAndFlags) {
  const std::vector<icd::Detection> in(8, make(100, 0, 0, 0, 20, 0));
  std::vector<io::CanFrame> out(2);  // room for 2 + 3 detections
  const icd::EncodeResult r = icd::encode_fd({}, in, out);
  EXPECT_EQ(r.encoded, 5u);
  EXPECT_EQ(r.truncated, 3u);
  EXPECT_EQ(r.frames, 2u);
  EXPECT_EQ(out[0].data[2], 5);
  EXPECT_EQ(out[0].data[3] & icd::status::kTruncated, icd::status::kTruncated);
  EXPECT_EQ(out[1].data[3], 3);  // SlotCount
  std::vector<io::CanFrame> none;
  EXPECT_EQ(icd::encode_fd({}, in, none).frames, 0u);
  EXPECT_EQ(icd::encode_fd({}, in, none).truncated, 8u);
  // An empty list is one header frame with DetectionCount 0.
  const icd::EncodeResult e = icd::encode_fd({}, {}, out);
  EXPECT_EQ(e.frames, 1u);
  icd::ListDecoder dec;
  EXPECT_EQ(dec.feed(out[0]), icd::FeedStatus::kComplete);
  EXPECT_EQ(dec.list().count, 0u);
}

TEST(DetectionIcdFd, DecoderRejectsCorruptionAndCountsIt) {
  const std::vector<icd::Detection> in(9, make(100, 1, 2, 3, 20, 0));
  std::vector<io::CanFrame> f(icd::frames_for_fd(9));
  icd::Header h;
  h.frame_counter = 0x0107;
  ASSERT_EQ(icd::encode_fd(h, in, f).frames, 4u);  // header (0-1), 2-4, 5-7, 8
  icd::ListDecoder dec;
  EXPECT_EQ(dec.feed(f[1]), icd::FeedStatus::kOrphan);  // continuation before any header
  io::CanFrame short_header = f[0];
  short_header.len = 32;
  EXPECT_EQ(dec.feed(short_header), icd::FeedStatus::kMalformed);
  EXPECT_EQ(dec.feed(f[0]), icd::FeedStatus::kConsumed);
  io::CanFrame short_len = f[1];
  short_len.len = 48;
  EXPECT_EQ(dec.feed(short_len), icd::FeedStatus::kMalformed);
  io::CanFrame not_fd = f[1];
  not_fd.fd = false;
  EXPECT_EQ(dec.feed(not_fd), icd::FeedStatus::kMalformed);
  io::CanFrame wrong_counter = f[1];
  wrong_counter.data[1] = 0x02;  // 0x0207: the low byte alone matches, the full counter does not
  EXPECT_EQ(dec.feed(wrong_counter), icd::FeedStatus::kMalformed);
  io::CanFrame bad_index = f[1];
  bad_index.data[2] = 3;  // not 2 + 3k
  EXPECT_EQ(dec.feed(bad_index), icd::FeedStatus::kMalformed);
  bad_index.data[2] = 11;  // 2 + 3 x 3, but the count is 9
  EXPECT_EQ(dec.feed(bad_index), icd::FeedStatus::kMalformed);
  io::CanFrame bad_slots = f[3];
  bad_slots.data[3] = 3;  // only detection 8 is left
  EXPECT_EQ(dec.feed(bad_slots), icd::FeedStatus::kMalformed);
  EXPECT_EQ(dec.feed(f[1]), icd::FeedStatus::kConsumed);
  EXPECT_EQ(dec.feed(f[1]), icd::FeedStatus::kMalformed);  // duplicate
  // A classic detection frame while an FD list is in progress has no header of its kind.
  std::vector<io::CanFrame> classic(icd::frames_for(1));
  ASSERT_EQ(icd::encode(h, std::span(in.data(), 1), classic).frames, 3u);
  EXPECT_EQ(dec.feed(classic[1]), icd::FeedStatus::kOrphan);
  EXPECT_EQ(dec.feed(f[2]), icd::FeedStatus::kConsumed);
  EXPECT_EQ(dec.feed(f[3]), icd::FeedStatus::kComplete);
  EXPECT_EQ(dec.list().count, 9u);
  // A classic header starts a classic list: an FD continuation is then an orphan, and an FD
  // header abandons the incomplete classic list.
  EXPECT_EQ(dec.feed(classic[0]), icd::FeedStatus::kConsumed);
  EXPECT_EQ(dec.feed(f[1]), icd::FeedStatus::kOrphan);
  EXPECT_EQ(dec.feed(f[0]), icd::FeedStatus::kConsumed);
  EXPECT_EQ(dec.incomplete_lists(), 1u);
  EXPECT_EQ(dec.malformed(), 8u);
  EXPECT_EQ(dec.orphans(), 3u);
}

TEST(DetectionIcdFd, RandomFramesNeverCrashAtFixedSeed) {
  const std::uint32_t seed = 2718;
  std::cout << "seed " << seed << "\n";
  std::mt19937 rng(seed);
  icd::ListDecoder dec;
  std::size_t complete = 0;
  const std::uint8_t lengths[] = {0, 8, 12, 32, 48, 64};
  for (int i = 0; i < 100'000; ++i) {
    io::CanFrame f;
    f.id = rng() % 4 == 0 ? 0x70Bu : 0x70Cu;
    f.fd = rng() % 20 != 0;
    f.len = rng() % 8 == 0 ? lengths[rng() % std::size(lengths)] : (f.id == 0x70B ? 48 : 64);
    for (std::size_t b = 0; b < f.len; ++b)
      f.data[b] = static_cast<std::uint8_t>(rng() % 4 == 0 ? rng() : rng() % 6);
    if (dec.feed(f) == icd::FeedStatus::kComplete) {
      ++complete;
      ASSERT_LE(dec.list().count, icd::kMaxDetectionsPerFrame);
    }
  }
  EXPECT_GT(complete, 0u);
  EXPECT_GT(dec.malformed(), 0u);
}
