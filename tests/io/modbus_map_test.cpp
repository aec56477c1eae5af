// Modbus register codecs and maps (io/modbus_map.hpp, docs/icd/modbus.md). Bit patterns are
// IEEE-754 (binary32/binary64) values worked out by hand; register images are built from the
// map in docs/icd/modbus.md, not from the encoder.

#include "io/modbus_map.hpp"

#include <gtest/gtest.h>

#include <bit>
#include <cmath>
#include <cstdint>
#include <limits>
#include <numbers>
#include <random>
#include <vector>

#include "common/units.hpp"

namespace {

using namespace radar_emu::io;
using namespace radar_emu::io::modbus;
namespace common = radar_emu::common;
using canas::Field;
using R2 = std::array<std::uint16_t, 2>;
using R4 = std::array<std::uint16_t, 4>;

constexpr std::uint32_t kSeed = 20240601;

// ---- Value codecs ---------------------------------------------------------------------------

TEST(ModbusCodec, Float32ReferenceVectorBothWordOrders) {
  // buses.md / libmodbus issue: 123456.0f = 0x47F12000 (sign 0, exponent 143, mantissa 0x712000).
  EXPECT_EQ(encode_f32(123456.0f, WordOrder::kABCD), (R2{0x47F1, 0x2000}));
  EXPECT_EQ(encode_f32(123456.0f, WordOrder::kCDAB), (R2{0x2000, 0x47F1}));
  EXPECT_EQ(decode_f32({0x47F1, 0x2000}, WordOrder::kABCD), 123456.0f);
  EXPECT_EQ(decode_f32({0x2000, 0x47F1}, WordOrder::kCDAB), 123456.0f);
  // What libmodbus 3.1.6's broken modbus_set_float_abcd writes is not 123456.
  EXPECT_NE(decode_f32({0xF147, 0x0020}, WordOrder::kABCD), 123456.0f);
}

TEST(ModbusCodec, Float32HandComputedPatterns) {
  EXPECT_EQ(encode_f32(1.0f), (R2{0x3F80, 0x0000}));   // exponent 127
  EXPECT_EQ(encode_f32(-2.5f), (R2{0xC020, 0x0000}));  // -1.25 * 2^1
  EXPECT_EQ(encode_f32(0.1f), (R2{0x3DCC, 0xCCCD}));   // mantissa rounded up
  EXPECT_EQ(encode_f32(1000.0f), (R2{0x447A, 0x0000}));
  EXPECT_EQ(encode_f32(std::numeric_limits<float>::infinity()), (R2{0x7F80, 0x0000}));
  EXPECT_EQ(encode_f32(-0.0f), (R2{0x8000, 0x0000}));
  EXPECT_EQ(decode_f32({0xC1C8, 0x0000}), -25.0f);
  EXPECT_EQ(decode_f32({0x0000, 0xC1C8}, WordOrder::kCDAB), -25.0f);
}

TEST(ModbusCodec, Float32NaNKeepsItsBitPattern) {
  EXPECT_EQ(encode_f32(std::numeric_limits<float>::quiet_NaN()), (R2{0x7FC0, 0x0000}));
  EXPECT_TRUE(std::isnan(decode_f32({0x7FC0, 0x0000})));
  EXPECT_TRUE(std::isnan(decode_f32({0xFFC0, 0x0001})));
  EXPECT_TRUE(std::isnan(decode_f32({0x0001, 0x7F80}, WordOrder::kCDAB)));  // 0x7F800001
}

TEST(ModbusCodec, Float64HandComputedPatterns) {
  // 123456.0 = 1.883789... * 2^16: exponent 1023 + 16 = 0x40F, mantissa 0xE24 << 40.
  EXPECT_EQ(encode_f64(123456.0), (R4{0x40FE, 0x2400, 0x0000, 0x0000}));
  EXPECT_EQ(encode_f64(123456.0, WordOrder::kCDAB), (R4{0x0000, 0x0000, 0x2400, 0x40FE}));
  EXPECT_EQ(encode_f64(1.0), (R4{0x3FF0, 0x0000, 0x0000, 0x0000}));
  EXPECT_EQ(encode_f64(-0.1), (R4{0xBFB9, 0x9999, 0x9999, 0x999A}));
  EXPECT_EQ(decode_f64({0x4046, 0x8000, 0x0000, 0x0000}), 45.0);
  EXPECT_EQ(decode_f64({0x0000, 0x0000, 0x0000, 0xBFE0}, WordOrder::kCDAB), -0.5);
  EXPECT_TRUE(std::isnan(decode_f64({0x7FF8, 0, 0, 0})));
}

TEST(ModbusCodec, Int32HighWordFirst) {
  EXPECT_EQ(encode_u32(0x12345678u), (R2{0x1234, 0x5678}));
  EXPECT_EQ(encode_u32(0x12345678u, WordOrder::kCDAB), (R2{0x5678, 0x1234}));
  EXPECT_EQ(encode_i32(-2), (R2{0xFFFF, 0xFFFE}));
  EXPECT_EQ(encode_i32(std::numeric_limits<std::int32_t>::min()), (R2{0x8000, 0x0000}));
  EXPECT_EQ(decode_i32({0xFFFF, 0xFFFE}), -2);
  EXPECT_EQ(decode_i32({0xFFFE, 0xFFFF}, WordOrder::kCDAB), -2);
  EXPECT_EQ(decode_u32({0x0001, 0x2345}), 0x12345u);
}

TEST(ModbusCodec, ScaledIntegers) {
  EXPECT_EQ(to_scaled_i32(47.1234567, 1e-7), 471234567);  // 0x1C167807
  EXPECT_EQ(encode_i32(*to_scaled_i32(47.1234567, 1e-7)), (R2{0x1C16, 0x7807}));
  EXPECT_EQ(to_scaled_i32(-122.4194155, 1e-7), -1224194155);  // 0xB7084795
  EXPECT_NEAR(from_scaled_i32(-1224194155, 1e-7), -122.4194155, 1e-12);
  // Rounding half away from zero.
  EXPECT_EQ(to_scaled_i16(2.5, 1.0), 3);
  EXPECT_EQ(to_scaled_i16(-2.5, 1.0), -3);
  EXPECT_EQ(to_scaled_u16(655.35, 0.01), 65535);
  // Outside the type, the "no data" code, NaN and bad scales are refused.
  EXPECT_FALSE(to_scaled_i16(327.68, 0.01));
  EXPECT_FALSE(to_scaled_i16(-327.68, 0.01));  // would be INT16_MIN, the no-data code
  EXPECT_EQ(to_scaled_i16(-327.67, 0.01), -32767);
  EXPECT_FALSE(to_scaled_u16(-0.01, 0.01));
  EXPECT_FALSE(to_scaled_i32(std::nan(""), 1.0));
  EXPECT_FALSE(to_scaled_i32(std::numeric_limits<double>::infinity(), 1.0));
  EXPECT_FALSE(to_scaled_i32(1.0, 0.0));
  EXPECT_FALSE(to_scaled_i32(1.0, -1.0));
  EXPECT_FALSE(to_scaled_i32(215.0, 1e-7));  // 2.15e9 > INT32_MAX
  EXPECT_TRUE(std::isnan(from_scaled_i32(kScaledI32NoData, 1e-7)));
  EXPECT_TRUE(std::isnan(from_scaled_i16(kScaledI16NoData, 0.01)));
  EXPECT_DOUBLE_EQ(from_scaled_i16(-100, 0.01), -1.0);
  EXPECT_DOUBLE_EQ(from_scaled_u16(65535, 0.01), 655.35);
}

TEST(ModbusCodec, BoundedAccessRejectsShortImages) {
  std::vector<std::uint16_t> regs(4, 0xAAAA);
  EXPECT_FALSE(put_f32(regs, 3, 1.0f, WordOrder::kABCD));
  EXPECT_FALSE(put_f64(regs, 1, 1.0, WordOrder::kABCD));
  EXPECT_FALSE(put_u16(regs, 4, 1));
  EXPECT_FALSE(put_u32(regs, std::numeric_limits<std::size_t>::max(), 1, WordOrder::kABCD));
  EXPECT_EQ(regs, std::vector<std::uint16_t>(4, 0xAAAA));  // nothing written
  EXPECT_TRUE(put_f32(regs, 2, 1.0f, WordOrder::kABCD));
  EXPECT_EQ(regs[2], 0x3F80);
  EXPECT_EQ(regs[3], 0x0000);
  const std::span<const std::uint16_t> c(regs);
  EXPECT_EQ(get_f32(c, 2, WordOrder::kABCD), 1.0f);
  EXPECT_FALSE(get_f32(c, 3, WordOrder::kABCD));
  EXPECT_FALSE(get_f64(c, 1, WordOrder::kABCD));
  EXPECT_FALSE(get_u16(c, 4));
  EXPECT_FALSE(get_i32(c, std::numeric_limits<std::size_t>::max() - 1, WordOrder::kABCD));
  EXPECT_FALSE(get_u32(std::span<const std::uint16_t>(), 0, WordOrder::kABCD));
}

TEST(ModbusCodec, RandomRoundTrips) {
  std::printf("seed %u\n", kSeed);
  std::mt19937_64 rng(kSeed);
  std::uniform_int_distribution<std::uint32_t> u32;
  std::uniform_int_distribution<std::uint64_t> u64;
  std::uniform_real_distribution<double> phys(-2100.0, 2100.0);
  for (int i = 0; i < 20000; ++i) {
    const WordOrder order = (i % 2 == 0) ? WordOrder::kABCD : WordOrder::kCDAB;
    const std::uint32_t bits32 = u32(rng);
    const auto r2 = encode_u32(bits32, order);
    // The registers are the value's bytes, high word first (ABCD) or swapped (CDAB).
    const R2 want = order == WordOrder::kABCD ? R2{static_cast<std::uint16_t>(bits32 >> 16),
                                                   static_cast<std::uint16_t>(bits32 & 0xFFFF)}
                                              : R2{static_cast<std::uint16_t>(bits32 & 0xFFFF),
                                                   static_cast<std::uint16_t>(bits32 >> 16)};
    ASSERT_EQ(r2, want);
    const float f = std::bit_cast<float>(bits32);
    if (!std::isnan(f)) {
      ASSERT_EQ(std::bit_cast<std::uint32_t>(decode_f32(encode_f32(f, order), order)), bits32);
    }
    const std::uint64_t bits64 = u64(rng);
    const double d = std::bit_cast<double>(bits64);
    if (!std::isnan(d)) {
      ASSERT_EQ(std::bit_cast<std::uint64_t>(decode_f64(encode_f64(d, order), order)), bits64);
    }
    const double v = phys(rng);
    const auto raw = to_scaled_i32(v, 1e-6);
    ASSERT_TRUE(raw);
    ASSERT_LE(std::abs(from_scaled_i32(decode_i32(encode_i32(*raw, order), order), 1e-6) - v),
              0.5e-6 * (1 + 1e-9));
  }
}

// ---- Navigation map -------------------------------------------------------------------------

TEST(ModbusNavMap, LayoutMatchesTheIcd) {
  const NavLayout f = nav_layout(NavMapConfig::Encoding::kFloat32);
  EXPECT_EQ(f.update_counter, 0u);
  EXPECT_EQ(f.status, 1u);
  EXPECT_EQ(f.time_ms, 2u);
  EXPECT_EQ(f.latitude, 4u);
  EXPECT_EQ(f.longitude, 8u);
  EXPECT_EQ(f.height, 12u);
  EXPECT_EQ(f.true_heading, 14u);
  EXPECT_EQ(f.pitch, 16u);
  EXPECT_EQ(f.roll, 18u);
  EXPECT_EQ(f.vel_east, 20u);
  EXPECT_EQ(f.vel_north, 22u);
  EXPECT_EQ(f.vel_up, 24u);
  EXPECT_EQ(f.count, 26u);
  const NavLayout s = nav_layout(NavMapConfig::Encoding::kScaledInt);
  EXPECT_EQ(s.latitude, 4u);
  EXPECT_EQ(s.longitude, 6u);
  EXPECT_EQ(s.height, 8u);
  EXPECT_EQ(s.true_heading, 10u);
  EXPECT_EQ(s.vel_up, 20u);
  EXPECT_EQ(s.count, 22u);
}

// docs/icd/modbus.md, float encoding, ABCD: counter 1, all valid, t = 0x12345 ms, lat 45 deg,
// lon -0.5 deg, height 100 m, heading 270 deg, pitch 2.5 deg, roll -10 deg, velocity
// (50, -25, 1) m/s.
std::vector<std::uint16_t> hand_image_float_abcd() {
  return {0x0001, 0x0007, 0x0001, 0x2345,                  // counter, status, time
          0x4046, 0x8000, 0x0000, 0x0000,                  // latitude 45.0 (f64)
          0xBFE0, 0x0000, 0x0000, 0x0000,                  // longitude -0.5 (f64)
          0x42C8, 0x0000, 0x4387, 0x0000, 0x4020, 0x0000,  // height, heading, pitch
          0xC120, 0x0000, 0x4248, 0x0000, 0xC1C8, 0x0000,  // roll, v_east, v_north
          0x3F80, 0x0000};                                 // v_up
}

void expect_hand_state(const canas::OwnshipState& s) {
  EXPECT_DOUBLE_EQ(s[Field::kLatitude].value, common::radians(45.0));
  EXPECT_DOUBLE_EQ(s[Field::kLongitude].value, common::radians(-0.5));
  EXPECT_DOUBLE_EQ(s[Field::kHeight].value, 100.0);
  EXPECT_DOUBLE_EQ(s[Field::kTrueHeading].value, common::radians(270.0));
  EXPECT_DOUBLE_EQ(s[Field::kPitch].value, common::radians(2.5));
  EXPECT_DOUBLE_EQ(s[Field::kRoll].value, common::radians(-10.0));
  EXPECT_DOUBLE_EQ(s[Field::kVelEast].value, 50.0);
  EXPECT_DOUBLE_EQ(s[Field::kVelNorth].value, -25.0);
  EXPECT_DOUBLE_EQ(s[Field::kVelUp].value, 1.0);
}

TEST(ModbusNavMap, DecodesAHandBuiltFloatImage) {
  NavDecoder dec;
  const auto img = hand_image_float_abcd();
  ASSERT_EQ(dec.decode(img, 1000), NavDecodeStatus::kAccepted);
  expect_hand_state(dec.state());
  EXPECT_EQ(dec.last_update_counter(), 1);
  EXPECT_EQ(dec.last_status(), nav_status::kAllValid);
  EXPECT_EQ(dec.last_sender_time_ms(), 0x12345u);
  for (std::size_t i = 0; i < canas::kFieldCount; ++i) {
    EXPECT_TRUE(dec.state().fields[i].received);
    EXPECT_EQ(dec.state().fields[i].updated_ns, 1000);
  }
  EXPECT_EQ(dec.counters().fields_accepted, 9u);
}

TEST(ModbusNavMap, DecodesAHandBuiltWordSwappedImage) {
  // The same state, CDAB: each 32-bit value's two registers swapped, each f64's four reversed.
  const std::vector<std::uint16_t> img = {0x0001, 0x0007, 0x2345, 0x0001, 0x0000, 0x0000, 0x8000,
                                          0x4046, 0x0000, 0x0000, 0x0000, 0xBFE0, 0x0000, 0x42C8,
                                          0x0000, 0x4387, 0x0000, 0x4020, 0x0000, 0xC120, 0x0000,
                                          0x4248, 0x0000, 0xC1C8, 0x0000, 0x3F80};
  NavDecoder dec({.base_address = 0, .order = WordOrder::kCDAB});
  ASSERT_EQ(dec.decode(img, 5), NavDecodeStatus::kAccepted);
  expect_hand_state(dec.state());
  EXPECT_EQ(dec.last_sender_time_ms(), 0x12345u);
}

TEST(ModbusNavMap, DecodesAHandBuiltScaledImage) {
  // lat 47.1234567 deg, lon -122.4194155 deg (1e-7 deg), height 1234.567 m (mm), heading
  // 90 deg, pitch -2.5 deg, roll 0 (1e-6 deg), velocity (12.5, -1.5, 0) m/s (1e-4 m/s).
  const std::vector<std::uint16_t> img = {
      0x0009, 0x0007, 0x0000, 0x0010,  // counter 9, all valid, 16 ms
      0x1C16, 0x7807, 0xB708, 0x4795, 0x0012, 0xD687, 0x055D, 0x4A80, 0xFFD9,
      0xDA60, 0x0000, 0x0000, 0x0001, 0xE848, 0xFFFF, 0xC568, 0x0000, 0x0000};
  NavDecoder dec({.encoding = NavMapConfig::Encoding::kScaledInt});
  ASSERT_EQ(dec.decode(img, 7), NavDecodeStatus::kAccepted);
  const auto& s = dec.state();
  EXPECT_NEAR(s[Field::kLatitude].value, common::radians(47.1234567), 1e-15);
  EXPECT_NEAR(s[Field::kLongitude].value, common::radians(-122.4194155), 1e-15);
  EXPECT_NEAR(s[Field::kHeight].value, 1234.567, 1e-9);
  EXPECT_NEAR(s[Field::kTrueHeading].value, std::numbers::pi / 2, 1e-15);
  EXPECT_NEAR(s[Field::kPitch].value, common::radians(-2.5), 1e-15);
  EXPECT_NEAR(s[Field::kRoll].value, 0.0, 1e-15);
  EXPECT_NEAR(s[Field::kVelEast].value, 12.5, 1e-12);
  EXPECT_NEAR(s[Field::kVelNorth].value, -1.5, 1e-12);
  EXPECT_NEAR(s[Field::kVelUp].value, 0.0, 1e-12);
  EXPECT_EQ(dec.last_sender_time_ms(), 16u);
}

TEST(ModbusNavMap, EncoderWritesTheHandBuiltImage) {
  NavEncoder enc;
  NavState st;
  st.latitude_rad = common::radians(45.0);
  st.longitude_rad = common::radians(-0.5);
  st.height_m = 100.0;
  st.true_heading_rad = common::radians(270.0);
  st.pitch_rad = common::radians(2.5);
  st.roll_rad = common::radians(-10.0);
  st.vel_east_mps = 50.0;
  st.vel_north_mps = -25.0;
  st.vel_up_mps = 1.0;
  std::vector<std::uint16_t> out(26);
  ASSERT_TRUE(enc.encode(st, nav_status::kAllValid, 0x12345, out));
  EXPECT_EQ(out, hand_image_float_abcd());
  std::vector<std::uint16_t> small(25);
  EXPECT_FALSE(enc.encode(st, nav_status::kAllValid, 0, small));
  EXPECT_EQ(enc.update_counter(), 1);  // unchanged by the refused call
}

TEST(ModbusNavMap, RandomRoundTripsEveryEncodingAndOrder) {
  std::printf("seed %u\n", kSeed + 1);
  std::mt19937_64 rng(kSeed + 1);
  std::uniform_real_distribution<double> lat(-89.0, 89.0), lon(-179.0, 179.0), h(-500.0, 20000.0),
      hdg(0.0, 359.999), att(-80.0, 80.0), vel(-900.0, 900.0);
  for (const auto enc_kind :
       {NavMapConfig::Encoding::kFloat32, NavMapConfig::Encoding::kScaledInt}) {
    for (const auto order : {WordOrder::kABCD, WordOrder::kCDAB}) {
      const NavMapConfig cfg{.base_address = 100, .order = order, .encoding = enc_kind};
      NavEncoder enc(cfg);
      NavDecoder dec(cfg);
      std::vector<std::uint16_t> img(nav_register_count(cfg));
      for (int i = 0; i < 500; ++i) {
        NavState st{common::radians(lat(rng)),
                    common::radians(lon(rng)),
                    h(rng),
                    common::radians(hdg(rng)),
                    common::radians(att(rng)),
                    common::radians(att(rng)),
                    vel(rng),
                    vel(rng),
                    vel(rng)};
        ASSERT_TRUE(enc.encode(st, nav_status::kAllValid, static_cast<std::uint32_t>(i), img));
        ASSERT_EQ(dec.decode(img, i), NavDecodeStatus::kAccepted);
        const auto& s = dec.state();
        const bool f = enc_kind == NavMapConfig::Encoding::kFloat32;
        // Float: lat/lon are float64 (rounding ~1e-14 deg); float32 fields lose at most half
        // an ulp, 2^-24 relative. Scaled: half a step of each scale.
        const double ll_tol = f ? common::radians(1e-12) : common::radians(0.5e-7) * (1 + 1e-6);
        EXPECT_NEAR(s[Field::kLatitude].value, st.latitude_rad, ll_tol);
        EXPECT_NEAR(s[Field::kLongitude].value, st.longitude_rad, ll_tol);
        auto tol = [&](double v, double step) {
          return f ? std::abs(v) * 0x1p-24 * 1.0001 : step * 0.5 * (1 + 1e-6);
        };
        EXPECT_NEAR(s[Field::kHeight].value, st.height_m, tol(st.height_m, 1e-3));
        EXPECT_NEAR(s[Field::kTrueHeading].value, st.true_heading_rad,
                    tol(st.true_heading_rad, common::radians(1e-6)));
        EXPECT_NEAR(s[Field::kPitch].value, st.pitch_rad, tol(st.pitch_rad, common::radians(1e-6)));
        EXPECT_NEAR(s[Field::kRoll].value, st.roll_rad, tol(st.roll_rad, common::radians(1e-6)));
        EXPECT_NEAR(s[Field::kVelEast].value, st.vel_east_mps, tol(st.vel_east_mps, 1e-4));
        EXPECT_NEAR(s[Field::kVelNorth].value, st.vel_north_mps, tol(st.vel_north_mps, 1e-4));
        EXPECT_NEAR(s[Field::kVelUp].value, st.vel_up_mps, tol(st.vel_up_mps, 1e-4));
      }
      EXPECT_EQ(dec.counters().new_samples, 500u);
      EXPECT_EQ(dec.counters().counter_gaps, 0u);
    }
  }
}

TEST(ModbusNavMap, StaleCounterKeepsTheFieldsAgeing) {
  NavDecoder dec;
  auto img = hand_image_float_abcd();
  const std::int64_t t0 = 1'000'000'000;
  const std::int64_t timeout_ns = 500'000'000;
  ASSERT_EQ(dec.decode(img, t0), NavDecodeStatus::kAccepted);
  // A frozen sender: the same counter a second later is stale, and the state goes stale.
  img[12] = 0x4348;  // height 200.0f, but the counter did not move: not taken
  EXPECT_EQ(dec.decode(img, t0 + 1'000'000'000), NavDecodeStatus::kStale);
  EXPECT_EQ(dec.counters().stale, 1u);
  EXPECT_EQ(dec.counters().rejected(), 0u);
  EXPECT_DOUBLE_EQ(dec.state()[Field::kHeight].value, 100.0);
  EXPECT_EQ(dec.state()[Field::kHeight].updated_ns, t0);
  EXPECT_FALSE(dec.state().all_fresh(t0 + 1'000'000'000, timeout_ns));
  // The counter moves: taken, fresh again.
  img[0] = 2;
  EXPECT_EQ(dec.decode(img, t0 + 1'100'000'000), NavDecodeStatus::kAccepted);
  EXPECT_DOUBLE_EQ(dec.state()[Field::kHeight].value, 200.0);
  EXPECT_TRUE(dec.state().all_fresh(t0 + 1'100'000'000, timeout_ns));
  // A jump of the counter (samples missed) is counted, the value kept; wrap 0xFFFF -> 0 is not.
  img[0] = 5;
  EXPECT_EQ(dec.decode(img, t0 + 2), NavDecodeStatus::kAccepted);
  EXPECT_EQ(dec.counters().counter_gaps, 1u);
  img[0] = 0xFFFF;
  (void)dec.decode(img, t0 + 3);
  img[0] = 0x0000;
  EXPECT_EQ(dec.decode(img, t0 + 4), NavDecodeStatus::kAccepted);
  EXPECT_EQ(dec.counters().counter_gaps, 2u);
}

TEST(ModbusNavMap, RejectsBadFieldsAndCountsThem) {
  NavDecoder dec;
  auto img = hand_image_float_abcd();
  img[12] = 0x7FC0;  // height NaN
  img[16] = 0x42BE;  // pitch 95 deg (0x42BE0000): beyond +-90
  EXPECT_EQ(dec.decode(img, 10), NavDecodeStatus::kPartial);
  EXPECT_EQ(dec.counters().not_a_number, 1u);
  EXPECT_EQ(dec.counters().out_of_range, 1u);
  EXPECT_EQ(dec.counters().fields_accepted, 7u);
  EXPECT_FALSE(dec.state()[Field::kHeight].received);
  EXPECT_FALSE(dec.state()[Field::kPitch].received);
  EXPECT_TRUE(dec.state()[Field::kRoll].received);
  // Latitude 95 deg (float64 0x4057C00000000000) is out of range too.
  img[0] = 2;
  img[4] = 0x4057;
  img[5] = 0xC000;
  EXPECT_EQ(dec.decode(img, 11), NavDecodeStatus::kPartial);
  EXPECT_EQ(dec.counters().not_a_number, 2u);
  EXPECT_EQ(dec.counters().out_of_range, 3u);
  EXPECT_EQ(dec.counters().rejected(), 5u);
}

TEST(ModbusNavMap, WrongSizeIsRejectedWithoutTouchingTheState) {
  NavDecoder dec;
  auto img = hand_image_float_abcd();
  EXPECT_EQ(dec.decode(std::span(img).first(25), 1), NavDecodeStatus::kWrongSize);
  img.push_back(0);
  EXPECT_EQ(dec.decode(img, 1), NavDecodeStatus::kWrongSize);
  EXPECT_EQ(dec.decode(std::span<const std::uint16_t>(), 1), NavDecodeStatus::kWrongSize);
  EXPECT_EQ(dec.counters().wrong_size, 3u);
  EXPECT_EQ(dec.counters().rejected(), 3u);
  for (const auto& f : dec.state().fields)
    EXPECT_FALSE(f.received);
  // The scaled map is 22 registers: a float image is the wrong size for it.
  NavDecoder scaled({.encoding = NavMapConfig::Encoding::kScaledInt});
  img.pop_back();
  EXPECT_EQ(scaled.decode(img, 1), NavDecodeStatus::kWrongSize);
}

TEST(ModbusNavMap, StatusBitsGateTheirFieldGroups) {
  NavDecoder dec;
  auto img = hand_image_float_abcd();
  img[1] = nav_status::kPositionValid;  // attitude and velocity flagged invalid
  EXPECT_EQ(dec.decode(img, 1), NavDecodeStatus::kPartial);
  EXPECT_EQ(dec.counters().flagged_invalid, 6u);
  EXPECT_TRUE(dec.state()[Field::kLatitude].received);
  EXPECT_TRUE(dec.state()[Field::kHeight].received);
  EXPECT_FALSE(dec.state()[Field::kTrueHeading].received);
  EXPECT_FALSE(dec.state()[Field::kVelUp].received);
  img[0] = 2;
  img[1] = 0;  // nothing valid
  EXPECT_EQ(dec.decode(img, 2), NavDecodeStatus::kRejected);
  EXPECT_EQ(dec.counters().flagged_invalid, 15u);
  EXPECT_EQ(dec.state()[Field::kLatitude].updated_ns, 1);
}

TEST(ModbusNavMap, HeadingWrapsAndScaledNoDataIsNaN) {
  const NavMapConfig cfg{.encoding = NavMapConfig::Encoding::kScaledInt};
  NavEncoder enc(cfg);
  NavDecoder dec(cfg);
  std::vector<std::uint16_t> img(22);
  NavState st;
  st.true_heading_rad = common::radians(-90.0);  // -> 270 deg
  st.height_m = std::nan("");                    // -> kScaledI32NoData
  ASSERT_TRUE(enc.encode(st, nav_status::kAllValid, 0, img));
  EXPECT_EQ(img[8], 0x8000);
  EXPECT_EQ(img[9], 0x0000);
  EXPECT_EQ(dec.decode(img, 1), NavDecodeStatus::kPartial);
  EXPECT_EQ(dec.counters().not_a_number, 1u);
  EXPECT_NEAR(dec.state()[Field::kTrueHeading].value, 1.5 * std::numbers::pi, 1e-12);
}

// ---- Detection table ------------------------------------------------------------------------

icd::Detection hand_detection() {
  icd::Detection d;
  d.range_m = 1000.0;
  d.azimuth_deg = -2.5;
  d.elevation_deg = 0.5;
  d.radial_velocity_mps = -50.0;
  d.snr_db = 20.0;
  d.rcs_dbsm = 10.0;
  d.range_std_m = 0.25;
  d.azimuth_std_deg = 0.125;
  d.elevation_std_deg = 1.0;
  d.radial_velocity_std_mps = 0.5;
  d.range_ambiguous = true;
  return d;
}

TEST(ModbusDetectionTable, HandComputedImage) {
  const DetectionTableConfig cfg{.base_address = 0, .order = WordOrder::kABCD, .max_detections = 3};
  ASSERT_EQ(detection_table_registers(cfg), 8u + 3 * 22 + 1);
  icd::Header h;
  h.frame_counter = 0x1234;
  h.status = icd::status::kOverrun;
  h.time_ms = 0x12345;
  icd::Detection second = hand_detection();
  second.range_m = 3.0;
  second.velocity_ambiguous = true;
  second.range_ambiguous = false;
  const icd::Detection dets[] = {hand_detection(), second};
  std::vector<std::uint16_t> out(detection_table_registers(cfg), 0xEEEE);
  const TableEncodeResult r = encode_detection_table(h, dets, out, cfg);
  ASSERT_TRUE(r.ok);
  EXPECT_EQ(r.encoded, 2u);
  std::vector<std::uint16_t> want(out.size(), 0);
  const std::uint16_t header[] = {0x1234, 2, 0x02, 3, 0x0001, 0x2345, 22, 1};
  std::copy(std::begin(header), std::end(header), want.begin());
  const std::uint16_t rec[] = {0x447A, 0, 0xC020, 0, 0x3F00, 0, 0xC248, 0, 0x41A0, 0, 0x4120, 0,
                               0x3E80, 0, 0x3E00, 0, 0x3F80, 0, 0x3F00, 0, 0x0001, 0};
  std::copy(std::begin(rec), std::end(rec), want.begin() + 8);
  std::copy(std::begin(rec), std::end(rec), want.begin() + 30);
  want[30] = 0x4040;  // 3.0f
  want[30 + 20] = 0x0002;
  want.back() = 0x1234;
  EXPECT_EQ(out, want);

  icd::DetectionList list;
  ASSERT_EQ(decode_detection_table(out, cfg, list), TableDecodeStatus::kOk);
  EXPECT_EQ(list.count, 2u);
  EXPECT_EQ(list.header.frame_counter, 0x1234);
  EXPECT_EQ(list.header.status, icd::status::kOverrun);
  EXPECT_EQ(list.header.time_ms, 0x12345u);
  EXPECT_EQ(list.detections[0].azimuth_deg, -2.5);
  EXPECT_EQ(list.detections[0].radial_velocity_std_mps, 0.5);
  EXPECT_TRUE(list.detections[0].range_ambiguous);
  EXPECT_FALSE(list.detections[0].velocity_ambiguous);
  EXPECT_EQ(list.detections[1].range_m, 3.0);
  EXPECT_TRUE(list.detections[1].velocity_ambiguous);
}

TEST(ModbusDetectionTable, WordSwappedTimeAndFloats) {
  const DetectionTableConfig cfg{.order = WordOrder::kCDAB, .max_detections = 1};
  icd::Header h;
  h.time_ms = 0x12345;
  const icd::Detection d = hand_detection();
  std::vector<std::uint16_t> out(detection_table_registers(cfg));
  ASSERT_TRUE(encode_detection_table(h, std::span(&d, 1), out, cfg).ok);
  EXPECT_EQ(out[4], 0x2345);
  EXPECT_EQ(out[5], 0x0001);
  EXPECT_EQ(out[8], 0x0000);
  EXPECT_EQ(out[9], 0x447A);
}

TEST(ModbusDetectionTable, DropsTruncatesAndFlags) {
  const DetectionTableConfig cfg{.max_detections = 3};
  icd::Header h;
  std::vector<icd::Detection> dets(6, hand_detection());
  dets[1].snr_db = std::nan("");
  dets[2].azimuth_deg = 91.0;
  dets[3].range_std_m = -1.0;
  dets.push_back(hand_detection());
  dets.push_back(hand_detection());  // 8 detections: 5 good + 3 bad -> 3 encoded, 2 truncated
  std::vector<std::uint16_t> out(detection_table_registers(cfg));
  const TableEncodeResult r = encode_detection_table(h, dets, out, cfg);
  ASSERT_TRUE(r.ok);
  EXPECT_EQ(r.dropped, 3u);
  EXPECT_EQ(r.encoded, 3u);
  EXPECT_EQ(r.truncated, 2u);
  EXPECT_EQ(out[table_offset::kDetectionCount], 3);
  EXPECT_EQ(out[table_offset::kStatus], icd::status::kDropped | icd::status::kTruncated);
}

TEST(ModbusDetectionTable, RefusesSmallOutputAndBadConfig) {
  const DetectionTableConfig cfg{.max_detections = 2};
  std::vector<std::uint16_t> out(detection_table_registers(cfg) - 1, 0xEEEE);
  const icd::Detection d = hand_detection();
  EXPECT_FALSE(encode_detection_table({}, std::span(&d, 1), out, cfg).ok);
  EXPECT_EQ(out, std::vector<std::uint16_t>(out.size(), 0xEEEE));
  std::vector<std::uint16_t> big(5000);
  EXPECT_FALSE(encode_detection_table({}, {}, big, {.max_detections = 0}).ok);
  EXPECT_FALSE(encode_detection_table({}, {}, big, {.max_detections = 256}).ok);
}

TEST(ModbusDetectionTable, DecoderRejectsMalformedTables) {
  const DetectionTableConfig cfg{.max_detections = 2};
  std::vector<std::uint16_t> out(detection_table_registers(cfg));
  icd::Header h;
  h.frame_counter = 7;
  ASSERT_TRUE(encode_detection_table(h, {}, out, cfg).ok);
  icd::DetectionList list;
  EXPECT_EQ(decode_detection_table(out, cfg, list), TableDecodeStatus::kOk);
  EXPECT_EQ(list.count, 0u);
  EXPECT_EQ(decode_detection_table(std::span(out).first(out.size() - 1), cfg, list),
            TableDecodeStatus::kWrongSize);
  auto torn = out;
  torn.back() = 8;
  EXPECT_EQ(decode_detection_table(torn, cfg, list), TableDecodeStatus::kTorn);
  auto bad = out;
  bad[table_offset::kDetectionCount] = 3;
  EXPECT_EQ(decode_detection_table(bad, cfg, list), TableDecodeStatus::kBadHeader);
  bad = out;
  bad[table_offset::kVersion] = 2;
  EXPECT_EQ(decode_detection_table(bad, cfg, list), TableDecodeStatus::kBadHeader);
  EXPECT_EQ(decode_detection_table(out, {.max_detections = 3}, list),
            TableDecodeStatus::kWrongSize);
}

}  // namespace
