// Randomized robustness test of the input decoders (issue 6): over a million frames (random
// identifiers 11/29-bit, lengths 0..64, FD flags, payloads; valid CANaerospace messages of every
// data type with edge-case values; valid ICD lists, classic and FD, mutated by bit flips, losses,
// duplicates and swaps) fed to canas::Decoder and icd::ListDecoder, and 10^5 random and mutated
// candump lines fed to parse_candump. Runs under ASan + UBSan (label sanitize): no crash, no UB.
// Asserted invariants:
//  - every frame gets exactly one status, and each decoder counter equals the count of its
//    status (canas: accepted, ignored, each rejection; ICD: malformed, orphans);
//  - an accepted CANaerospace value is finite and inside its field's valid range
//    (docs/icd/canaerospace_input.md), and only an accepted frame changes the ownship state;
//  - a completed ICD list has count == header count, every signal finite and inside what its
//    field can carry (docs/icd/detections.md), and every unmutated list that follows any amount
//    of garbage decodes to exactly the values sent;
//  - a candump line that parses is a well-formed frame, and format/parse round-trips it.
// The seed is fixed and printed.

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <bit>
#include <cmath>
#include <cstdio>
#include <limits>
#include <numbers>
#include <random>
#include <span>
#include <string>
#include <vector>

#include "common/units.hpp"
#include "io/canaerospace.hpp"
#include "io/candump.hpp"
#include "io/detection_icd.hpp"

namespace io = radar_emu::io;
namespace canas = radar_emu::io::canas;
namespace icd = radar_emu::io::icd;

namespace {

constexpr std::uint64_t kSeed = 0x6ADD'0006;
constexpr std::size_t kFrames = 1'000'000;
constexpr std::size_t kCandumpLines = 100'000;
using radar_emu::common::kRadPerDeg;

// The consumed identifiers and their valid ranges in bus units, from
// docs/icd/canaerospace_input.md (written independently of the decoder's table).
struct FieldSpec {
  std::uint16_t id;
  canas::Field field;
  double lo, hi;  // [deg], [m] or [m/s]
  bool angle;
  bool long_ok;  // LONG (1e-7 deg) accepted
};
constexpr std::array<FieldSpec, canas::kFieldCount> kSpecs = {{
    {311, canas::Field::kPitch, -90.0, 90.0, true, false},
    {312, canas::Field::kRoll, -180.0, 180.0, true, false},
    {1133, canas::Field::kTrueHeading, -360.0, 360.0, true, false},
    {1036, canas::Field::kLatitude, -90.0, 90.0, true, true},
    {1037, canas::Field::kLongitude, -180.0, 180.0, true, true},
    {1038, canas::Field::kHeight, -1000.0, 60000.0, false, false},
    {1130, canas::Field::kVelEast, -1500.0, 1500.0, false, false},
    {1131, canas::Field::kVelNorth, -1500.0, 1500.0, false, false},
    {1132, canas::Field::kVelUp, -1500.0, 1500.0, false, false},
}};

const FieldSpec* spec_of(const io::CanFrame& f) {
  if (f.extended)
    return nullptr;
  for (const FieldSpec& s : kSpecs) {
    if (s.id == f.id)
      return &s;
  }
  return nullptr;
}

constexpr std::array<std::uint32_t, 5> kIcdIds = {icd::kHeaderId, icd::kDetectionAId,
                                                  icd::kDetectionBId, icd::kFdHeaderId,
                                                  icd::kFdContinuationId};
constexpr std::array<std::uint8_t, 16> kFdLengths = {0, 1,  2,  3,  4,  5,  6,  7,
                                                     8, 12, 16, 20, 24, 32, 48, 64};

class Gen {
 public:
  explicit Gen(std::uint64_t seed) : rng_(seed) {}
  std::uint64_t operator()() { return rng_(); }
  std::uint64_t below(std::uint64_t n) { return rng_() % n; }
  bool chance(double p) { return uniform() < p; }
  double uniform() { return static_cast<double>(rng_() >> 11) * 0x1.0p-53; }
  double uniform(double lo, double hi) { return lo + (hi - lo) * uniform(); }
  std::int64_t between(std::int64_t lo, std::int64_t hi) {  // inclusive
    return lo + static_cast<std::int64_t>(below(static_cast<std::uint64_t>(hi - lo + 1)));
  }

 private:
  std::mt19937_64 rng_;
};

void fill_payload(io::CanFrame& f, Gen& g) {
  for (std::size_t i = 0; i < f.len; ++i)
    f.data[i] = static_cast<std::uint8_t>(g());
}

// Anything: any identifier width, any length 0..64 whatever the FD flag says.
io::CanFrame random_frame(Gen& g) {
  io::CanFrame f;
  f.extended = g.chance(0.5);
  f.id = static_cast<std::uint32_t>(g() & (f.extended ? 0x1FFFFFFFu : 0x7FFu));
  f.fd = g.chance(0.5);
  f.fd_flags = static_cast<std::uint8_t>(g.below(16));
  f.len = static_cast<std::uint8_t>(g.below(io::kCanFdMaxBytes + 1));
  fill_payload(f, g);
  return f;
}

// An identifier the decoders consume, with a random payload and a plausible length.
io::CanFrame targeted_frame(Gen& g) {
  io::CanFrame f;
  f.id = g.chance(0.5) ? kSpecs[g.below(kSpecs.size())].id : kIcdIds[g.below(kIcdIds.size())];
  f.extended = g.chance(0.05);
  f.fd = g.chance(0.3);
  f.len = f.fd ? kFdLengths[g.below(kFdLengths.size())] : static_cast<std::uint8_t>(g.below(9));
  fill_payload(f, g);
  return f;
}

// Flips 1..3 bits among the identifier's 11 bits and the payload; sometimes changes the length.
void mutate(io::CanFrame& f, Gen& g) {
  const std::uint64_t flips = 1 + g.below(3);
  for (std::uint64_t k = 0; k < flips; ++k) {
    const std::uint64_t bit = g.below(11 + 8 * static_cast<std::uint64_t>(f.len));
    if (bit < 11) {
      f.id ^= 1u << bit;
    } else {
      f.data[(bit - 11) / 8] ^= static_cast<std::uint8_t>(1u << ((bit - 11) % 8));
    }
  }
  if (g.chance(0.1)) {
    const auto len = static_cast<std::uint8_t>(g.below(io::kCanFdMaxBytes + 1));
    for (std::size_t i = len; i < f.len; ++i)
      f.data[i] = 0;
    f.len = len;
  }
}

// A value for a field in bus units: in range, just outside, special or random bits.
double field_value(const FieldSpec& s, Gen& g) {
  const double span = s.hi - s.lo;
  switch (g.below(8)) {
    case 0:
      return g.chance(0.5) ? s.lo : s.hi;
    case 1:
      return g.chance(0.5) ? std::nextafter(s.lo, -1e300) : std::nextafter(s.hi, 1e300);
    case 2: {
      constexpr std::array<double, 7> kSpecial = {std::numeric_limits<double>::quiet_NaN(),
                                                  std::numeric_limits<double>::infinity(),
                                                  -std::numeric_limits<double>::infinity(),
                                                  0.0,
                                                  -0.0,
                                                  std::numeric_limits<double>::denorm_min(),
                                                  1e300};
      return kSpecial[g.below(kSpecial.size())];
    }
    case 3:
      return std::bit_cast<double>(g());
    case 4:
      return g.uniform(s.lo - span, s.hi + span);
    default:
      return g.uniform(s.lo, s.hi);
  }
}

// One to three frames of a CANaerospace message for a consumed field.
void canas_message(Gen& g, std::array<std::uint8_t, 2048>& codes, std::vector<io::CanFrame>& out) {
  const FieldSpec& s = kSpecs[g.below(kSpecs.size())];
  const auto node = static_cast<std::uint8_t>(g.below(4));
  std::uint8_t& code = codes[s.id];
  const double v = field_value(s, g);
  const std::uint64_t kind = g.below(10);
  if (kind < 4) {
    out.push_back(canas::encode_float(s.id, node, code++, static_cast<float>(v)));
  } else if (kind < 7) {
    auto [high, low] = canas::encode_double(s.id, node, code, v);
    code = static_cast<std::uint8_t>(code + 2);
    out.push_back(high);
    if (g.chance(0.1))  // something else on the identifier in between, or the low half lost
      out.push_back(canas::encode_float(s.id, node, code++, 1.0f));
    if (!g.chance(0.05))
      out.push_back(low);
    if (g.chance(0.05))  // a DOUBLEL alone
      out.push_back(low);
  } else if (kind < 8) {
    const double raw = std::isfinite(v)
                           ? std::clamp(std::round(v / 1e-7), -2147483648.0, 2147483647.0)
                           : static_cast<double>(static_cast<std::int32_t>(g()));
    out.push_back(canas::encode_long(s.id, node, code++, static_cast<std::int32_t>(raw)));
  } else {
    // Any data type code, any service code, any length.
    io::CanFrame f = canas::encode_float(s.id, node, code++, static_cast<float>(v));
    f.data[1] = static_cast<std::uint8_t>(g());
    f.data[2] = static_cast<std::uint8_t>(g());
    if (g.chance(0.3)) {
      f.len = static_cast<std::uint8_t>(g.below(9));
      for (std::size_t i = f.len; i < 8; ++i)
        f.data[i] = 0;
    }
    out.push_back(f);
  }
  if (g.chance(0.2))
    code = static_cast<std::uint8_t>(g());  // a message code gap
  if (g.chance(0.2))
    mutate(out.back(), g);
}

// A detection whose every signal is an exact multiple of its step, so that the decoded value
// equals it; some outside the ICD ranges (the encoder drops those).
struct RawDetection {
  icd::Detection physical;
  bool valid;
};
RawDetection random_detection(Gen& g) {
  RawDetection r{};
  icd::Detection& d = r.physical;
  d.range_m = static_cast<double>(g.between(0, 0xFFFFFF)) * icd::kRangeScale_m;
  d.radial_velocity_mps =
      static_cast<double>(g.between(-32767, 32767)) * icd::kRadialVelocityScale_mps;
  d.snr_db = static_cast<double>(g.between(0, 255)) * icd::kSnrScale_db;
  d.azimuth_deg = static_cast<double>(g.between(-9000, 9000)) * icd::kAngleScale_deg;
  d.elevation_deg = static_cast<double>(g.between(-9000, 9000)) * icd::kAngleScale_deg;
  d.rcs_dbsm = static_cast<double>(g.between(-32768, 32767)) * icd::kRcsScale_dbsm;
  d.range_std_m = static_cast<double>(g.between(0, 0xFFFF)) * icd::kRangeStdScale_m;
  d.radial_velocity_std_mps =
      static_cast<double>(g.between(0, 0xFFF)) * icd::kRadialVelocityStdScale_mps;
  d.azimuth_std_deg = static_cast<double>(g.between(0, 0x3FFF)) * icd::kAngleStdScale_deg;
  d.elevation_std_deg = static_cast<double>(g.between(0, 0x3FFF)) * icd::kAngleStdScale_deg;
  d.range_ambiguous = g.chance(0.5);
  d.velocity_ambiguous = g.chance(0.5);
  r.valid = true;
  if (g.chance(0.03)) {
    d.azimuth_deg = g.chance(0.5) ? 95.0 : std::numeric_limits<double>::quiet_NaN();
    r.valid = false;
  }
  return r;
}

struct SentList {
  std::vector<io::CanFrame> frames;
  std::vector<icd::Detection> expected;  // what the encoder kept
  icd::Header header;
  bool fd = false;
};

SentList icd_list(Gen& g, std::uint16_t frame_counter) {
  SentList s;
  s.fd = g.chance(0.4);
  const std::size_t n = g.chance(0.01) ? icd::kMaxDetectionsPerFrame : g.below(25);
  std::vector<icd::Detection> dets;
  for (std::size_t i = 0; i < n; ++i) {
    const RawDetection r = random_detection(g);
    dets.push_back(r.physical);
    if (r.valid)
      s.expected.push_back(r.physical);
  }
  s.header.frame_counter = frame_counter;
  s.header.status = static_cast<std::uint8_t>(g.below(4));
  s.header.time_ms = static_cast<std::uint32_t>(g());
  s.frames.resize(s.fd ? icd::frames_for_fd(n) : icd::frames_for(n));
  const icd::EncodeResult r =
      s.fd ? icd::encode_fd(s.header, dets, s.frames) : icd::encode(s.header, dets, s.frames);
  s.frames.resize(r.frames);
  s.header.detection_count = static_cast<std::uint8_t>(r.encoded);
  return s;
}

// Inside what each ICD signal can carry (docs/icd/detections.md); angles are checked against
// their field (+-327.68 deg), not the ICD-valid +-90 deg, which ListDecoder does not enforce.
bool carriable(const icd::Detection& d, bool fd) {
  const bool finite =
      std::isfinite(d.range_m) && std::isfinite(d.radial_velocity_mps) && std::isfinite(d.snr_db) &&
      std::isfinite(d.azimuth_deg) && std::isfinite(d.elevation_deg) && std::isfinite(d.rcs_dbsm) &&
      std::isfinite(d.range_std_m) && std::isfinite(d.azimuth_std_deg) &&
      std::isfinite(d.elevation_std_deg) && std::isfinite(d.radial_velocity_std_mps);
  const bool main = d.range_m >= 0.0 && d.range_m <= icd::kMaxRange_m &&
                    std::abs(d.radial_velocity_mps) <= 655.36 && d.snr_db >= 0.0 &&
                    d.snr_db <= 127.5 && std::abs(d.azimuth_deg) <= 327.68 &&
                    std::abs(d.elevation_deg) <= 327.68 && std::abs(d.rcs_dbsm) <= 327.68;
  const bool accuracies = fd ? d.range_std_m >= 0.0 && d.range_std_m <= 655.35 &&
                                   d.radial_velocity_std_mps >= 0.0 &&
                                   d.radial_velocity_std_mps <= 40.95 && d.azimuth_std_deg >= 0.0 &&
                                   d.azimuth_std_deg <= 32.766 && d.elevation_std_deg >= 0.0 &&
                                   d.elevation_std_deg <= 32.766
                             : d.range_std_m == 0.0 && d.radial_velocity_std_mps == 0.0 &&
                                   d.azimuth_std_deg == 0.0 && d.elevation_std_deg == 0.0;
  return finite && main && accuracies;
}

bool same_main_signals(const icd::Detection& a, const icd::Detection& b) {
  return a.range_m == b.range_m && a.radial_velocity_mps == b.radial_velocity_mps &&
         a.snr_db == b.snr_db && a.azimuth_deg == b.azimuth_deg &&
         a.elevation_deg == b.elevation_deg && a.rcs_dbsm == b.rcs_dbsm;
}

bool same_sample(const canas::FieldSample& a, const canas::FieldSample& b) {
  return std::bit_cast<std::uint64_t>(a.value) == std::bit_cast<std::uint64_t>(b.value) &&
         a.updated_ns == b.updated_ns && a.received == b.received;
}

}  // namespace

TEST(DecoderRandom, MillionFramesLandInExactlyOneCounterAndStayInRange) {
  std::printf("seed 0x%llx, %zu frames\n", static_cast<unsigned long long>(kSeed), kFrames);
  Gen g(kSeed);
  canas::Decoder canas_decoder;
  icd::ListDecoder list_decoder;
  std::array<std::uint64_t, 32> canas_status{};
  std::array<std::uint64_t, 8> icd_status{};
  std::array<std::uint8_t, 2048> codes{};
  std::uint64_t frames = 0, bad_canas = 0, state_changed_without_accept = 0;
  std::uint64_t lists_complete = 0, bad_lists = 0, clean_lists = 0, clean_lists_wrong = 0;
  std::uint64_t angles_beyond_icd = 0;
  std::uint16_t frame_counter = 0;
  std::vector<io::CanFrame> batch;
  batch.reserve(600);

  auto feed = [&](const io::CanFrame& f) -> icd::FeedStatus {
    ++frames;
    const std::int64_t now_ns = static_cast<std::int64_t>(frames) * 1000;
    const canas::OwnshipState before = canas_decoder.state();
    const canas::DecodeStatus cs = canas_decoder.decode(f, now_ns);
    ++canas_status[static_cast<std::size_t>(cs)];
    const canas::OwnshipState& after = canas_decoder.state();
    const FieldSpec* spec = spec_of(f);
    for (std::size_t i = 0; i < canas::kFieldCount; ++i) {
      const bool is_target = spec != nullptr && static_cast<std::size_t>(spec->field) == i;
      if (!(cs == canas::DecodeStatus::kAccepted && is_target) &&
          !same_sample(before.fields[i], after.fields[i])) {
        ++state_changed_without_accept;
      }
    }
    if (cs == canas::DecodeStatus::kAccepted) {
      const canas::FieldSample& s = after[spec != nullptr ? spec->field : canas::Field::kPitch];
      const double k = spec != nullptr && spec->angle ? kRadPerDeg : 1.0;
      bool ok = spec != nullptr && s.received && s.updated_ns == now_ns && std::isfinite(s.value);
      if (ok && spec->field == canas::Field::kTrueHeading) {
        ok = s.value >= 0.0 && s.value < 2.0 * std::numbers::pi;
      } else if (ok) {
        ok = s.value >= spec->lo * k && s.value <= spec->hi * k;
      }
      if (!ok) {
        ++bad_canas;
        if (bad_canas <= 5) {
          ADD_FAILURE() << "accepted out of range: id " << f.id << " value " << s.value;
        }
      }
    }
    const icd::FeedStatus is = list_decoder.feed(f);
    ++icd_status[static_cast<std::size_t>(is)];
    const icd::DetectionList& l = list_decoder.list();
    if (l.count > l.header.detection_count)
      ++bad_lists;
    if (is == icd::FeedStatus::kComplete) {
      ++lists_complete;
      bool ok = l.count == l.header.detection_count;
      for (std::size_t i = 0; i < l.count; ++i) {
        ok = ok && carriable(l.detections[i], l.fd);
        angles_beyond_icd += std::abs(l.detections[i].azimuth_deg) > icd::kMaxAbsAngle_deg ||
                                     std::abs(l.detections[i].elevation_deg) > icd::kMaxAbsAngle_deg
                                 ? 1u
                                 : 0u;
      }
      if (!ok) {
        ++bad_lists;
        if (bad_lists <= 5)
          ADD_FAILURE() << "completed list with count " << l.count << " out of range";
      }
    }
    return is;
  };

  while (frames < kFrames) {
    const std::uint64_t kind = g.below(100);
    batch.clear();
    if (kind < 20) {
      for (int i = 0; i < 8; ++i)
        batch.push_back(random_frame(g));
    } else if (kind < 40) {
      for (int i = 0; i < 8; ++i)
        batch.push_back(targeted_frame(g));
    } else if (kind < 75) {
      for (int i = 0; i < 8; ++i)
        canas_message(g, codes, batch);
    } else {
      SentList s = icd_list(g, frame_counter++);
      const bool clean = g.chance(0.5);
      if (clean) {
        icd::FeedStatus last = icd::FeedStatus::kIgnored;
        for (const io::CanFrame& f : s.frames)
          last = feed(f);
        ++clean_lists;
        // Whatever came before, an intact list decodes to exactly what was sent.
        const icd::DetectionList& l = list_decoder.list();
        bool ok = last == icd::FeedStatus::kComplete && l.fd == s.fd &&
                  l.header.frame_counter == s.header.frame_counter &&
                  l.header.time_ms == s.header.time_ms && l.count == s.expected.size();
        for (std::size_t i = 0; ok && i < l.count; ++i)
          ok = same_main_signals(l.detections[i], s.expected[i]);
        if (!ok) {
          ++clean_lists_wrong;
          if (clean_lists_wrong <= 5)
            ADD_FAILURE() << "intact list " << s.header.frame_counter << " decoded wrongly";
        }
        continue;
      }
      // Mutated: bit flips, losses, duplicates and swaps.
      for (std::size_t i = 0; i < s.frames.size(); ++i) {
        if (i + 1 < s.frames.size() && g.chance(0.03))
          std::swap(s.frames[i], s.frames[i + 1]);
        io::CanFrame f = s.frames[i];
        if (g.chance(0.03))
          continue;
        if (g.chance(0.05))
          mutate(f, g);
        batch.push_back(f);
        if (g.chance(0.03))
          batch.push_back(f);
      }
    }
    for (const io::CanFrame& f : batch)
      (void)feed(f);
  }

  // Every frame got one status; each counter equals its status count.
  std::uint64_t canas_total = 0, icd_total = 0;
  for (std::uint64_t n : canas_status)
    canas_total += n;
  for (std::uint64_t n : icd_status)
    icd_total += n;
  EXPECT_EQ(canas_total, frames);
  EXPECT_EQ(icd_total, frames);
  const canas::DecoderCounters& c = canas_decoder.counters();
  auto n_of = [&](canas::DecodeStatus s) { return canas_status[static_cast<std::size_t>(s)]; };
  EXPECT_EQ(c.frames, frames);
  EXPECT_EQ(c.accepted, n_of(canas::DecodeStatus::kAccepted));
  EXPECT_EQ(c.ignored_id, n_of(canas::DecodeStatus::kIgnoredId));
  EXPECT_EQ(c.short_frame, n_of(canas::DecodeStatus::kShortFrame));
  EXPECT_EQ(c.unknown_data_type, n_of(canas::DecodeStatus::kUnknownDataType));
  EXPECT_EQ(c.unsupported_data_type, n_of(canas::DecodeStatus::kUnsupportedDataType));
  EXPECT_EQ(c.not_a_number, n_of(canas::DecodeStatus::kNotANumber));
  EXPECT_EQ(c.out_of_range, n_of(canas::DecodeStatus::kOutOfRange));
  EXPECT_EQ(c.extended_id, n_of(canas::DecodeStatus::kExtendedId));
  EXPECT_EQ(c.other_node, n_of(canas::DecodeStatus::kOtherNode));
  EXPECT_EQ(c.repeated_message_code, n_of(canas::DecodeStatus::kRepeatedMessageCode));
  // unpaired_double also counts DOUBLEH frames abandoned later (returned as kPendingDoubleLow
  // when they came), so it is at least the kUnpairedDouble count, and pending + unpaired frames
  // are accounted for exactly by: frames - (everything else).
  EXPECT_GE(c.unpaired_double, n_of(canas::DecodeStatus::kUnpairedDouble));
  EXPECT_EQ(c.accepted + c.ignored_id + c.other_node + c.repeated_message_code + c.short_frame +
                c.unknown_data_type + c.unsupported_data_type + c.not_a_number + c.out_of_range +
                c.extended_id + n_of(canas::DecodeStatus::kUnpairedDouble) +
                n_of(canas::DecodeStatus::kPendingDoubleLow),
            frames);
  EXPECT_EQ(list_decoder.malformed(),
            icd_status[static_cast<std::size_t>(icd::FeedStatus::kMalformed)]);
  EXPECT_EQ(list_decoder.orphans(), icd_status[static_cast<std::size_t>(icd::FeedStatus::kOrphan)]);
  EXPECT_EQ(bad_canas, 0u);
  EXPECT_EQ(state_changed_without_accept, 0u);
  EXPECT_EQ(bad_lists, 0u);
  EXPECT_EQ(angles_beyond_icd, 0u);  // frames with angles beyond +-90 deg are malformed
  EXPECT_EQ(clean_lists_wrong, 0u);
  // The mix reached every path that matters.
  EXPECT_GT(c.accepted, 10'000u);
  for (canas::DecodeStatus s :
       {canas::DecodeStatus::kIgnoredId, canas::DecodeStatus::kShortFrame,
        canas::DecodeStatus::kUnknownDataType, canas::DecodeStatus::kUnsupportedDataType,
        canas::DecodeStatus::kNotANumber, canas::DecodeStatus::kOutOfRange,
        canas::DecodeStatus::kUnpairedDouble, canas::DecodeStatus::kExtendedId,
        canas::DecodeStatus::kPendingDoubleLow}) {
    EXPECT_GT(n_of(s), 100u) << "status " << static_cast<int>(s);
  }
  EXPECT_GT(clean_lists, 1'000u);
  EXPECT_GT(lists_complete, clean_lists);  // mutated lists complete too (flips in values)
  EXPECT_GT(list_decoder.malformed(), 1'000u);
  EXPECT_GT(list_decoder.orphans(), 100u);
  std::printf(
      "canas: accepted %llu, rejected %llu, pending %llu; icd: complete %llu (intact %llu), "
      "malformed %llu, orphans %llu, incomplete %llu; completed detections with angles beyond "
      "+-90 deg %llu\n",
      static_cast<unsigned long long>(c.accepted), static_cast<unsigned long long>(c.rejected()),
      static_cast<unsigned long long>(n_of(canas::DecodeStatus::kPendingDoubleLow)),
      static_cast<unsigned long long>(lists_complete), static_cast<unsigned long long>(clean_lists),
      static_cast<unsigned long long>(list_decoder.malformed()),
      static_cast<unsigned long long>(list_decoder.orphans()),
      static_cast<unsigned long long>(list_decoder.incomplete_lists()),
      static_cast<unsigned long long>(angles_beyond_icd));
}

namespace {

bool valid_length(const io::CanFrame& f) {
  if (f.len <= io::kCanClassicMaxBytes)
    return true;
  if (!f.fd)
    return false;
  for (std::uint8_t n : kFdLengths)
    if (n == f.len)
      return true;
  return false;
}

bool same_frame(const io::CanFrame& a, const io::CanFrame& b) {
  return a.id == b.id && a.len == b.len && a.extended == b.extended && a.fd == b.fd &&
         a.fd_flags == b.fd_flags && a.data == b.data && a.timestamp_ns == b.timestamp_ns;
}

// A random well-formed frame (FD only with a valid FD length), time stamp in whole microseconds.
io::CanFrame random_valid_frame(Gen& g) {
  io::CanFrame f;
  f.extended = g.chance(0.5);
  f.id = static_cast<std::uint32_t>(g() & (f.extended ? 0x1FFFFFFFu : 0x7FFu));
  f.fd = g.chance(0.4);
  f.fd_flags = f.fd ? static_cast<std::uint8_t>(g.below(16)) : 0;
  f.len = f.fd ? kFdLengths[g.below(kFdLengths.size())] : static_cast<std::uint8_t>(g.below(9));
  fill_payload(f, g);
  f.timestamp_ns = static_cast<std::int64_t>(g.below(9'000'000'000ULL * 1'000'000)) * 1000;
  return f;
}

std::string random_interface(Gen& g) {
  static constexpr char kChars[] = "abcdefghijklmnopqrstuvwxyz0123456789_-";
  std::string s(1 + g.below(15), 'x');
  for (char& c : s)
    c = kChars[g.below(sizeof kChars - 1)];
  return s;
}

void mutate_line(std::string& line, Gen& g) {
  static constexpr char kAlphabet[] = "0123456789abcdefABCDEF#().Rr \r\n-+x";
  const std::uint64_t edits = 1 + g.below(4);
  for (std::uint64_t e = 0; e < edits; ++e) {
    const std::size_t at = line.empty() ? 0 : g.below(line.size());
    const char c =
        g.chance(0.8) ? kAlphabet[g.below(sizeof kAlphabet - 1)] : static_cast<char>(g.below(256));
    switch (g.below(5)) {
      case 0:
        if (!line.empty())
          line[at] = c;
        break;
      case 1:
        line.insert(line.begin() + static_cast<std::ptrdiff_t>(at), c);
        break;
      case 2:
        if (!line.empty())
          line.erase(at, 1);
        break;
      case 3:
        line.resize(at);
        break;
      default:
        line.insert(at, line.substr(at, g.below(12)));
        break;
    }
  }
}

}  // namespace

TEST(DecoderRandom, CandumpLinesParseOrFailCleanly) {
  std::printf("seed 0x%llx, %zu lines\n", static_cast<unsigned long long>(kSeed + 1),
              kCandumpLines);
  Gen g(kSeed + 1);
  std::array<char, io::kCandumpMaxLine> buf{};
  io::CandumpLine parsed, again;
  std::string error, line;
  std::uint64_t round_trip_failures = 0, malformed_accepted = 0, silent_errors = 0;
  std::uint64_t accepted_mutants = 0, rejected = 0;
  for (std::size_t n = 0; n < kCandumpLines; ++n) {
    const io::CanFrame frame = random_valid_frame(g);
    const std::string iface = random_interface(g);
    const std::size_t len = io::format_candump(frame, iface, buf);
    ASSERT_GT(len, 0u);
    line.assign(buf.data(), len);
    const std::uint64_t kind = g.below(10);
    if (kind < 3) {
      // Intact: must parse back to the same frame.
      error.clear();
      if (!io::parse_candump(line, parsed, error) || !same_frame(parsed.frame, frame) ||
          parsed.interface_name != iface) {
        ++round_trip_failures;
        if (round_trip_failures <= 5)
          ADD_FAILURE() << "round trip: " << line << " " << error;
      }
      continue;
    }
    if (kind < 9) {
      mutate_line(line, g);
    } else {
      line.resize(g.below(80));
      for (char& c : line)
        c = static_cast<char>(g.below(256));
    }
    error.clear();
    if (!io::parse_candump(line, parsed, error)) {
      ++rejected;
      if (error.empty() || error.find('\n') != std::string::npos)
        ++silent_errors;
      continue;
    }
    ++accepted_mutants;
    // Whatever was accepted is a well-formed frame, and a fixed point of format -> parse.
    const io::CanFrame& f = parsed.frame;
    bool ok = f.id <= (f.extended ? 0x1FFFFFFFu : 0x7FFu) && valid_length(f) && f.fd_flags <= 0xF &&
              (f.fd || f.fd_flags == 0) && f.timestamp_ns >= 0 && !parsed.interface_name.empty() &&
              parsed.interface_name.size() <= 15 &&
              parsed.interface_name.find(' ') == std::string::npos;
    for (std::size_t b = f.len; b < io::kCanFdMaxBytes; ++b)
      ok = ok && f.data[b] == 0;
    const std::size_t len2 = ok ? io::format_candump(f, parsed.interface_name, buf) : 0;
    ok = ok && len2 > 0 && io::parse_candump(std::string_view(buf.data(), len2), again, error) &&
         same_frame(again.frame, f) && again.interface_name == parsed.interface_name;
    if (!ok) {
      ++malformed_accepted;
      if (malformed_accepted <= 5)
        ADD_FAILURE() << "accepted but not well formed: [" << line << "]";
    }
  }
  EXPECT_EQ(round_trip_failures, 0u);
  EXPECT_EQ(malformed_accepted, 0u);
  EXPECT_EQ(silent_errors, 0u);
  EXPECT_GT(accepted_mutants, 1'000u);  // mutations that keep a valid line happen too
  EXPECT_GT(rejected, 10'000u);
  std::printf("candump: %llu mutated lines accepted, %llu rejected\n",
              static_cast<unsigned long long>(accepted_mutants),
              static_cast<unsigned long long>(rejected));
}

// The case the random test found: a heading a hair below 0 deg must wrap into [0, 2 pi)
// (docs/icd/canaerospace_input.md), not to 2 pi itself (fmod then + 2 pi rounds up to 2 pi).
TEST(DecoderRandom, HeadingJustBelowZeroWrapsBelowTwoPi) {
  for (const float deg : {-1e-30f, -1e-12f, -0.0f, -360.0f, 359.99997f}) {
    canas::Decoder d;
    ASSERT_EQ(d.decode(canas::encode_float(canas::id::kTrueHeading, 1, 0, deg), 1),
              canas::DecodeStatus::kAccepted);
    const double h = d.state()[canas::Field::kTrueHeading].value;
    EXPECT_GE(h, 0.0) << deg;
    EXPECT_LT(h, 2.0 * std::numbers::pi) << deg;
  }
}
