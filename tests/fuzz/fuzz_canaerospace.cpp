// Harness: the CANaerospace decoder (io/canaerospace.hpp) on arbitrary frame sequences, with
// the default configuration, a node-ID filter, or a configuration read from the input (which
// validate() must accept or reject with std::invalid_argument).
//
// Input: byte 0 selects the configuration; then frames, each: a control byte (low nibble 0..8
// picks a consumed identifier, 9..15 a raw 11/29-bit identifier from the next bytes; bit 4
// extended; bit 5 advances the clock), a length byte (mod 9) and the payload.
//
// Oracles: the decoder's counters equal the statuses it returned (counted here); every stored
// field is finite and inside its physical range in SI units; a FLOAT value it accepts equals
// the frame's big-endian IEEE-754 single converted here (deg -> rad, heading wrapped).

#include <bit>
#include <cmath>
#include <numbers>
#include <stdexcept>

#include "common/units.hpp"
#include "io/canaerospace.hpp"
#include "tests/fuzz/fuzz_input.hpp"
#include "tests/fuzz/harnesses.hpp"

namespace radar_emu::fuzz {

namespace {

namespace canas = io::canas;
using canas::Field;

constexpr double kPi = std::numbers::pi;
constexpr double kEps = 1e-9;

struct SiRange {
  double lo, hi;
};

// Physical ranges in SI (docs/icd/canaerospace_input.md), with heading in [0, 2 pi).
SiRange si_range(Field f) {
  constexpr double d = common::kRadPerDeg;
  switch (f) {
    case Field::kPitch:
    case Field::kLatitude:
      return {-90.0 * d, 90.0 * d};
    case Field::kRoll:
    case Field::kLongitude:
      return {-180.0 * d, 180.0 * d};
    case Field::kTrueHeading:
      return {0.0, 2.0 * kPi};
    case Field::kHeight:
      return {-1000.0, 60000.0};
    default:
      return {-1500.0, 1500.0};
  }
}

bool is_angle(Field f) {
  return f == Field::kPitch || f == Field::kRoll || f == Field::kTrueHeading ||
         f == Field::kLatitude || f == Field::kLongitude;
}

}  // namespace

int canaerospace(const std::uint8_t* data, std::size_t size) {
  FuzzInput in(data, size);
  const std::uint8_t mode = in.u8();
  canas::DecoderConfig config;
  if ((mode & 0x01) != 0)
    config.node_id = in.u8();
  if ((mode & 0x02) != 0) {
    for (canas::FieldInput& f : config.fields) {
      f.can_id = static_cast<std::uint16_t>(in.u16() & 0x0FFF);
      f.accepted = static_cast<std::uint8_t>(in.u8() & 0x0F);
      f.long_lsb = std::bit_cast<double>(in.u64());
    }
    try {
      canas::validate(config);
    } catch (const std::invalid_argument&) {
      return 0;  // a rejected configuration (setup error): nothing to decode with
    }
  }
  canas::Decoder decoder(config);

  // Statuses counted here, compared with the decoder's own counters at the end.
  std::array<std::uint64_t, 12> status_count{};
  std::uint64_t calls = 0;
  std::int64_t now_ns = 1'000'000'000;
  while (!in.empty()) {
    io::CanFrame f;
    const std::uint8_t ctl = in.u8();
    const std::uint8_t pick = ctl & 0x0F;
    if (pick < canas::kFieldCount) {
      f.id = config.fields[pick].can_id;
    } else {
      f.id = in.u32() & ((ctl & 0x10) != 0 ? 0x1FFFFFFFu : 0x7FFu);
    }
    f.extended = (ctl & 0x10) != 0;
    if ((ctl & 0x20) != 0)
      now_ns += static_cast<std::int64_t>(in.u16()) * 1000;
    f.len = static_cast<std::uint8_t>(in.u8() % 9);
    in.bytes(std::span(f.data.data(), f.len));
    f.timestamp_ns = now_ns;

    const canas::DecodeStatus st = decoder.decode(f, now_ns);
    ++calls;
    const auto s = static_cast<std::size_t>(st);
    FUZZ_CHECK(s < status_count.size());
    ++status_count[s];

    if (st == canas::DecodeStatus::kAccepted && f.data[1] == 2) {  // FLOAT
      std::size_t k = 0;
      while (k < canas::kFieldCount && config.fields[k].can_id != f.id)
        ++k;
      FUZZ_CHECK(k < canas::kFieldCount);
      const auto field = static_cast<Field>(k);
      const std::uint32_t bits = (std::uint32_t{f.data[4]} << 24) |
                                 (std::uint32_t{f.data[5]} << 16) |
                                 (std::uint32_t{f.data[6]} << 8) | f.data[7];
      double want = static_cast<double>(std::bit_cast<float>(bits));
      if (is_angle(field))
        want *= kPi / 180.0;
      if (field == Field::kTrueHeading) {
        want = std::fmod(want, 2.0 * kPi);
        if (want < 0.0)
          want += 2.0 * kPi;
      }
      const double got = decoder.state()[field].value;
      FUZZ_CHECK(std::abs(got - want) <= kEps || std::abs(got - want + 2.0 * kPi) <= kEps);
      FUZZ_CHECK(decoder.state()[field].updated_ns == now_ns);
    }
    for (std::size_t k = 0; k < canas::kFieldCount; ++k) {
      const canas::FieldSample& fs = decoder.state().fields[k];
      if (!fs.received)
        continue;
      const SiRange r = si_range(static_cast<Field>(k));
      FUZZ_CHECK(std::isfinite(fs.value));
      FUZZ_CHECK(fs.value >= r.lo - kEps && fs.value <= r.hi + kEps);
      if (static_cast<Field>(k) == Field::kTrueHeading)
        FUZZ_CHECK(fs.value < 2.0 * kPi);
    }
  }

  using S = canas::DecodeStatus;
  const auto n = [&](S s) { return status_count[static_cast<std::size_t>(s)]; };
  const canas::DecoderCounters& c = decoder.counters();
  FUZZ_CHECK(c.frames == calls);
  FUZZ_CHECK(c.accepted == n(S::kAccepted));
  FUZZ_CHECK(c.ignored_id == n(S::kIgnoredId));
  FUZZ_CHECK(c.short_frame == n(S::kShortFrame));
  FUZZ_CHECK(c.unknown_data_type == n(S::kUnknownDataType));
  FUZZ_CHECK(c.unsupported_data_type == n(S::kUnsupportedDataType));
  FUZZ_CHECK(c.not_a_number == n(S::kNotANumber));
  FUZZ_CHECK(c.out_of_range == n(S::kOutOfRange));
  FUZZ_CHECK(c.extended_id == n(S::kExtendedId));
  FUZZ_CHECK(c.other_node == n(S::kOtherNode));
  FUZZ_CHECK(c.repeated_message_code == n(S::kRepeatedMessageCode));
  // A DOUBLEL without its DOUBLEH is returned as such; a DOUBLEH broken by another value or
  // by a second DOUBLEH is counted without a status of its own.
  FUZZ_CHECK(c.unpaired_double >= n(S::kUnpairedDouble));
  std::uint64_t gaps = 0;
  for (std::uint64_t g : c.message_code_gaps_by_field)
    gaps += g;
  FUZZ_CHECK(gaps == c.message_code_gaps);
  return 0;
}

}  // namespace radar_emu::fuzz
