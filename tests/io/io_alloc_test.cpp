// The bus codecs' frame path must not allocate (style.md: nothing in the frame path allocates):
// count every operator new while encoding and decoding classic and CAN FD detection lists and
// decoding CANaerospace frames with a configured decoder. Its own executable:
// tests/alloc_counter.cpp replaces the global operator new.

#include <gtest/gtest.h>

#include <cstdint>
#include <vector>

#include "io/canaerospace.hpp"
#include "io/detection_icd.hpp"
#include "tests/alloc_counter.hpp"

namespace io = radar_emu::io;
namespace icd = radar_emu::io::icd;
namespace canas = radar_emu::io::canas;

TEST(IoAllocation, CodecsDoNotAllocate) {
  std::vector<icd::Detection> dets(icd::kMaxDetectionsPerFrame);
  for (std::size_t i = 0; i < dets.size(); ++i) {
    dets[i].range_m = 100.0 + static_cast<double>(i);
    dets[i].snr_db = 20.0;
    dets[i].range_std_m = 1.5;
  }
  std::vector<io::CanFrame> classic(icd::frames_for(icd::kMaxDetectionsPerFrame));
  std::vector<io::CanFrame> fd(icd::frames_for_fd(icd::kMaxDetectionsPerFrame));
  canas::DecoderConfig config;
  config[canas::Field::kLatitude].can_id = 1049;
  config.node_id = 1;
  canas::Decoder canas_decoder(config);  // setup: may allocate
  icd::ListDecoder list_decoder;
  std::uint64_t complete = 0;

  radar_emu::test::start_counting_allocations();
  for (int frame = 0; frame < 50; ++frame) {
    icd::Header h;
    h.frame_counter = static_cast<std::uint16_t>(frame);
    const icd::EncodeResult c = icd::encode(h, dets, classic);
    const icd::EncodeResult f = icd::encode_fd(h, dets, fd);
    for (std::size_t i = 0; i < c.frames; ++i)
      complete += list_decoder.feed(classic[i]) == icd::FeedStatus::kComplete ? 1u : 0u;
    for (std::size_t i = 0; i < f.frames; ++i)
      complete += list_decoder.feed(fd[i]) == icd::FeedStatus::kComplete ? 1u : 0u;
    const auto code = static_cast<std::uint8_t>(frame);
    (void)canas_decoder.decode(canas::encode_float(canas::id::kPitchAngle, 1, code, 1.0f), frame);
    (void)canas_decoder.decode(canas::encode_float(canas::id::kRollAngle, 2, code, 1.0f), frame);
    // A DOUBLE pair takes two message codes (DOUBLEH c, DOUBLEL c + 1), so pairs advance by 2.
    const auto [hi, lo] = canas::encode_double(1049, 1, static_cast<std::uint8_t>(2 * frame), 48.0);
    (void)canas_decoder.decode(hi, frame);
    (void)canas_decoder.decode(lo, frame);
  }
  const std::uint64_t allocations = radar_emu::test::stop_counting_allocations();
  EXPECT_EQ(allocations, 0u);
  EXPECT_EQ(complete, 100u);
  EXPECT_EQ(canas_decoder.counters().accepted, 100u);
  EXPECT_EQ(canas_decoder.counters().other_node, 50u);
}
