// CANaerospace decoder and encoder: frames worked out by hand from the specification (v1.7,
// sec. 4: node-ID, data type, service code, message code, big-endian value), round trips at
// fixed seeds, every kind of malformed frame rejected and counted, and the configurable input
// (remapped identifiers, accepted types, node-ID filter, per-field gaps, setup errors).

#include "io/canaerospace.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <limits>
#include <numbers>
#include <optional>
#include <random>
#include <stdexcept>
#include <string>
#include <utility>

#include "common/units.hpp"

namespace io = radar_emu::io;
namespace canas = radar_emu::io::canas;

namespace {
namespace common = radar_emu::common;

io::CanFrame raw(std::uint32_t id, std::initializer_list<std::uint8_t> bytes) {
  io::CanFrame f;
  f.id = id;
  f.len = static_cast<std::uint8_t>(bytes.size());
  std::size_t i = 0;
  for (auto b : bytes)
    f.data[i++] = b;
  return f;
}
}  // namespace

TEST(CanaerospaceByHand, FloatPitch) {
  // Pitch angle, id 311 = 0x137, node 1, FLOAT (2), service code 0, message code 7, value
  // 2.5 deg. IEEE-754 single: 2.5 = 1.25 x 2^1 -> sign 0, exponent 127 + 1 = 0x80,
  // fraction .01 -> 0 10000000 0100...0 = 0x40200000, sent big-endian.
  const io::CanFrame expected = raw(0x137, {0x01, 0x02, 0x00, 0x07, 0x40, 0x20, 0x00, 0x00});
  const io::CanFrame f = canas::encode_float(canas::id::kPitchAngle, 1, 7, 2.5f);
  EXPECT_EQ(f.id, expected.id);
  EXPECT_EQ(f.len, 8);
  EXPECT_EQ(std::memcmp(f.data.data(), expected.data.data(), 8), 0);
  canas::Decoder d;
  EXPECT_EQ(d.decode(expected, 123), canas::DecodeStatus::kAccepted);
  EXPECT_DOUBLE_EQ(d.state()[canas::Field::kPitch].value, common::radians(2.5));
  EXPECT_EQ(d.state()[canas::Field::kPitch].updated_ns, 123);
}

TEST(CanaerospaceByHand, NegativeFloatVelocity) {
  // True east velocity, id 1130 = 0x46A, node 9, message code 255, -122.5 m/s:
  // -122.5 = -1.9140625 x 2^6 -> sign 1, exponent 133 = 0x85, fraction .1110101 ->
  // 1 10000101 11101010...0 = 0xC2F50000.
  const io::CanFrame f = raw(0x46A, {0x09, 0x02, 0x00, 0xFF, 0xC2, 0xF5, 0x00, 0x00});
  canas::Decoder d;
  EXPECT_EQ(d.decode(f, 0), canas::DecodeStatus::kAccepted);
  EXPECT_DOUBLE_EQ(d.state()[canas::Field::kVelEast].value, -122.5);
  const io::CanFrame e = canas::encode_float(canas::id::kTrueEastVelocity, 9, 255, -122.5f);
  EXPECT_EQ(std::memcmp(e.data.data(), f.data.data(), 8), 0);
}

TEST(CanaerospaceByHand, DoubleLatitudePair) {
  // GPS latitude, id 1036 = 0x40C, 48.1234567 deg as IEEE-754 double, high word first.
  // 48.1234567 = 1.50385802... x 2^5: sign 0, exponent 1023 + 5 = 0x404, so the bits start
  // 0x4048...; the full pattern 0x40480FCD 6DDC7C6D was computed independently with Python's
  // struct.pack('>d', 48.1234567). DOUBLEH (30 = 0x1E) then DOUBLEL (31 = 0x1F), message codes
  // 4 and 5.
  const io::CanFrame high = raw(0x40C, {0x01, 0x1E, 0x00, 0x04, 0x40, 0x48, 0x0F, 0xCD});
  const io::CanFrame low = raw(0x40C, {0x01, 0x1F, 0x00, 0x05, 0x6D, 0xDC, 0x7C, 0x6D});
  const auto [h, l] = canas::encode_double(canas::id::kGpsLatitude, 1, 4, 48.1234567);
  EXPECT_EQ(std::memcmp(h.data.data(), high.data.data(), 8), 0);
  EXPECT_EQ(std::memcmp(l.data.data(), low.data.data(), 8), 0);
  canas::Decoder d;
  EXPECT_EQ(d.decode(high, 10), canas::DecodeStatus::kPendingDoubleLow);
  EXPECT_FALSE(d.state()[canas::Field::kLatitude].received);
  EXPECT_EQ(d.decode(low, 20), canas::DecodeStatus::kAccepted);
  EXPECT_EQ(d.state()[canas::Field::kLatitude].value, common::radians(48.1234567));  // bit exact
  EXPECT_EQ(d.counters().message_code_gaps, 0u);
}

TEST(CanaerospaceByHand, LongLatitudeInTenMillionthsOfDegree) {
  // Some vendors send latitude as LONG (3) in 1e-7 deg: 481234567 = 0x1CAF0E87.
  const io::CanFrame f = raw(0x40C, {0x01, 0x03, 0x00, 0x00, 0x1C, 0xAF, 0x0E, 0x87});
  canas::Decoder d;
  EXPECT_EQ(d.decode(f, 0), canas::DecodeStatus::kAccepted);
  EXPECT_NEAR(d.state()[canas::Field::kLatitude].value, common::radians(48.1234567), 1e-15);
  // LONG on pitch is not a documented encoding: unsupported.
  const io::CanFrame p = raw(0x137, {0x01, 0x03, 0x00, 0x00, 0x00, 0x00, 0x00, 0x01});
  EXPECT_EQ(d.decode(p, 0), canas::DecodeStatus::kUnsupportedDataType);
}

TEST(Canaerospace, RoundTripEveryFieldAtFixedSeed) {
  const std::uint32_t seed = 20261122;
  std::cout << "seed " << seed << "\n";
  std::mt19937 rng(seed);
  struct Case {
    canas::Field field;
    double lo, hi;  // bus units
    bool angle;
  };
  const Case cases[] = {
      {canas::Field::kPitch, -90, 90, true},         {canas::Field::kRoll, -180, 180, true},
      {canas::Field::kTrueHeading, 0, 359.99, true}, {canas::Field::kLatitude, -90, 90, true},
      {canas::Field::kLongitude, -180, 180, true},   {canas::Field::kHeight, -500, 20000, false},
      {canas::Field::kVelEast, -600, 600, false},    {canas::Field::kVelNorth, -600, 600, false},
      {canas::Field::kVelUp, -100, 100, false}};
  canas::Decoder d;
  std::uint8_t code = 0;
  for (int i = 0; i < 2000; ++i) {
    for (const Case& c : cases) {
      const double v = std::uniform_real_distribution<double>(c.lo, c.hi)(rng);
      const std::uint16_t id = canas::can_id_of(c.field);
      const double si = c.angle ? common::radians(v) : v;
      // FLOAT: exact for the float nearest to v.
      ASSERT_EQ(d.decode(canas::encode_float(id, 1, code, static_cast<float>(v)), 1),
                canas::DecodeStatus::kAccepted);
      const double as_float =
          static_cast<double>(static_cast<float>(v)) * (c.angle ? common::kRadPerDeg : 1.0);
      ASSERT_EQ(d.state()[c.field].value, as_float) << i;
      // DOUBLE pair: bit exact.
      const auto [h, l] = canas::encode_double(id, 1, static_cast<std::uint8_t>(code + 1), v);
      ASSERT_EQ(d.decode(h, 2), canas::DecodeStatus::kPendingDoubleLow);
      ASSERT_EQ(d.decode(l, 3), canas::DecodeStatus::kAccepted);
      ASSERT_NEAR(d.state()[c.field].value, si, std::abs(si) * 1e-15 + 1e-300) << i;
    }
    code = static_cast<std::uint8_t>(code + 3);
  }
  EXPECT_EQ(d.counters().rejected(), 0u);
}

TEST(Canaerospace, HeadingWrapsToZeroToTwoPi) {
  canas::Decoder d;
  ASSERT_EQ(d.decode(canas::encode_float(canas::id::kTrueHeading, 1, 0, -90.0f), 0),
            canas::DecodeStatus::kAccepted);
  EXPECT_NEAR(d.state()[canas::Field::kTrueHeading].value, 1.5 * std::numbers::pi, 1e-12);
  // -1e-20 deg: -1.7e-22 rad + 2 pi rounds to 2 pi in double (its ulp is 8.9e-16); the stored
  // value must stay below 2 pi.
  ASSERT_EQ(d.decode(canas::encode_float(canas::id::kTrueHeading, 1, 1, -1e-20f), 0),
            canas::DecodeStatus::kAccepted);
  EXPECT_GE(d.state()[canas::Field::kTrueHeading].value, 0.0);
  EXPECT_LT(d.state()[canas::Field::kTrueHeading].value, 2.0 * std::numbers::pi);
}

TEST(Canaerospace, MalformedFramesAreRejectedAndCountedByReason) {
  canas::Decoder d;
  // Short DLC: header incomplete (3 bytes), then header but no value (6 bytes).
  EXPECT_EQ(d.decode(raw(0x137, {0x01, 0x02, 0x00}), 0), canas::DecodeStatus::kShortFrame);
  EXPECT_EQ(d.decode(raw(0x137, {0x01, 0x02, 0x00, 0x00, 0x40, 0x20}), 0),
            canas::DecodeStatus::kShortFrame);
  // Unknown data type (reserved 32..99 and user-defined 100..255).
  EXPECT_EQ(d.decode(raw(0x137, {0x01, 77, 0x00, 0x00, 0, 0, 0, 0}), 0),
            canas::DecodeStatus::kUnknownDataType);
  EXPECT_EQ(d.decode(raw(0x137, {0x01, 200, 0x00, 0x00, 0, 0, 0, 0}), 0),
            canas::DecodeStatus::kUnknownDataType);
  // A defined type radar-emu does not accept here (SHORT = 6).
  EXPECT_EQ(d.decode(raw(0x137, {0x01, 6, 0x00, 0x00, 0, 1, 0, 0}), 0),
            canas::DecodeStatus::kUnsupportedDataType);
  // NaN and infinity.
  EXPECT_EQ(d.decode(canas::encode_float(canas::id::kPitchAngle, 1, 0,
                                         std::numeric_limits<float>::quiet_NaN()),
                     0),
            canas::DecodeStatus::kNotANumber);
  EXPECT_EQ(d.decode(canas::encode_float(canas::id::kRollAngle, 1, 0,
                                         std::numeric_limits<float>::infinity()),
                     0),
            canas::DecodeStatus::kNotANumber);
  // Out of range: latitude 91 deg, pitch 120 deg, height 100 km.
  EXPECT_EQ(d.decode(canas::encode_float(canas::id::kGpsLatitude, 1, 0, 91.0f), 0),
            canas::DecodeStatus::kOutOfRange);
  EXPECT_EQ(d.decode(canas::encode_float(canas::id::kPitchAngle, 1, 1, 120.0f), 0),
            canas::DecodeStatus::kOutOfRange);
  EXPECT_EQ(d.decode(canas::encode_float(canas::id::kGpsHeight, 1, 0, 1e5f), 0),
            canas::DecodeStatus::kOutOfRange);
  // DOUBLEL with no DOUBLEH before it.
  const auto [h, l] = canas::encode_double(canas::id::kGpsLongitude, 1, 0, 1.4);
  (void)h;
  EXPECT_EQ(d.decode(l, 0), canas::DecodeStatus::kUnpairedDouble);
  // Extended identifier.
  io::CanFrame ext = canas::encode_float(canas::id::kPitchAngle, 1, 0, 1.0f);
  ext.extended = true;
  EXPECT_EQ(d.decode(ext, 0), canas::DecodeStatus::kExtendedId);
  // An identifier radar-emu does not consume is ignored, not rejected.
  EXPECT_EQ(d.decode(canas::encode_float(315, 1, 0, 70.0f), 0), canas::DecodeStatus::kIgnoredId);

  const canas::DecoderCounters& c = d.counters();
  EXPECT_EQ(c.short_frame, 2u);
  EXPECT_EQ(c.unknown_data_type, 2u);
  EXPECT_EQ(c.unsupported_data_type, 1u);
  EXPECT_EQ(c.not_a_number, 2u);
  EXPECT_EQ(c.out_of_range, 3u);
  EXPECT_EQ(c.unpaired_double, 1u);
  EXPECT_EQ(c.extended_id, 1u);
  EXPECT_EQ(c.ignored_id, 1u);
  EXPECT_EQ(c.rejected(), 12u);
  EXPECT_EQ(c.accepted, 0u);
  for (std::size_t i = 0; i < canas::kFieldCount; ++i) {
    EXPECT_FALSE(d.state().fields[i].received) << "a rejected frame changed field " << i;
  }
}

TEST(Canaerospace, DoubleHighFollowedByAnotherTypeIsUnpaired) {
  canas::Decoder d;
  const auto [h, l] = canas::encode_double(canas::id::kGpsLatitude, 1, 0, 10.0);
  (void)l;
  EXPECT_EQ(d.decode(h, 0), canas::DecodeStatus::kPendingDoubleLow);
  EXPECT_EQ(d.decode(canas::encode_float(canas::id::kGpsLatitude, 1, 1, 11.0f), 0),
            canas::DecodeStatus::kAccepted);
  EXPECT_EQ(d.counters().unpaired_double, 1u);
  EXPECT_DOUBLE_EQ(d.state()[canas::Field::kLatitude].value, common::radians(11.0));
}

TEST(Canaerospace, MessageCodeGapsAreCountedAndWrapIsNot) {
  canas::Decoder d;
  // Wrap 255 -> 0 is no gap; 1 -> 5 is one; 6 -> 6 repeats the message (spec sec. 4.1.4: +1 per
  // message): not a gap, and its value is not taken.
  const std::uint8_t codes[] = {254, 255, 0, 1, 5, 6, 6};
  for (std::uint8_t c : codes) {
    (void)d.decode(canas::encode_float(canas::id::kRollAngle, 1, c, 1.0f), 0);
  }
  EXPECT_EQ(d.counters().message_code_gaps, 1u);
  EXPECT_EQ(d.counters().repeated_message_code, 1u);
  EXPECT_EQ(d.counters().accepted, 6u);
}

TEST(Canaerospace, RepeatedMessagesDoNotRefreshTheField) {
  // A sender stuck on its last message (FLOAT, and a DOUBLE pair replayed whole) keeps its
  // message codes: the field's reception time must not move, so it goes stale.
  canas::Decoder d;
  ASSERT_EQ(d.decode(canas::encode_float(canas::id::kPitchAngle, 1, 7, 2.0f), 100),
            canas::DecodeStatus::kAccepted);
  EXPECT_EQ(d.decode(canas::encode_float(canas::id::kPitchAngle, 1, 7, 2.0f), 200),
            canas::DecodeStatus::kRepeatedMessageCode);
  EXPECT_EQ(d.state()[canas::Field::kPitch].updated_ns, 100);
  const auto [h, l] = canas::encode_double(canas::id::kGpsLatitude, 1, 40, 43.6);
  ASSERT_EQ(d.decode(h, 100), canas::DecodeStatus::kPendingDoubleLow);
  ASSERT_EQ(d.decode(l, 100), canas::DecodeStatus::kAccepted);
  EXPECT_EQ(d.decode(h, 300), canas::DecodeStatus::kRepeatedMessageCode);
  EXPECT_EQ(d.decode(l, 300), canas::DecodeStatus::kRepeatedMessageCode);
  EXPECT_EQ(d.state()[canas::Field::kLatitude].updated_ns, 100);
  // The next pair (codes 42, 43) is new.
  const auto [h2, l2] = canas::encode_double(canas::id::kGpsLatitude, 1, 42, 43.7);
  EXPECT_EQ(d.decode(h2, 400), canas::DecodeStatus::kPendingDoubleLow);
  EXPECT_EQ(d.decode(l2, 400), canas::DecodeStatus::kAccepted);
  EXPECT_EQ(d.state()[canas::Field::kLatitude].updated_ns, 400);
  EXPECT_EQ(d.counters().repeated_message_code, 3u);
  EXPECT_EQ(d.counters().message_code_gaps, 0u);
}

TEST(OwnshipState, AgeAndFreshness) {
  canas::Decoder d;
  EXPECT_TRUE(std::isinf(d.state().age_s(canas::Field::kPitch, 0)));
  EXPECT_FALSE(d.state().fresh(canas::Field::kPitch, 0, 1'000'000'000));
  (void)d.decode(canas::encode_float(canas::id::kPitchAngle, 1, 0, 1.0f), 1'000'000'000);
  EXPECT_DOUBLE_EQ(d.state().age_s(canas::Field::kPitch, 1'250'000'000), 0.25);
  EXPECT_TRUE(d.state().fresh(canas::Field::kPitch, 1'500'000'000, 500'000'000));  // age = timeout
  EXPECT_FALSE(d.state().fresh(canas::Field::kPitch, 1'500'000'001, 500'000'000));
  EXPECT_FALSE(d.state().all_fresh(1'000'000'000, 500'000'000));  // other fields never received
}

TEST(Canaerospace, RandomFramesNeverCrashAtFixedSeed) {
  const std::uint32_t seed = 97;
  std::cout << "seed " << seed << "\n";
  std::mt19937 rng(seed);
  canas::Decoder d;
  std::size_t accepted = 0, pending = 0, ignored = 0, rejected = 0;
  const std::uint32_t ids[] = {311, 312, 1036, 1037, 1038, 1130, 1131, 1132, 1133, 0x7FF, 0};
  for (int i = 0; i < 200'000; ++i) {
    io::CanFrame f;
    f.id = ids[rng() % std::size(ids)];
    f.len = static_cast<std::uint8_t>(rng() % 9);
    f.extended = rng() % 50 == 0;
    for (std::size_t b = 0; b < 8; ++b)
      f.data[b] = static_cast<std::uint8_t>(rng());
    if (rng() % 2)
      f.data[1] = static_cast<std::uint8_t>(rng() % 32);  // mostly known types
    switch (d.decode(f, i)) {
      case canas::DecodeStatus::kAccepted:
        ++accepted;
        break;
      case canas::DecodeStatus::kPendingDoubleLow:
        ++pending;
        break;
      case canas::DecodeStatus::kIgnoredId:
        ++ignored;
        break;
      default:
        ++rejected;
    }
  }
  const canas::DecoderCounters& c = d.counters();
  EXPECT_EQ(c.frames, 200'000u);
  EXPECT_EQ(accepted + pending + ignored + rejected, 200'000u);
  EXPECT_EQ(c.accepted, accepted);
  EXPECT_EQ(c.ignored_id, ignored);
  // A pending DOUBLEH that is never closed is counted as unpaired later, so the rejection
  // counter may exceed the rejected returns by at most the number of pending highs.
  EXPECT_GE(c.rejected(), rejected);
  EXPECT_LE(c.rejected(), rejected + pending);
  EXPECT_GT(rejected, 1000u);
  EXPECT_GT(accepted, 100u);  // random 32-bit values are mostly out of range or NaN
  for (std::size_t k = 0; k < canas::kFieldCount; ++k) {
    const auto& s = d.state().fields[k];
    if (s.received) {
      EXPECT_TRUE(std::isfinite(s.value));
    }
  }
}

// ---- Configurable input (DecoderConfig) ----------------------------------------------------

namespace {
// Message from setup that must throw std::invalid_argument; empty if it did not.
template <typename F>
std::string invalid_argument_of(F&& setup) {
  try {
    setup();
  } catch (const std::invalid_argument& e) {
    return e.what();
  }
  return {};
}
}  // namespace

TEST(CanaerospaceConfig, DefaultsAreTheSpecIdentifiers) {
  // Spec v1.7 appendix A (default identifier distribution): pitch 311, roll 312, true heading
  // 1133, GPS latitude/longitude/height 1036/1037/1038, true east/north/up velocity
  // 1130/1131/1132.
  const canas::DecoderConfig c;
  const std::pair<canas::Field, std::uint16_t> want[] = {
      {canas::Field::kPitch, 311},        {canas::Field::kRoll, 312},
      {canas::Field::kTrueHeading, 1133}, {canas::Field::kLatitude, 1036},
      {canas::Field::kLongitude, 1037},   {canas::Field::kHeight, 1038},
      {canas::Field::kVelEast, 1130},     {canas::Field::kVelNorth, 1131},
      {canas::Field::kVelUp, 1132}};
  for (const auto& [field, can_id] : want) {
    EXPECT_EQ(c[field].can_id, can_id) << canas::field_name(field);
    const bool lat_lon = field == canas::Field::kLatitude || field == canas::Field::kLongitude;
    EXPECT_EQ(c[field].accepted,
              canas::accept::kFloat | canas::accept::kDouble | (lat_lon ? canas::accept::kLong : 0))
        << canas::field_name(field);
    EXPECT_EQ(c[field].long_lsb, lat_lon ? 1e-7 : 0.0);
  }
  EXPECT_FALSE(c.node_id.has_value());
  EXPECT_NO_THROW(canas::validate(c));
  const canas::Decoder d;
  EXPECT_FALSE(d.config().node_id.has_value());
  EXPECT_EQ(d.config()[canas::Field::kTrueHeading].can_id, 1133);
}

TEST(CanaerospaceConfig, FieldNamesRoundTrip) {
  for (std::size_t i = 0; i < canas::kFieldCount; ++i) {
    const auto f = static_cast<canas::Field>(i);
    EXPECT_FALSE(canas::field_name(f).empty());
    EXPECT_EQ(canas::field_from_name(canas::field_name(f)), f);
  }
  EXPECT_EQ(canas::field_name(canas::Field::kLatitude), "latitude");
  EXPECT_EQ(canas::field_from_name("heading"), std::nullopt);
}

TEST(CanaerospaceConfig, RemappedIdentifiers) {
  // Latitude from the INS (1049) instead of GPS (1036); heading from the heading angle 321
  // (+-180 deg) instead of true heading 1133; longitude on a user-defined low-priority id 1850.
  canas::DecoderConfig c;
  c[canas::Field::kLatitude].can_id = 1049;
  c[canas::Field::kTrueHeading].can_id = 321;
  c[canas::Field::kLongitude].can_id = 1850;
  canas::Decoder d(c);
  // INS latitude 1049 = 0x419, FLOAT 2.5 deg (0x40200000, see FloatPitch).
  EXPECT_EQ(d.decode(raw(0x419, {0x01, 0x02, 0x00, 0x00, 0x40, 0x20, 0x00, 0x00}), 5),
            canas::DecodeStatus::kAccepted);
  EXPECT_DOUBLE_EQ(d.state()[canas::Field::kLatitude].value, common::radians(2.5));
  // The old identifiers are now ignored, not errors.
  EXPECT_EQ(d.decode(canas::encode_float(1036, 1, 0, 3.0f), 6), canas::DecodeStatus::kIgnoredId);
  EXPECT_EQ(d.decode(canas::encode_float(1133, 1, 0, 3.0f), 6), canas::DecodeStatus::kIgnoredId);
  // Heading angle 321 = 0x141: -90 deg (0xC2B40000: sign 1, exponent 133, fraction .0110100)
  // wraps to 270 deg.
  EXPECT_EQ(d.decode(raw(0x141, {0x01, 0x02, 0x00, 0x00, 0xC2, 0xB4, 0x00, 0x00}), 7),
            canas::DecodeStatus::kAccepted);
  EXPECT_NEAR(d.state()[canas::Field::kTrueHeading].value, 1.5 * std::numbers::pi, 1e-12);
  // Longitude on 1850 as a DOUBLE pair.
  const auto [h, l] = canas::encode_double(1850, 1, 0, -122.25);
  EXPECT_EQ(d.decode(h, 8), canas::DecodeStatus::kPendingDoubleLow);
  EXPECT_EQ(d.decode(l, 9), canas::DecodeStatus::kAccepted);
  EXPECT_EQ(d.state()[canas::Field::kLongitude].value, common::radians(-122.25));
  EXPECT_EQ(d.counters().ignored_id, 2u);
  EXPECT_EQ(d.counters().rejected(), 0u);
}

TEST(CanaerospaceConfig, AcceptedDataTypesPerField) {
  canas::DecoderConfig c;
  c[canas::Field::kPitch].accepted = canas::accept::kFloat;  // no DOUBLE pairs for pitch
  c[canas::Field::kHeight].accepted = canas::accept::kLong;  // height as LONG in centimetres
  c[canas::Field::kHeight].long_lsb = 0.01;
  c[canas::Field::kLatitude].accepted = canas::accept::kDouble;  // no FLOAT, no LONG
  canas::Decoder d(c);
  const auto [h, l] = canas::encode_double(canas::id::kPitchAngle, 1, 0, 1.0);
  (void)l;
  EXPECT_EQ(d.decode(h, 0), canas::DecodeStatus::kUnsupportedDataType);
  EXPECT_EQ(d.decode(canas::encode_float(canas::id::kPitchAngle, 1, 1, 1.0f), 0),
            canas::DecodeStatus::kAccepted);
  // GPS height 1038 = 0x40E, LONG (3), 123456 cm = 0x0001E240 -> 1234.56 m.
  EXPECT_EQ(d.decode(raw(0x40E, {0x01, 0x03, 0x00, 0x00, 0x00, 0x01, 0xE2, 0x40}), 0),
            canas::DecodeStatus::kAccepted);
  EXPECT_NEAR(d.state()[canas::Field::kHeight].value, 1234.56, 1e-9);
  EXPECT_EQ(d.decode(canas::encode_float(canas::id::kGpsHeight, 1, 1, 10.0f), 0),
            canas::DecodeStatus::kUnsupportedDataType);
  EXPECT_EQ(d.decode(canas::encode_float(canas::id::kGpsLatitude, 1, 0, 10.0f), 0),
            canas::DecodeStatus::kUnsupportedDataType);
  EXPECT_EQ(d.decode(canas::encode_long(canas::id::kGpsLatitude, 1, 1, 100000000), 0),
            canas::DecodeStatus::kUnsupportedDataType);
  EXPECT_EQ(d.counters().unsupported_data_type, 4u);
}

TEST(CanaerospaceConfig, NodeFilterCountsOtherNodesNotErrors) {
  canas::DecoderConfig c;
  c.node_id = 5;
  canas::Decoder d(c);
  EXPECT_EQ(d.decode(canas::encode_float(canas::id::kRollAngle, 5, 10, 1.0f), 0),
            canas::DecodeStatus::kAccepted);
  // Node 7 on the same identifier, with message codes of its own: neither stored nor counted as
  // a gap in node 5's sequence.
  EXPECT_EQ(d.decode(canas::encode_float(canas::id::kRollAngle, 7, 200, 2.0f), 1),
            canas::DecodeStatus::kOtherNode);
  EXPECT_EQ(d.decode(raw(0x138, {0x07, 0x02, 0x00, 0x00, 0x40, 0x20, 0x00, 0x00}), 1),
            canas::DecodeStatus::kOtherNode);
  EXPECT_DOUBLE_EQ(d.state()[canas::Field::kRoll].value, common::radians(1.0));
  EXPECT_EQ(d.state()[canas::Field::kRoll].updated_ns, 0);
  EXPECT_EQ(d.decode(canas::encode_float(canas::id::kRollAngle, 5, 11, 3.0f), 2),
            canas::DecodeStatus::kAccepted);
  // Identifiers not consumed stay ignored whatever the node.
  EXPECT_EQ(d.decode(canas::encode_float(315, 7, 0, 1.0f), 3), canas::DecodeStatus::kIgnoredId);
  const canas::DecoderCounters& k = d.counters();
  EXPECT_EQ(k.other_node, 2u);
  EXPECT_EQ(k.accepted, 2u);
  EXPECT_EQ(k.rejected(), 0u);
  EXPECT_EQ(k.message_code_gaps, 0u);
  // Unset: any node is accepted (today's behaviour).
  canas::Decoder any;
  EXPECT_EQ(any.decode(canas::encode_float(canas::id::kRollAngle, 7, 0, 2.0f), 0),
            canas::DecodeStatus::kAccepted);
  EXPECT_EQ(any.counters().other_node, 0u);
}

TEST(CanaerospaceConfig, MessageCodeGapsAreCountedPerField) {
  canas::Decoder d;
  for (const std::uint8_t code : std::initializer_list<std::uint8_t>{
           254, 255, 0, 1, 5, 6, 6})  // roll: 1 -> 5 (6 -> 6 repeats)
    (void)d.decode(canas::encode_float(canas::id::kRollAngle, 1, code, 1.0f), 0);
  for (const std::uint8_t code :
       std::initializer_list<std::uint8_t>{10, 11, 13})  // pitch: 11 -> 13
    (void)d.decode(canas::encode_float(canas::id::kPitchAngle, 1, code, 1.0f), 0);
  // A DOUBLE pair takes two codes: 20, 21, then 22, 23; then 30 is a gap.
  for (const std::uint8_t code : std::initializer_list<std::uint8_t>{20, 22, 30}) {
    const auto [h, l] = canas::encode_double(canas::id::kGpsLatitude, 1, code, 1.0);
    (void)d.decode(h, 0);
    (void)d.decode(l, 0);
  }
  const canas::DecoderCounters& c = d.counters();
  const auto gaps = [&](canas::Field f) {
    return c.message_code_gaps_by_field[static_cast<std::size_t>(f)];
  };
  EXPECT_EQ(gaps(canas::Field::kRoll), 1u);
  EXPECT_EQ(gaps(canas::Field::kPitch), 1u);
  EXPECT_EQ(gaps(canas::Field::kLatitude), 1u);
  EXPECT_EQ(gaps(canas::Field::kHeight), 0u);
  EXPECT_EQ(c.message_code_gaps, 3u);
  EXPECT_EQ(c.repeated_message_code, 1u);
}

TEST(CanaerospaceConfig, SetupErrorsNameTheField) {
  canas::DecoderConfig dup;
  dup[canas::Field::kLongitude].can_id = 1036;  // latitude's
  std::string e = invalid_argument_of([&] { canas::Decoder d(dup); });
  EXPECT_NE(e.find("'longitude'"), std::string::npos) << e;
  EXPECT_NE(e.find("'latitude'"), std::string::npos) << e;
  EXPECT_NE(e.find("1036"), std::string::npos) << e;

  canas::DecoderConfig wide;
  wide[canas::Field::kPitch].can_id = 2048;  // 12 bits
  e = invalid_argument_of([&] { canas::Decoder d(wide); });
  EXPECT_NE(e.find("'pitch'"), std::string::npos) << e;
  EXPECT_NE(e.find("2048"), std::string::npos) << e;
  wide[canas::Field::kPitch].can_id = 2047;  // the largest 11-bit identifier is fine
  EXPECT_NO_THROW(canas::validate(wide));

  canas::DecoderConfig none;
  none[canas::Field::kVelUp].accepted = 0;
  e = invalid_argument_of([&] { canas::validate(none); });
  EXPECT_NE(e.find("'vel_up'"), std::string::npos) << e;

  canas::DecoderConfig long_no_lsb;
  long_no_lsb[canas::Field::kRoll].accepted |= canas::accept::kLong;
  e = invalid_argument_of([&] { canas::validate(long_no_lsb); });
  EXPECT_NE(e.find("'roll'"), std::string::npos) << e;
  EXPECT_NE(e.find("long_lsb"), std::string::npos) << e;
}
