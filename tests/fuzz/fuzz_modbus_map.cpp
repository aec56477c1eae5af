// Harnesses: the Modbus register maps (io/modbus_map.hpp, docs/icd/modbus.md).
//
// modbus_nav: byte 0 picks the encoding (float32 / scaled int32) and the word order (ABCD /
// CDAB); then register images, each: a size byte (>= 8: the map's size; below: that many
// registers, a wrong size), a clock step, the registers (big-endian pairs of bytes). Oracles:
// the decoder's counters equal the statuses it returned; every stored field is finite and in
// its documented range in SI units; after an accepted or partial image every field whose group
// bit is set and whose value, decoded here from the documented layout (offsets, word order,
// scale), lies in its range was stored with this image's time and that value.
//
// modbus_table: byte 0 picks the word order and bit 1 the mode. Decode mode: a table
// configuration (base address, 1..255 records) and arbitrary registers into
// decode_detection_table; oracle: kOk only for a well-formed header with a matching trailer,
// and then the list's header and records are the registers' values. Round-trip mode: a header
// and up to 255 detections from raw double bits (NaN, infinities, huge values included),
// encoded and decoded; oracles: dropped/truncated/encoded counts from the documented rule
// (a value NaN/infinite, a negative range or accuracy, an angle beyond +-90 deg), and each
// record the float32 of what was sent.

#include <bit>
#include <cmath>
#include <limits>
#include <numbers>
#include <vector>

#include "io/modbus_map.hpp"
#include "tests/fuzz/fuzz_input.hpp"
#include "tests/fuzz/harnesses.hpp"

namespace radar_emu::fuzz {

namespace {

namespace mb = io::modbus;
namespace canas = io::canas;
using canas::Field;

constexpr double kPi = std::numbers::pi;

// The registers of a value, most significant first (undoing the word order): ABCD keeps them,
// CDAB reverses them (docs/icd/modbus.md, "Conventions").
std::uint64_t join(std::span<const std::uint16_t> regs, std::size_t at, std::size_t n,
                   mb::WordOrder order) {
  std::uint64_t v = 0;
  for (std::size_t i = 0; i < n; ++i) {
    const std::size_t k = order == mb::WordOrder::kABCD ? at + i : at + n - 1 - i;
    v = (v << 16) | regs[k];
  }
  return v;
}

struct DocField {
  Field field;
  std::size_t float_offset, scaled_offset;
  std::uint16_t bit;
  double scale, lo, hi;
  bool angle;
};

// docs/icd/modbus.md, "Navigation map": offsets, status bits, scales and valid ranges.
constexpr DocField kDocFields[] = {
    {Field::kLatitude, 4, 4, 0x0001, 1e-7, -90, 90, true},
    {Field::kLongitude, 8, 6, 0x0001, 1e-7, -180, 180, true},
    {Field::kHeight, 12, 8, 0x0001, 1e-3, -1000, 60000, false},
    {Field::kTrueHeading, 14, 10, 0x0002, 1e-6, -360, 360, true},
    {Field::kPitch, 16, 12, 0x0002, 1e-6, -90, 90, true},
    {Field::kRoll, 18, 14, 0x0002, 1e-6, -180, 180, true},
    {Field::kVelEast, 20, 16, 0x0004, 1e-4, -1500, 1500, false},
    {Field::kVelNorth, 22, 18, 0x0004, 1e-4, -1500, 1500, false},
    {Field::kVelUp, 24, 20, 0x0004, 1e-4, -1500, 1500, false},
};

double doc_value(const DocField& f, std::span<const std::uint16_t> regs, bool floats,
                 mb::WordOrder order) {
  if (!floats) {
    const auto raw = static_cast<std::int32_t>(
        static_cast<std::uint32_t>(join(regs, f.scaled_offset, 2, order)));
    return raw == std::numeric_limits<std::int32_t>::min()
               ? std::numeric_limits<double>::quiet_NaN()
               : static_cast<double>(raw) * f.scale;
  }
  if (f.field == Field::kLatitude || f.field == Field::kLongitude)
    return std::bit_cast<double>(join(regs, f.float_offset, 4, order));
  return static_cast<double>(
      std::bit_cast<float>(static_cast<std::uint32_t>(join(regs, f.float_offset, 2, order))));
}

double to_si(const DocField& f, double v) {
  double si = f.angle ? v * kPi / 180.0 : v;
  if (f.field == Field::kTrueHeading) {
    si = std::fmod(si, 2.0 * kPi);
    if (si < 0.0)
      si += 2.0 * kPi;
  }
  return si;
}

}  // namespace

int modbus_nav(const std::uint8_t* data, std::size_t size) {
  FuzzInput in(data, size);
  const std::uint8_t mode = in.u8();
  mb::NavMapConfig config;
  config.encoding = (mode & 1) != 0 ? mb::NavMapConfig::Encoding::kScaledInt
                                    : mb::NavMapConfig::Encoding::kFloat32;
  config.order = (mode & 2) != 0 ? mb::WordOrder::kCDAB : mb::WordOrder::kABCD;
  const bool floats = config.encoding == mb::NavMapConfig::Encoding::kFloat32;
  mb::NavDecoder decoder(config);
  const std::size_t count = floats ? 26 : 22;  // documented map lengths
  FUZZ_CHECK(decoder.register_count() == count);
  FUZZ_CHECK(mb::nav_register_count(config) == count);

  std::array<std::uint64_t, 5> status_count{};
  std::uint64_t calls = 0;
  std::int64_t now_ns = 0;
  std::vector<std::uint16_t> regs;
  while (!in.empty()) {
    const std::uint8_t size_sel = in.u8();
    regs.resize(size_sel >= 8 ? count : size_sel * 5u);
    now_ns += 1 + static_cast<std::int64_t>(in.u16()) * 1000;
    for (std::uint16_t& r : regs)
      r = in.u16();
    const canas::OwnshipState before = decoder.state();
    const mb::NavDecodeStatus st = decoder.decode(regs, now_ns);
    ++calls;
    FUZZ_CHECK(static_cast<std::size_t>(st) < status_count.size());
    ++status_count[static_cast<std::size_t>(st)];
    const canas::OwnshipState& after = decoder.state();
    if (st == mb::NavDecodeStatus::kWrongSize || st == mb::NavDecodeStatus::kStale) {
      for (std::size_t k = 0; k < canas::kFieldCount; ++k) {
        FUZZ_CHECK(after.fields[k].updated_ns == before.fields[k].updated_ns);
        FUZZ_CHECK(std::bit_cast<std::uint64_t>(after.fields[k].value) ==
                   std::bit_cast<std::uint64_t>(before.fields[k].value));
      }
      FUZZ_CHECK(st != mb::NavDecodeStatus::kWrongSize || regs.size() != count);
      continue;
    }
    FUZZ_CHECK(regs.size() == count);
    FUZZ_CHECK(decoder.last_update_counter() == regs[0]);
    FUZZ_CHECK(decoder.last_status() == regs[1]);
    FUZZ_CHECK(decoder.last_sender_time_ms() ==
               static_cast<std::uint32_t>(join(regs, 2, 2, config.order)));
    std::size_t stored = 0, skipped = 0;
    for (const DocField& f : kDocFields) {
      const canas::FieldSample& s = after.fields[static_cast<std::size_t>(f.field)];
      const double v = doc_value(f, regs, floats, config.order);
      const bool take = (regs[1] & f.bit) != 0 && std::isfinite(v) && v >= f.lo && v <= f.hi;
      if (take) {
        ++stored;
        FUZZ_CHECK(s.received && s.updated_ns == now_ns);
        const double want = to_si(f, v);
        FUZZ_CHECK(std::abs(s.value - want) <= 1e-12 * std::max(1.0, std::abs(want)) ||
                   (f.field == Field::kTrueHeading && s.value == 0.0 &&
                    std::abs(want - 2.0 * kPi) <= 1e-12));
      } else {
        ++skipped;
        FUZZ_CHECK(s.updated_ns == before.fields[static_cast<std::size_t>(f.field)].updated_ns);
      }
    }
    FUZZ_CHECK(st == (stored == 0    ? mb::NavDecodeStatus::kRejected
                      : skipped == 0 ? mb::NavDecodeStatus::kAccepted
                                     : mb::NavDecodeStatus::kPartial));
    for (std::size_t k = 0; k < canas::kFieldCount; ++k) {
      if (!after.fields[k].received)
        continue;
      const double v = after.fields[k].value;
      FUZZ_CHECK(std::isfinite(v));
      if (static_cast<Field>(k) == Field::kTrueHeading)
        FUZZ_CHECK(v >= 0.0 && v < 2.0 * kPi);
    }
  }
  const mb::NavDecoderCounters& c = decoder.counters();
  FUZZ_CHECK(c.samples == calls);
  FUZZ_CHECK(c.wrong_size ==
             status_count[static_cast<std::size_t>(mb::NavDecodeStatus::kWrongSize)]);
  FUZZ_CHECK(c.stale == status_count[static_cast<std::size_t>(mb::NavDecodeStatus::kStale)]);
  FUZZ_CHECK(c.new_samples == calls - c.wrong_size - c.stale);
  return 0;
}

namespace {

bool table_drops(const io::icd::Detection& d) {
  const double values[] = {d.range_m,
                           d.azimuth_deg,
                           d.elevation_deg,
                           d.radial_velocity_mps,
                           d.snr_db,
                           d.rcs_dbsm,
                           d.range_std_m,
                           d.azimuth_std_deg,
                           d.elevation_std_deg,
                           d.radial_velocity_std_mps};
  for (double v : values) {
    if (!std::isfinite(v))
      return true;
  }
  return d.range_m < 0.0 || d.range_std_m < 0.0 || d.azimuth_std_deg < 0.0 ||
         d.elevation_std_deg < 0.0 || d.radial_velocity_std_mps < 0.0 ||
         std::abs(d.azimuth_deg) > 90.0 || std::abs(d.elevation_deg) > 90.0;
}

// float32 of a finite double, saturated to +-infinity beyond float's range.
float as_f32(double v) {
  constexpr double kMax = static_cast<double>(std::numeric_limits<float>::max());
  if (v > kMax)
    return std::numeric_limits<float>::infinity();
  if (v < -kMax)
    return -std::numeric_limits<float>::infinity();
  return static_cast<float>(v);
}

double raw_double(FuzzInput& in) {
  const std::uint8_t sel = in.u8();
  if (sel < 200)  // mostly ordinary values, so records survive
    return (static_cast<double>(static_cast<std::int32_t>(in.u32())) / 65536.0) *
           (sel % 4 == 0 ? 1e-3 : 1.0);
  return std::bit_cast<double>(in.u64());
}

}  // namespace

int modbus_table(const std::uint8_t* data, std::size_t size) {
  FuzzInput in(data, size);
  const std::uint8_t mode = in.u8();
  mb::DetectionTableConfig config;
  config.order = (mode & 1) != 0 ? mb::WordOrder::kCDAB : mb::WordOrder::kABCD;
  config.base_address = in.u16();
  config.max_detections = in.u8();  // 0 is invalid
  const std::size_t total = mb::detection_table_registers(config);
  FUZZ_CHECK(total == 8 + 22 * config.max_detections + 1);
  const bool config_ok = config.max_detections >= 1 && config.base_address + total <= 65536;
  io::icd::DetectionList list;

  if ((mode & 2) == 0) {  // decode arbitrary registers
    std::vector<std::uint16_t> regs((in.u8() & 1) != 0 ? total : in.u8());
    for (std::uint16_t& r : regs)
      r = in.u16();
    const mb::TableDecodeStatus st = mb::decode_detection_table(regs, config, list);
    if (!config_ok || regs.size() != total) {
      FUZZ_CHECK(st == mb::TableDecodeStatus::kWrongSize);
      return 0;
    }
    const bool header_ok = regs[7] == 1 && regs[6] == 22 && regs[3] == config.max_detections &&
                           regs[1] <= config.max_detections && regs[2] <= 0xFF;
    if (!header_ok) {
      FUZZ_CHECK(st == mb::TableDecodeStatus::kBadHeader);
      return 0;
    }
    if (regs[total - 1] != regs[0]) {
      FUZZ_CHECK(st == mb::TableDecodeStatus::kTorn);
      return 0;
    }
    FUZZ_CHECK(st == mb::TableDecodeStatus::kOk);
    FUZZ_CHECK(list.count == regs[1] && list.header.detection_count == regs[1]);
    FUZZ_CHECK(list.header.frame_counter == regs[0] && list.header.status == regs[2]);
    FUZZ_CHECK(list.header.time_ms == static_cast<std::uint32_t>(join(regs, 4, 2, config.order)));
    for (std::size_t i = 0; i < list.count; ++i) {
      const std::size_t at = 8 + 22 * i;
      const auto f32 = [&](std::size_t off) {
        return std::bit_cast<float>(
            static_cast<std::uint32_t>(join(regs, at + off, 2, config.order)));
      };
      // The same float (a signalling NaN comes back quiet through double: any NaN is equal).
      const auto same = [](double got, float want) {
        return std::isnan(want) ? std::isnan(got)
                                : std::bit_cast<std::uint32_t>(static_cast<float>(got)) ==
                                      std::bit_cast<std::uint32_t>(want);
      };
      const io::icd::Detection& d = list.detections[i];
      FUZZ_CHECK(same(d.range_m, f32(0)) && same(d.azimuth_deg, f32(2)) &&
                 same(d.elevation_deg, f32(4)) && same(d.radial_velocity_mps, f32(6)) &&
                 same(d.snr_db, f32(8)) && same(d.rcs_dbsm, f32(10)) &&
                 same(d.range_std_m, f32(12)) && same(d.azimuth_std_deg, f32(14)) &&
                 same(d.elevation_std_deg, f32(16)) && same(d.radial_velocity_std_mps, f32(18)));
      FUZZ_CHECK(d.range_ambiguous == ((regs[at + 20] & 1) != 0));
      FUZZ_CHECK(d.velocity_ambiguous == ((regs[at + 20] & 2) != 0));
    }
    return 0;
  }

  // Round trip.
  io::icd::Header header;
  header.frame_counter = in.u16();
  header.status = static_cast<std::uint8_t>(in.u8() & 0x03);
  header.time_ms = in.u32();
  std::vector<io::icd::Detection> sent(in.u8());
  for (io::icd::Detection& d : sent) {
    d.range_m = raw_double(in);
    d.azimuth_deg = raw_double(in);
    d.elevation_deg = raw_double(in);
    d.radial_velocity_mps = raw_double(in);
    d.snr_db = raw_double(in);
    d.rcs_dbsm = raw_double(in);
    d.range_std_m = raw_double(in);
    d.azimuth_std_deg = raw_double(in);
    d.elevation_std_deg = raw_double(in);
    d.radial_velocity_std_mps = raw_double(in);
    const std::uint8_t flags = in.u8();
    d.range_ambiguous = (flags & 1) != 0;
    d.velocity_ambiguous = (flags & 2) != 0;
  }
  std::vector<std::uint16_t> regs(total + (in.u8() & 1), 0xA5A5);  // sometimes one too many
  const mb::TableEncodeResult enc = mb::encode_detection_table(header, sent, regs, config);
  if (!config_ok) {
    FUZZ_CHECK(!enc.ok && enc.encoded == 0);
    return 0;
  }
  FUZZ_CHECK(enc.ok);
  std::vector<const io::icd::Detection*> kept;
  std::size_t dropped = 0;
  for (const io::icd::Detection& d : sent) {
    if (table_drops(d))
      ++dropped;
    else
      kept.push_back(&d);
  }
  const std::size_t encoded = std::min(kept.size(), config.max_detections);
  FUZZ_CHECK(enc.dropped == dropped && enc.encoded == encoded &&
             enc.truncated == kept.size() - encoded);
  if (regs.size() > total)
    FUZZ_CHECK(regs[total] == 0xA5A5);  // nothing written past the table
  regs.resize(total);
  FUZZ_CHECK(mb::decode_detection_table(regs, config, list) == mb::TableDecodeStatus::kOk);
  FUZZ_CHECK(list.count == encoded);
  FUZZ_CHECK(list.header.frame_counter == header.frame_counter);
  FUZZ_CHECK(list.header.time_ms == header.time_ms);
  std::uint8_t status = header.status;
  if (enc.dropped > 0)
    status |= io::icd::status::kDropped;
  if (enc.truncated > 0)
    status |= io::icd::status::kTruncated;
  FUZZ_CHECK(list.header.status == status);
  const auto same = [](double got, double sent_value) {
    return std::bit_cast<std::uint32_t>(static_cast<float>(got)) ==
           std::bit_cast<std::uint32_t>(as_f32(sent_value));
  };
  for (std::size_t i = 0; i < encoded; ++i) {
    const io::icd::Detection& s = *kept[i];
    const io::icd::Detection& g = list.detections[i];
    FUZZ_CHECK(same(g.range_m, s.range_m) && same(g.azimuth_deg, s.azimuth_deg) &&
               same(g.elevation_deg, s.elevation_deg) &&
               same(g.radial_velocity_mps, s.radial_velocity_mps) && same(g.snr_db, s.snr_db) &&
               same(g.rcs_dbsm, s.rcs_dbsm) && same(g.range_std_m, s.range_std_m) &&
               same(g.azimuth_std_deg, s.azimuth_std_deg) &&
               same(g.elevation_std_deg, s.elevation_std_deg) &&
               same(g.radial_velocity_std_mps, s.radial_velocity_std_mps));
    FUZZ_CHECK(g.range_ambiguous == s.range_ambiguous &&
               g.velocity_ambiguous == s.velocity_ambiguous);
  }
  for (std::size_t i = encoded; i < config.max_detections; ++i) {
    for (std::size_t k = 0; k < 22; ++k)
      FUZZ_CHECK(regs[8 + 22 * i + k] == 0);  // records past the count are zero
  }
  return 0;
}

}  // namespace radar_emu::fuzz
