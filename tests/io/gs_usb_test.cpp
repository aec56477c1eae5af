// gs_usb protocol layer, checked against Linux drivers/net/can/usb/gs_usb.c: the byte layouts
// below are written out by hand from its packed structs (gs_host_config, gs_device_mode,
// gs_device_bittiming, gs_device_bt_const, gs_host_frame with classic_can(_ts)/canfd(_ts)), the
// request codes from enum gs_usb_breq, the setup order from gs_usb_probe/gs_make_candev/
// gs_can_open. Bit timing is checked against the closed form bit rate = fclk / (brp * (1 + prop +
// ps1 + ps2)), an exhaustive search over all settings, and the buses.md example (48 MHz,
// 1 Mbit/s: brp 3, prop 1, ps1 12, ps2 2). The libusb path runs init + enumerate for real.

#include "io/gs_usb.hpp"

#include <gtest/gtest.h>
#include <linux/can.h>
#include <linux/can/error.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <map>
#include <memory>
#include <span>
#include <stdexcept>
#include <string>
#include <vector>

#include "io/socketcan.hpp"
#include "tests/alloc_counter.hpp"

namespace radar_emu::io {
namespace {

using Bytes = std::vector<std::uint8_t>;

// ---- Limits of real controllers ------------------------------------------------------------

// STM32F0 bxCAN (candleLight, CANable): CAN_BTR TS1 4 bits, TS2 3 bits, SJW 2 bits, BRP 10 bits,
// each register value + 1 (RM0091, bxCAN "Bit timing register"); candleLight reports these
// ranges and a 48 MHz clock in BT_CONST.
constexpr GsUsbTimingLimits kBxCan{1, 16, 1, 8, 4, 1, 1024, 1};
// STM32G4 FDCAN nominal / data phase (RM0440 FDCAN_NBTP: NTSEG1 8 bits, NTSEG2 7, NSJW 7, NBRP 9;
// FDCAN_DBTP: DTSEG1 5 bits, DTSEG2 4, DSJW 4, DBRP 5; each + 1).
constexpr GsUsbTimingLimits kFdCanNominal{1, 256, 1, 128, 128, 1, 512, 1};
constexpr GsUsbTimingLimits kFdCanData{1, 32, 1, 16, 16, 1, 32, 1};

// ---- Constants ---------------------------------------------------------------------------------

TEST(GsUsbConstants, RequestTypesAndCodes) {
  // USB 2.0 sec. 9.3.1 bmRequestType: D7 direction (1 = device-to-host), D6..5 type (2 = vendor),
  // D4..0 recipient (1 = interface).
  EXPECT_EQ(kGsUsbRequestTypeOut, (0 << 7) | (2 << 5) | 1);
  EXPECT_EQ(kGsUsbRequestTypeIn, (1 << 7) | (2 << 5) | 1);
  EXPECT_EQ(kGsUsbRequestTypeOut, 0x41);
  EXPECT_EQ(kGsUsbRequestTypeIn, 0xC1);
  // enum gs_usb_breq counts from GS_USB_BREQ_HOST_FORMAT = 0 in this order.
  const std::array<GsUsbRequest, 15> order{
      GsUsbRequest::kHostFormat,     GsUsbRequest::kBitTiming,      GsUsbRequest::kMode,
      GsUsbRequest::kBerr,           GsUsbRequest::kBtConst,        GsUsbRequest::kDeviceConfig,
      GsUsbRequest::kTimestamp,      GsUsbRequest::kIdentify,       GsUsbRequest::kGetUserId,
      GsUsbRequest::kSetUserId,      GsUsbRequest::kDataBitTiming,  GsUsbRequest::kBtConstExt,
      GsUsbRequest::kSetTermination, GsUsbRequest::kGetTermination, GsUsbRequest::kGetState};
  for (std::size_t i = 0; i < order.size(); ++i)
    EXPECT_EQ(static_cast<std::size_t>(order[i]), i) << to_string(order[i]);
  EXPECT_EQ(kGsUsbVendorId, 0x1D50);
  EXPECT_EQ(kGsUsbProductId, 0x606F);
  EXPECT_EQ(kGsUsbEndpointIn, 0x81);
  EXPECT_EQ(kGsUsbEndpointOut, 0x02);
  // struct_size(hf, classic_can, 1) etc.: 12-byte header + 8 / +8+4 / +64 / +64+4.
  EXPECT_EQ(kGsUsbClassicFrameBytes, 20U);
  EXPECT_EQ(kGsUsbClassicTsFrameBytes, 24U);
  EXPECT_EQ(kGsUsbFdFrameBytes, 76U);
  EXPECT_EQ(kGsUsbFdTsFrameBytes, 80U);
}

TEST(GsUsbFrames, CanFdDlcTable) {
  // ISO 11898-1:2015 DLC coding: 9..15 -> 12, 16, 20, 24, 32, 48, 64 bytes.
  const std::array<int, 16> len{0, 1, 2, 3, 4, 5, 6, 7, 8, 12, 16, 20, 24, 32, 48, 64};
  for (std::uint8_t dlc = 0; dlc < 16; ++dlc) {
    EXPECT_EQ(can_fd_dlc_to_len(dlc), len[dlc]);
    EXPECT_EQ(can_fd_len_to_dlc(static_cast<std::uint8_t>(len[dlc])), dlc);
  }
  EXPECT_EQ(can_fd_len_to_dlc(13), 10);  // 13 bytes need the 16-byte DLC
  EXPECT_EQ(can_fd_len_to_dlc(33), 14);
}

// ---- Bit timing --------------------------------------------------------------------------------

// Exhaustive search: the smallest sample-point error any (brp, tseg1, tseg2) within the limits
// reaches at exactly `bitrate` (tseg1 >= 2 so that prop_seg and phase_seg1 are both >= 1).
double best_exact_sample_point_error(std::uint32_t clk, const GsUsbTimingLimits& l,
                                     std::uint32_t bitrate, double sp) {
  double best = 1.0;
  for (std::uint32_t brp = l.brp_min; brp <= l.brp_max; brp += l.brp_inc)
    for (std::uint32_t t1 = std::max(l.tseg1_min, 2U); t1 <= l.tseg1_max; ++t1)
      for (std::uint32_t t2 = l.tseg2_min; t2 <= l.tseg2_max; ++t2) {
        const std::uint64_t n = 1 + t1 + t2;
        if (static_cast<std::uint64_t>(brp) * n * bitrate != clk)
          continue;
        best = std::min(best, std::abs(static_cast<double>(1 + t1) / static_cast<double>(n) - sp));
      }
  return best;
}

struct TimingCase {
  const char* name;
  std::uint32_t clk_hz;
  GsUsbTimingLimits limits;
  std::uint32_t bitrate_bps;
  double sample_point;
  std::uint32_t brp;         // expected, worked out by hand
  std::uint32_t tq_per_bit;  // expected
};

TEST(GsUsbBitTiming, MatchesTheClosedFormAndAnExhaustiveSearch) {
  const std::array<TimingCase, 15> cases{{
      {"48MHz bxCAN 1M", 48'000'000, kBxCan, 1'000'000, 0.875, 3, 16},
      {"48MHz bxCAN 500k", 48'000'000, kBxCan, 500'000, 0.875, 6, 16},
      {"48MHz bxCAN 250k", 48'000'000, kBxCan, 250'000, 0.875, 12, 16},
      {"48MHz bxCAN 125k", 48'000'000, kBxCan, 125'000, 0.875, 24, 16},
      {"80MHz bxCAN-like 1M", 80'000'000, kBxCan, 1'000'000, 0.875, 5, 16},
      {"80MHz FDCAN 1M", 80'000'000, kFdCanNominal, 1'000'000, 0.875, 1, 80},
      {"80MHz FDCAN 500k", 80'000'000, kFdCanNominal, 500'000, 0.875, 1, 160},
      // 320 tq would need tseg1 = 279 > 256: brp 2 and 160 tq hit 87.5 % exactly.
      {"80MHz FDCAN 250k", 80'000'000, kFdCanNominal, 250'000, 0.875, 2, 160},
      {"80MHz FDCAN 125k", 80'000'000, kFdCanNominal, 125'000, 0.875, 4, 160},
      {"40MHz FDCAN 1M", 40'000'000, kFdCanNominal, 1'000'000, 0.875, 1, 40},
      {"40MHz FDCAN 500k", 40'000'000, kFdCanNominal, 500'000, 0.875, 1, 80},
      {"40MHz FDCAN 125k", 40'000'000, kFdCanNominal, 125'000, 0.875, 2, 160},
      {"80MHz FDCAN data 2M", 80'000'000, kFdCanData, 2'000'000, 0.75, 1, 40},
      {"80MHz FDCAN data 5M", 80'000'000, kFdCanData, 5'000'000, 0.75, 1, 16},
      {"40MHz FDCAN data 8M", 40'000'000, kFdCanData, 8'000'000, 0.80, 1, 5},
  }};
  for (const TimingCase& c : cases) {
    SCOPED_TRACE(c.name);
    const GsUsbBitTiming bt =
        compute_gs_usb_bit_timing(c.clk_hz, c.limits, c.bitrate_bps, c.sample_point);
    EXPECT_EQ(bt.brp, c.brp);
    EXPECT_EQ(bt.tq_per_bit(), c.tq_per_bit);
    // Closed form, in integers: clk = bitrate * brp * (1 + prop + ps1 + ps2).
    EXPECT_EQ(static_cast<std::uint64_t>(c.bitrate_bps) * bt.brp * bt.tq_per_bit(), c.clk_hz);
    EXPECT_DOUBLE_EQ(bt.bitrate_bps(c.clk_hz), static_cast<double>(c.bitrate_bps));
    // Within the device limits; tseg1 = prop + ps1.
    EXPECT_GE(bt.prop_seg + bt.phase_seg1, c.limits.tseg1_min);
    EXPECT_LE(bt.prop_seg + bt.phase_seg1, c.limits.tseg1_max);
    EXPECT_GE(bt.phase_seg2, c.limits.tseg2_min);
    EXPECT_LE(bt.phase_seg2, c.limits.tseg2_max);
    EXPECT_GE(bt.sjw, 1U);
    EXPECT_LE(bt.sjw, std::min({c.limits.sjw_max, bt.phase_seg1, bt.phase_seg2}));
    // The sample point is the best any exact setting reaches.
    EXPECT_NEAR(std::abs(bt.sample_point() - c.sample_point),
                best_exact_sample_point_error(c.clk_hz, c.limits, c.bitrate_bps, c.sample_point),
                1e-12);
    std::printf("  %-22s brp %4u prop %u ps1 %3u ps2 %3u sjw %3u  tq %3u  sp %.4f\n", c.name,
                bt.brp, bt.prop_seg, bt.phase_seg1, bt.phase_seg2, bt.sjw, bt.tq_per_bit(),
                bt.sample_point());
  }
}

TEST(GsUsbBitTiming, BusesMdExample) {
  // 48 MHz, 1 Mbit/s, sample point 87.5 %: brp 3, prop 1, ps1 12, ps2 2 (16 tq; 14/16 = 0.875).
  const GsUsbBitTiming bt = compute_gs_usb_bit_timing(48'000'000, kBxCan, 1'000'000);
  EXPECT_EQ(bt.brp, 3U);
  EXPECT_EQ(bt.prop_seg, 1U);
  EXPECT_EQ(bt.phase_seg1, 12U);
  EXPECT_EQ(bt.phase_seg2, 2U);
  EXPECT_EQ(bt.sjw, 2U);  // min(sjw_max 4, ps1 12, ps2 2)
  EXPECT_DOUBLE_EQ(bt.sample_point(), 0.875);
}

TEST(GsUsbBitTiming, ImpossibleRatesAreRejectedWithAReason) {
  auto message = [](std::uint32_t rate) {
    try {
      (void)compute_gs_usb_bit_timing(48'000'000, kBxCan, rate);
    } catch (const std::invalid_argument& e) {
      return std::string(e.what());
    }
    return std::string("accepted");
  };
  // 48e6 / 1.1e6 = 43.6 tq: the nearest settings give 48e6 / 44 = 1090909 bit/s, 0.83 % slow.
  EXPECT_EQ(message(1'100'000),
            "gsusb: bit rate 1100000 bit/s from a 48000000 Hz clock: closest is 1090909 bit/s, "
            "0.83 % off (at most 0.50 % allowed)");
  // 48e6 / 20e6 = 2.4 tq per bit, below the minimum of 1 + 2 + 1.
  EXPECT_EQ(message(20'000'000),
            "gsusb: bit rate 20000000 bit/s from a 48000000 Hz clock: no prescaler in 1..1024 "
            "gives 4..25 time quanta per bit");
  EXPECT_NE(message(0).find("must be positive"), std::string::npos);
  // 83.333 kbit/s is not exact (48e6 / 576 = 83333.33) but well within 0.5 %: accepted.
  const GsUsbBitTiming bt = compute_gs_usb_bit_timing(48'000'000, kBxCan, 83'333);
  EXPECT_NEAR(bt.bitrate_bps(48'000'000), 83'333.33, 0.01);
}

// ---- Control payloads -------------------------------------------------------------------------

TEST(GsUsbPacking, ControlPayloadsByteForByte) {
  // struct gs_host_config { __le32 byte_order; } = 0x0000beef.
  EXPECT_EQ(pack_gs_usb_host_config(), (std::array<std::uint8_t, 4>{0xEF, 0xBE, 0x00, 0x00}));
  // struct gs_device_mode { __le32 mode; __le32 flags; }: START with FD | HW_TIMESTAMP.
  EXPECT_EQ(pack_gs_usb_mode(kGsUsbModeStart, gs_usb_flag::kFd | gs_usb_flag::kHwTimestamp),
            (std::array<std::uint8_t, 8>{0x01, 0, 0, 0, 0x10, 0x01, 0, 0}));
  // struct gs_device_bittiming { prop_seg, phase_seg1, phase_seg2, sjw, brp } all __le32.
  GsUsbBitTiming bt;
  bt.prop_seg = 1;
  bt.phase_seg1 = 12;
  bt.phase_seg2 = 2;
  bt.sjw = 2;
  bt.brp = 0x0102;
  EXPECT_EQ(pack_gs_usb_bit_timing(bt),
            (std::array<std::uint8_t, 20>{1, 0, 0, 0, 12, 0, 0,    0,    2, 0,
                                          0, 0, 2, 0, 0,  0, 0x02, 0x01, 0, 0}));
}

Bytes le32s(std::initializer_list<std::uint32_t> words) {
  Bytes b;
  for (std::uint32_t w : words)
    for (int i = 0; i < 4; ++i)
      b.push_back(static_cast<std::uint8_t>(w >> (8 * i)));
  return b;
}

TEST(GsUsbPacking, ParsesDeviceConfigAndBtConst) {
  // struct gs_device_config { u8 reserved1..3; u8 icount; __le32 sw_version; __le32 hw_version; }
  const Bytes dconf{0, 0, 0, 1, 2, 0, 0, 0, 0x34, 0x12, 0, 0};
  const GsUsbDeviceConfig c = parse_gs_usb_device_config(dconf);
  EXPECT_EQ(c.icount, 1);
  EXPECT_EQ(c.channel_count(), 2U);
  EXPECT_EQ(c.sw_version, 2U);
  EXPECT_EQ(c.hw_version, 0x1234U);
  // struct gs_device_bt_const: feature, fclk_can, tseg1_min/max, tseg2_min/max, sjw_max,
  // brp_min/max/inc.
  const Bytes btc = le32s({0x113, 48'000'000, 1, 16, 1, 8, 4, 1, 1024, 1});
  const GsUsbBtConst b = parse_gs_usb_bt_const(btc);
  EXPECT_EQ(b.feature, 0x113U);
  EXPECT_EQ(b.fclk_can_hz, 48'000'000U);
  EXPECT_EQ(b.nominal.tseg1_max, 16U);
  EXPECT_EQ(b.nominal.tseg2_max, 8U);
  EXPECT_EQ(b.nominal.sjw_max, 4U);
  EXPECT_EQ(b.nominal.brp_max, 1024U);
  EXPECT_EQ(b.data.tseg1_max, 16U);  // no extended part: data = nominal
  // gs_device_bt_const_extended adds dtseg1_min .. dbrp_inc.
  const Bytes ext =
      le32s({0x513, 80'000'000, 1, 256, 1, 128, 128, 1, 512, 1, 1, 32, 1, 16, 16, 1, 32, 1});
  const GsUsbBtConst e = parse_gs_usb_bt_const(ext);
  EXPECT_EQ(e.nominal.tseg1_max, 256U);
  EXPECT_EQ(e.data.tseg1_max, 32U);
  EXPECT_EQ(e.data.tseg2_max, 16U);
  EXPECT_EQ(e.data.brp_max, 32U);
  // Short replies are refused with the expected size.
  try {
    (void)parse_gs_usb_bt_const(std::span(btc.data(), 12));
    FAIL();
  } catch (const std::runtime_error& err) {
    EXPECT_EQ(std::string(err.what()), "gsusb: BT_CONST reply has 12 bytes, expected 40");
  }
  EXPECT_THROW((void)parse_gs_usb_device_config(std::span(dconf.data(), 11)), std::runtime_error);
}

// ---- Host frames -------------------------------------------------------------------------------

TEST(GsUsbPacking, ClassicTxFrameByteForByte) {
  CanFrame f;
  f.id = 0x123;
  f.len = 3;
  f.data[0] = 0x11;
  f.data[1] = 0x22;
  f.data[2] = 0x33;
  GsUsbHostFrame hf;
  ASSERT_TRUE(to_gs_usb_frame(f, 5, 0, false, hf));
  std::array<std::uint8_t, kGsUsbMaxFrameBytes> out{};
  const GsUsbFrameFormat classic{false, false};
  ASSERT_EQ(pack_gs_usb_frame(hf, classic, out), 20U);
  // echo_id | can_id | can_dlc channel flags reserved | data[8]
  const Bytes expect{0x05, 0, 0, 0, 0x23, 0x01, 0, 0, 3, 0, 0, 0, 0x11, 0x22, 0x33, 0, 0, 0, 0, 0};
  EXPECT_EQ(Bytes(out.begin(), out.begin() + 20), expect);

  // Extended identifier: can_id carries CAN_EFF_FLAG (0x80000000), little endian.
  f.id = 0x1ABCDEF0;
  f.extended = true;
  f.len = 0;
  ASSERT_TRUE(to_gs_usb_frame(f, 0x3F, 1, false, hf));
  ASSERT_EQ(pack_gs_usb_frame(hf, classic, out), 20U);
  EXPECT_EQ(Bytes(out.begin(), out.begin() + 12),
            (Bytes{0x3F, 0, 0, 0, 0xF0, 0xDE, 0xBC, 0x9A, 0, 1, 0, 0}));
  // Too small an output buffer: nothing written.
  std::array<std::uint8_t, 19> small{};
  EXPECT_EQ(pack_gs_usb_frame(hf, classic, small), 0U);
}

TEST(GsUsbPacking, FdTxFrameByteForByte) {
  CanFrame f;
  f.id = 0x7FF;
  f.fd = true;
  f.fd_flags = 0x1;  // BRS
  f.len = 20;
  for (std::size_t i = 0; i < 20; ++i)
    f.data[i] = static_cast<std::uint8_t>(0xA0 + i);
  GsUsbHostFrame hf;
  EXPECT_FALSE(to_gs_usb_frame(f, 63, 0, false, hf));  // FD frame, channel not in FD mode
  ASSERT_TRUE(to_gs_usb_frame(f, 63, 0, true, hf));
  std::array<std::uint8_t, kGsUsbMaxFrameBytes> out{};
  ASSERT_EQ(pack_gs_usb_frame(hf, GsUsbFrameFormat{true, true}, out), 76U);  // no ts on TX
  Bytes expect{63,   0, 0, 0, 0xFF, 0x07, 0, 0,
               11,    // DLC 11 = 20 bytes
               0,     // channel
               0x06,  // GS_CAN_FLAG_FD 0x02 | GS_CAN_FLAG_BRS 0x04
               0};
  for (std::size_t i = 0; i < 64; ++i)
    expect.push_back(i < 20 ? static_cast<std::uint8_t>(0xA0 + i) : 0);
  EXPECT_EQ(Bytes(out.begin(), out.begin() + 76), expect);
  // In FD mode even classic frames travel in the 76-byte layout (gs_can_open, hf_size_tx).
  CanFrame c;
  c.id = 1;
  c.len = 1;
  ASSERT_TRUE(to_gs_usb_frame(c, 0, 0, true, hf));
  EXPECT_EQ(pack_gs_usb_frame(hf, GsUsbFrameFormat{true, false}, out), 76U);
  // Lengths that are not CAN FD lengths, and classic lengths > 8, are refused.
  f.len = 13;
  EXPECT_FALSE(to_gs_usb_frame(f, 0, 0, true, hf));
  c.len = 9;
  EXPECT_FALSE(to_gs_usb_frame(c, 0, 0, true, hf));
  c.len = 1;
  c.id = 0x800;  // 11-bit id out of range
  EXPECT_FALSE(to_gs_usb_frame(c, 0, 0, true, hf));
}

Bytes classic_rx_ts(std::uint32_t echo, std::uint32_t can_id, std::uint8_t dlc,
                    std::uint8_t channel, std::uint8_t flags, std::uint32_t ts_us) {
  Bytes b = le32s({echo, can_id});
  b.insert(b.end(), {dlc, channel, flags, 0});
  for (std::uint8_t i = 0; i < 8; ++i)
    b.push_back(static_cast<std::uint8_t>(0x10 + i));
  const Bytes ts = le32s({ts_us});
  b.insert(b.end(), ts.begin(), ts.end());
  return b;
}

TEST(GsUsbPacking, UnpacksReceivedFramesByteForByte) {
  // classic_can_ts: 12-byte header, data[8], __le32 timestamp_us at offset 20.
  const Bytes rx = classic_rx_ts(0xFFFFFFFF, 0x345, 8, 0, 0, 0x12345678);
  ASSERT_EQ(rx.size(), 24U);
  GsUsbHostFrame hf;
  ASSERT_EQ(unpack_gs_usb_frame(rx, GsUsbFrameFormat{false, true}, hf), GsUsbUnpack::kOk);
  EXPECT_EQ(hf.echo_id, kGsUsbRxEchoId);
  EXPECT_EQ(hf.can_id, 0x345U);
  EXPECT_EQ(hf.can_dlc, 8);
  EXPECT_EQ(hf.data[7], 0x17);
  EXPECT_EQ(hf.timestamp_us, 0x12345678U);
  CanFrame f;
  ASSERT_EQ(from_gs_usb_frame(hf, f), GsUsbFrameKind::kData);
  EXPECT_EQ(f.id, 0x345U);
  EXPECT_EQ(f.len, 8);
  EXPECT_EQ(f.data[0], 0x10);

  // canfd_ts: data[64], timestamp at offset 76; DLC 15 = 64 bytes; ESI.
  Bytes fd = le32s({0xFFFFFFFF, CAN_EFF_FLAG | 0x1234567});
  fd.insert(fd.end(), {15, 0, 0x0A, 0});  // FD 0x02 | ESI 0x08
  for (std::size_t i = 0; i < 64; ++i)
    fd.push_back(static_cast<std::uint8_t>(i));
  const Bytes ts = le32s({0xCAFEBABE});
  fd.insert(fd.end(), ts.begin(), ts.end());
  ASSERT_EQ(fd.size(), 80U);
  ASSERT_EQ(unpack_gs_usb_frame(fd, GsUsbFrameFormat{true, true}, hf), GsUsbUnpack::kOk);
  EXPECT_EQ(hf.timestamp_us, 0xCAFEBABEU);
  ASSERT_EQ(from_gs_usb_frame(hf, f), GsUsbFrameKind::kData);
  EXPECT_TRUE(f.fd);
  EXPECT_TRUE(f.extended);
  EXPECT_EQ(f.id, 0x1234567U);
  EXPECT_EQ(f.len, 64);
  EXPECT_EQ(f.fd_flags, 0x2);  // ESI
  EXPECT_EQ(f.data[63], 63);
  // Not in FD mode: the same frame is refused.
  EXPECT_EQ(unpack_gs_usb_frame(fd, GsUsbFrameFormat{false, true}, hf), GsUsbUnpack::kNotFdMode);

  // Classic DLC 9..15 means 8 bytes; above 15 is malformed; RTR and error frames are classified.
  GsUsbHostFrame h2;
  h2.can_dlc = 12;
  EXPECT_EQ(from_gs_usb_frame(h2, f), GsUsbFrameKind::kData);
  EXPECT_EQ(f.len, 8);
  h2.can_dlc = 16;
  EXPECT_EQ(from_gs_usb_frame(h2, f), GsUsbFrameKind::kBadDlc);
  h2.can_dlc = 0;
  h2.can_id = CAN_RTR_FLAG | 7;
  EXPECT_EQ(from_gs_usb_frame(h2, f), GsUsbFrameKind::kRemote);
  h2.can_id = CAN_ERR_FLAG | CAN_ERR_CRTL;
  EXPECT_EQ(from_gs_usb_frame(h2, f), GsUsbFrameKind::kError);
}

TEST(GsUsbPacking, TruncatedAndOversizedBuffersAreRejectedWithoutReadingPast) {
  // Each prefix is copied into its own heap buffer of exactly that size, so AddressSanitizer
  // would flag a read past its end.
  const Bytes full = classic_rx_ts(0xFFFFFFFF, 0x100, 1, 0, 0, 1);
  const GsUsbFrameFormat ts_format{false, true};
  GsUsbHostFrame hf;
  for (std::size_t n = 0; n < full.size(); ++n) {
    const Bytes prefix(full.begin(), full.begin() + static_cast<std::ptrdiff_t>(n));
    EXPECT_EQ(unpack_gs_usb_frame(prefix, ts_format, hf), GsUsbUnpack::kTruncated) << n;
  }
  Bytes longer = full;
  longer.push_back(0);
  EXPECT_EQ(unpack_gs_usb_frame(longer, ts_format, hf), GsUsbUnpack::kOversized);
  // Without time stamps a classic frame is 20 bytes; 24 is too long for that format.
  EXPECT_EQ(unpack_gs_usb_frame(full, GsUsbFrameFormat{false, false}, hf), GsUsbUnpack::kOversized);
  // In FD mode a classic frame may come padded to the FD size, and an FD-flagged frame needs all
  // 64 data bytes.
  Bytes padded = full;
  padded.resize(80, 0);
  EXPECT_EQ(unpack_gs_usb_frame(padded, GsUsbFrameFormat{true, true}, hf), GsUsbUnpack::kOk);
  EXPECT_EQ(hf.timestamp_us, 1U);  // at offset 20: the frame is classic
  Bytes fd_short = full;           // 24 bytes with the FD flag set
  fd_short[10] = gs_usb_frame_flag::kFd;
  EXPECT_EQ(unpack_gs_usb_frame(fd_short, GsUsbFrameFormat{true, true}, hf),
            GsUsbUnpack::kTruncated);
}

// ---- Echo pool ---------------------------------------------------------------------------------

TEST(GsUsbEchoPool, HandsOutEverySlotOnceAndMatchesEchoes) {
  GsUsbEchoPool pool;
  std::uint32_t id = 0;
  for (std::uint32_t i = 0; i < GsUsbEchoPool::kSlots; ++i) {
    ASSERT_TRUE(pool.acquire(id));
    EXPECT_EQ(id, i);
  }
  EXPECT_EQ(pool.in_flight(), 64U);
  EXPECT_FALSE(pool.acquire(id));  // exhausted
  EXPECT_TRUE(pool.release(10));
  EXPECT_FALSE(pool.release(10));  // a repeated echo
  EXPECT_FALSE(pool.release(64));  // never handed out
  EXPECT_FALSE(pool.release(kGsUsbRxEchoId));
  ASSERT_TRUE(pool.acquire(id));
  EXPECT_EQ(id, 10U);
  pool.reset();
  EXPECT_EQ(pool.in_flight(), 0U);
}

// ---- Endpoint over a fake transport ------------------------------------------------------------

struct Request {
  bool in = false;
  GsUsbRequest request{};
  std::uint16_t value = 0;
  std::uint16_t index = 0;
  Bytes data;  // OUT: what was sent; IN: how many bytes were asked for (size only)
};

// What the fake saw; shared so that the test can read it after the endpoint is gone.
struct FakeLog {
  std::vector<Request> requests;
  std::vector<std::string> events;  // "start_receiving 24", "stop_receiving"
  std::array<std::array<std::uint8_t, kGsUsbMaxFrameBytes>, 256> out{};
  std::array<std::size_t, 256> out_size{};
  std::array<std::uint32_t, 256> out_tag{};
  std::size_t outs = 0;
};

class FakeTransport final : public GsUsbTransport {
 public:
  FakeTransport(std::shared_ptr<FakeLog> log, std::map<GsUsbRequest, Bytes> replies)
      : log_(std::move(log)), replies_(std::move(replies)) {
    rx_.reserve(1024);
  }
  void control_out(GsUsbRequest request, std::uint16_t value, std::uint16_t index,
                   std::span<const std::uint8_t> data) override {
    log_->requests.push_back({false, request, value, index, Bytes(data.begin(), data.end())});
  }
  std::size_t control_in(GsUsbRequest request, std::uint16_t value, std::uint16_t index,
                         std::span<std::uint8_t> data) override {
    log_->requests.push_back({true, request, value, index, Bytes(data.size())});
    const auto it = replies_.find(request);
    if (it == replies_.end())
      throw std::runtime_error("gsusb: " + std::string(to_string(request)) +
                               " request failed (LIBUSB_ERROR_PIPE)");
    const std::size_t n = std::min(data.size(), it->second.size());
    std::copy_n(it->second.begin(), n, data.begin());
    return n;
  }
  void start_receiving(std::size_t bytes) override {
    log_->events.push_back("start_receiving " + std::to_string(bytes));
  }
  void stop_receiving() noexcept override { log_->events.emplace_back("stop_receiving"); }
  bool bulk_out(std::span<const std::uint8_t> bytes, std::uint32_t tag) noexcept override {
    if (refuse_out || log_->outs >= log_->out.size())
      return false;
    log_->out_tag[log_->outs] = tag;
    std::copy(bytes.begin(), bytes.end(), log_->out[log_->outs].begin());
    log_->out_size[log_->outs++] = bytes.size();
    return true;
  }
  bool poll_in(GsUsbRxTransfer& out) noexcept override {
    if (next_ >= rx_.size())
      return false;
    out = rx_[next_++];
    return true;
  }
  bool poll_out_failed(std::uint32_t& tag) noexcept override {
    if (failed_.empty())
      return false;
    tag = failed_.back();
    failed_.pop_back();
    return true;
  }
  /// Reports the OUT transfer tagged `tag` lost, as a USB error or timeout would.
  void fail_out(std::uint32_t tag) { failed_.push_back(tag); }
  /// Queues one IN transfer as the device would complete it.
  void deliver(const Bytes& b, std::int64_t host_time_ns = 0, bool overflow = false) {
    GsUsbRxTransfer t;
    t.size = static_cast<std::uint32_t>(std::min(b.size(), t.bytes.size()));
    std::copy_n(b.begin(), t.size, t.bytes.begin());
    t.host_time_ns = host_time_ns;
    t.overflow = overflow;
    rx_.push_back(t);
  }
  bool refuse_out = false;

 private:
  std::shared_ptr<FakeLog> log_;
  std::map<GsUsbRequest, Bytes> replies_;
  std::vector<GsUsbRxTransfer> rx_;
  std::size_t next_ = 0;
  std::vector<std::uint32_t> failed_;
};

// A candleLight: one channel, 48 MHz bxCAN, listen-only, loop-back, HW time stamps, identify.
constexpr std::uint32_t kCandleFeatures = gs_usb_flag::kListenOnly | gs_usb_flag::kLoopBack |
                                          gs_usb_flag::kHwTimestamp | gs_usb_flag::kIdentify;

std::map<GsUsbRequest, Bytes> candlelight_replies(std::uint32_t feature = kCandleFeatures,
                                                  std::uint32_t timestamp_us = 0xFFFFFF00) {
  return {
      {GsUsbRequest::kDeviceConfig, Bytes{0, 0, 0, 0, 2, 0, 0, 0, 1, 0, 0, 0}},
      {GsUsbRequest::kBtConst, le32s({feature, 48'000'000, 1, 16, 1, 8, 4, 1, 1024, 1})},
      {GsUsbRequest::kTimestamp, le32s({timestamp_us})},
  };
}

struct Rig {
  std::shared_ptr<FakeLog> log = std::make_shared<FakeLog>();
  FakeTransport* fake = nullptr;
  std::unique_ptr<GsUsbEndpoint> ep;
  explicit Rig(const GsUsbOptions& o,
               std::map<GsUsbRequest, Bytes> replies = candlelight_replies()) {
    auto t = std::make_unique<FakeTransport>(log, std::move(replies));
    fake = t.get();
    ep = std::make_unique<GsUsbEndpoint>(std::move(t), o);
  }
};

void expect_request(const Request& r, bool in, GsUsbRequest req, std::uint16_t value,
                    std::uint16_t index, const Bytes& data) {
  SCOPED_TRACE(to_string(req));
  EXPECT_EQ(r.in, in);
  EXPECT_EQ(r.request, req);
  EXPECT_EQ(r.value, value);
  EXPECT_EQ(r.index, index);
  EXPECT_EQ(r.data, data);
}

TEST(GsUsbEndpoint, SetupSequenceAsTheKernelDriverRunsIt) {
  std::shared_ptr<FakeLog> log;
  {
    GsUsbOptions o;
    o.bitrate_bps = 1'000'000;
    Rig rig(o);
    log = rig.log;
    EXPECT_EQ(rig.ep->mode_flags(), gs_usb_flag::kHwTimestamp);
    EXPECT_EQ(rig.ep->bus_state(), CanBusState::kErrorActive);
    EXPECT_EQ(rig.ep->device_config().sw_version, 2U);
    ASSERT_EQ(log->requests.size(), 7U);
    const auto& r = log->requests;
    expect_request(r[0], false, GsUsbRequest::kHostFormat, 1, 0, Bytes{0xEF, 0xBE, 0, 0});
    expect_request(r[1], true, GsUsbRequest::kDeviceConfig, 1, 0, Bytes(12));
    expect_request(r[2], true, GsUsbRequest::kBtConst, 0, 0, Bytes(40));
    expect_request(r[3], false, GsUsbRequest::kMode, 0, 0, Bytes{0, 0, 0, 0, 0, 0, 0, 0});
    expect_request(r[4], false, GsUsbRequest::kBitTiming, 0, 0,
                   Bytes{1, 0, 0, 0, 12, 0, 0, 0, 2, 0, 0, 0, 2, 0, 0, 0, 3, 0, 0, 0});
    expect_request(r[5], true, GsUsbRequest::kTimestamp, 0, 0, Bytes(4));
    expect_request(r[6], false, GsUsbRequest::kMode, 0, 0,
                   Bytes{1, 0, 0, 0, 0x10, 0, 0, 0});  // START, GS_CAN_MODE_HW_TIMESTAMP
    ASSERT_EQ(log->events.size(), 1U);
    EXPECT_EQ(log->events[0], "start_receiving 24");  // classic_can_ts frames
  }
  // Destruction resets the channel and stops the IN path.
  ASSERT_EQ(log->requests.size(), 8U);
  expect_request(log->requests[7], false, GsUsbRequest::kMode, 0, 0, Bytes(8));
  EXPECT_EQ(log->events.back(), "stop_receiving");
}

TEST(GsUsbEndpoint, FdSetupReadsExtendedConstantsAndSetsTheDataPhase) {
  auto replies = candlelight_replies();
  const std::uint32_t feature = gs_usb_flag::kFd | gs_usb_flag::kBtConstExt |
                                gs_usb_flag::kHwTimestamp | gs_usb_flag::kOneShot;
  replies[GsUsbRequest::kBtConst] = le32s({feature, 80'000'000, 1, 256, 1, 128, 128, 1, 512, 1});
  replies[GsUsbRequest::kBtConstExt] =
      le32s({feature, 80'000'000, 1, 256, 1, 128, 128, 1, 512, 1, 1, 32, 1, 16, 16, 1, 32, 1});
  GsUsbOptions o;
  o.fd = true;
  o.bitrate_bps = 500'000;
  o.dbitrate_bps = 2'000'000;
  o.one_shot = true;
  o.hw_timestamps = false;
  Rig rig(o, replies);
  const auto& r = rig.log->requests;
  ASSERT_EQ(r.size(), 8U);
  expect_request(r[2], true, GsUsbRequest::kBtConst, 0, 0, Bytes(40));
  expect_request(r[3], true, GsUsbRequest::kBtConstExt, 0, 0, Bytes(72));
  expect_request(r[4], false, GsUsbRequest::kMode, 0, 0, Bytes(8));
  // 500 kbit/s from 80 MHz: brp 1, 160 tq, prop 1, ps1 138, ps2 20, sjw 20.
  expect_request(r[5], false, GsUsbRequest::kBitTiming, 0, 0, le32s({1, 138, 20, 20, 1}));
  // 2 Mbit/s data phase, 75 %: brp 1, 40 tq, prop 1, ps1 28, ps2 10, sjw 10.
  expect_request(r[6], false, GsUsbRequest::kDataBitTiming, 0, 0, le32s({1, 28, 10, 10, 1}));
  // START with GS_CAN_MODE_FD (0x100) | GS_CAN_MODE_ONE_SHOT (0x08).
  expect_request(r[7], false, GsUsbRequest::kMode, 0, 0, Bytes{1, 0, 0, 0, 0x08, 0x01, 0, 0});
  EXPECT_EQ(rig.log->events[0], "start_receiving 76");
}

TEST(GsUsbEndpoint, SetupRefusalsAreOneLineErrors) {
  auto error = [](const GsUsbOptions& o, std::map<GsUsbRequest, Bytes> replies) {
    try {
      Rig rig(o, std::move(replies));
    } catch (const std::exception& e) {
      return std::string(e.what());
    }
    return std::string("accepted");
  };
  GsUsbOptions fd;
  fd.fd = true;
  EXPECT_EQ(error(fd, candlelight_replies()),
            "gsusb: the device has no CAN FD (BT_CONST feature 0x00000033)");
  GsUsbOptions ch;
  ch.channel = 1;
  EXPECT_EQ(error(ch, candlelight_replies()),
            "gsusb: channel 1 requested, the device has 1 channel(s)");
  auto short_btc = candlelight_replies();
  short_btc[GsUsbRequest::kBtConst].resize(12);
  EXPECT_EQ(error(GsUsbOptions{}, short_btc), "gsusb: BT_CONST reply has 12 bytes, expected 40");
  auto no_ts = candlelight_replies();
  no_ts.erase(GsUsbRequest::kTimestamp);
  EXPECT_EQ(error(GsUsbOptions{}, no_ts), "gsusb: TIMESTAMP request failed (LIBUSB_ERROR_PIPE)");
  GsUsbOptions rate;
  rate.bitrate_bps = 1'100'000;
  EXPECT_NE(error(rate, candlelight_replies()).find("closest is 1090909 bit/s"), std::string::npos);
}

Bytes classic_rx(std::uint32_t echo, std::uint32_t can_id, std::uint8_t dlc, std::uint8_t flags = 0,
                 std::uint8_t channel = 0) {
  Bytes b = le32s({echo, can_id});
  b.insert(b.end(), {dlc, channel, flags, 0});
  for (std::uint8_t i = 0; i < 8; ++i)
    b.push_back(static_cast<std::uint8_t>(0x40 + i));
  return b;
}

TEST(GsUsbEndpoint, MatchesEchoesAndCountsWhatItRejects) {
  GsUsbOptions o;
  o.hw_timestamps = false;  // 20-byte frames
  o.timestamp_offset_ns = 1000;
  Rig rig(o);
  GsUsbEndpoint& ep = *rig.ep;
  CanFrame f;
  f.id = 0x200;
  f.len = 2;
  f.data[0] = 0xAA;
  f.data[1] = 0xBB;
  for (int i = 0; i < 3; ++i)
    ASSERT_TRUE(ep.send(f));
  ASSERT_EQ(rig.log->outs, 3U);
  EXPECT_EQ(rig.log->out_size[0], 20U);
  // The third frame went out with echo id 2.
  EXPECT_EQ(Bytes(rig.log->out[2].begin(), rig.log->out[2].begin() + 20),
            (Bytes{2, 0, 0, 0, 0x00, 0x02, 0, 0, 2, 0, 0, 0, 0xAA, 0xBB, 0, 0, 0, 0, 0, 0}));
  EXPECT_EQ(ep.echoes_in_flight(), 3U);

  FakeTransport& dev = *rig.fake;
  dev.deliver(classic_rx(1, 0x200, 2));                   // echo of frame 1
  dev.deliver(classic_rx(7, 0x200, 2));                   // echo of nothing
  dev.deliver(classic_rx(1, 0x200, 2));                   // echo 1 again
  dev.deliver(classic_rx(kGsUsbRxEchoId, 0x7, 4, 0, 1));  // another channel
  dev.deliver(Bytes(11, 0));                              // shorter than the header
  dev.deliver(Bytes(100, 0));                             // longer than any frame
  dev.deliver(Bytes(20, 0), 0, /*overflow=*/true);        // libusb overflow
  Bytes fdflag = classic_rx(kGsUsbRxEchoId, 0x5, 1, gs_usb_frame_flag::kFd);
  dev.deliver(fdflag);  // FD frame outside FD mode
  dev.deliver(classic_rx(kGsUsbRxEchoId, CAN_RTR_FLAG | 0x9, 0));
  Bytes err = classic_rx(kGsUsbRxEchoId, CAN_ERR_FLAG | CAN_ERR_CRTL, 8);
  err[12 + 1] = CAN_ERR_CRTL_TX_PASSIVE;
  dev.deliver(err);  // error frame: passive
  dev.deliver(classic_rx(kGsUsbRxEchoId, 0x123, 3, gs_usb_frame_flag::kOverflow), 5'000);

  CanFrame got;
  ASSERT_TRUE(ep.receive(got));
  EXPECT_EQ(got.id, 0x123U);
  EXPECT_EQ(got.len, 3);
  EXPECT_EQ(got.data[2], 0x42);
  EXPECT_EQ(got.data[3], 0);                  // bytes past len are zero
  EXPECT_EQ(got.timestamp_ns, 5'000 + 1000);  // host time of the transfer + offset
  EXPECT_FALSE(ep.receive(got));

  const GsUsbStats& s = ep.stats();
  EXPECT_EQ(s.echoes, 1U);
  EXPECT_EQ(s.unknown_echoes, 2U);
  EXPECT_EQ(s.rx_wrong_channel, 1U);
  EXPECT_EQ(s.rx_truncated, 1U);
  EXPECT_EQ(s.rx_oversized, 2U);
  EXPECT_EQ(s.rx_malformed, 1U);
  EXPECT_EQ(s.rx_rtr_dropped, 1U);
  EXPECT_EQ(s.frames_received, 1U);
  EXPECT_EQ(ep.echoes_in_flight(), 2U);
  EXPECT_EQ(ep.bus_state(), CanBusState::kErrorPassive);
  EXPECT_EQ(ep.error_counters().error_passive, 1U);
  EXPECT_EQ(ep.error_counters().rx_overflows, 1U);
}

TEST(GsUsbEndpoint, RefusesWhenAllEchoIdsAreInFlightOrTheQueueIsFull) {
  GsUsbOptions o;
  o.hw_timestamps = false;
  Rig rig(o);
  GsUsbEndpoint& ep = *rig.ep;
  CanFrame f;
  f.id = 0x10;
  for (std::uint32_t i = 0; i < GsUsbEchoPool::kSlots; ++i)
    ASSERT_TRUE(ep.send(f)) << i;
  EXPECT_FALSE(ep.send(f));
  EXPECT_EQ(ep.stats().tx_pool_exhausted, 1U);
  // The device confirms frame 17: one slot frees and the next frame takes id 17.
  rig.fake->deliver(classic_rx(17, 0x10, 0));
  CanFrame got;
  EXPECT_FALSE(ep.receive(got));  // an echo is not a received frame (receive_own off)
  ASSERT_TRUE(ep.send(f));
  EXPECT_EQ(rig.log->out[rig.log->outs - 1][0], 17);
  // A full transport queue: refused, counted, and the echo id given back.
  rig.fake->deliver(classic_rx(3, 0x10, 0));
  EXPECT_FALSE(ep.receive(got));
  rig.fake->refuse_out = true;
  EXPECT_FALSE(ep.send(f));
  EXPECT_EQ(ep.stats().tx_queue_full, 1U);
  EXPECT_EQ(ep.echoes_in_flight(), 63U);
  // Invalid frames never take an id.
  CanFrame fd;
  fd.fd = true;
  EXPECT_FALSE(ep.send(fd));
  EXPECT_EQ(ep.stats().tx_rejected, 1U);
  EXPECT_EQ(ep.stats().frames_sent, 65U);

  // All 64 in flight again; the transport reports frame 40 lost on USB: the next send reclaims
  // its id instead of refusing.
  rig.fake->refuse_out = false;
  ASSERT_TRUE(ep.send(f));
  EXPECT_EQ(ep.echoes_in_flight(), 64U);
  EXPECT_EQ(rig.log->out_tag[rig.log->outs - 1], 3U);  // the tag is the echo id
  rig.fake->fail_out(40);
  rig.fake->fail_out(40);  // a repeated report frees nothing more
  ASSERT_TRUE(ep.send(f));
  EXPECT_EQ(rig.log->out[rig.log->outs - 1][0], 40);
  EXPECT_EQ(ep.stats().tx_failed, 1U);
  EXPECT_EQ(ep.stats().tx_pool_exhausted, 1U);
}

TEST(GsUsbEndpoint, ReceiveOwnHandsOutEchoes) {
  GsUsbOptions o;
  o.hw_timestamps = false;
  o.receive_own = true;
  Rig rig(o);
  CanFrame f;
  f.id = 0x42;
  f.len = 1;
  ASSERT_TRUE(rig.ep->send(f));
  rig.fake->deliver(classic_rx(0, 0x42, 1), 77);
  CanFrame got;
  ASSERT_TRUE(rig.ep->receive(got));
  EXPECT_EQ(got.id, 0x42U);
  EXPECT_EQ(got.timestamp_ns, 77);
  EXPECT_EQ(rig.ep->stats().echoes, 1U);
}

TEST(GsUsbEndpoint, HardwareTimestampsFollowTheCounterAcrossItsWrap) {
  GsUsbOptions o;
  o.timestamp_offset_ns = -5;
  const std::int64_t before = realtime_now_ns();
  Rig rig(o, candlelight_replies(kCandleFeatures, 0xFFFFFF00));  // counter read at setup
  const std::int64_t after = realtime_now_ns();
  rig.fake->deliver(classic_rx_ts(kGsUsbRxEchoId, 0x1, 0, 0, 0, 0xFFFFFFF0));
  rig.fake->deliver(classic_rx_ts(kGsUsbRxEchoId, 0x2, 0, 0, 0, 0x00000010));  // wrapped
  CanFrame a;
  CanFrame b;
  ASSERT_TRUE(rig.ep->receive(a));
  ASSERT_TRUE(rig.ep->receive(b));
  // 0xFFFFFFF0 - 0xFFFFFF00 = 240 us after the setup read; 0x10 + 2^32 - 0xFFFFFFF0 = 32 us later.
  EXPECT_GE(a.timestamp_ns, before + 240'000 - 5);
  EXPECT_LE(a.timestamp_ns, after + 240'000 - 5);
  EXPECT_EQ(b.timestamp_ns - a.timestamp_ns, 32'000);
}

TEST(GsUsbEndpoint, SendAndReceiveNeverAllocate) {
  GsUsbOptions o;
  o.hw_timestamps = false;
  Rig rig(o);
  // Each round: send (takes echo id 0, the lowest free), then the device's echo of it and one
  // received frame.
  for (int i = 0; i < 200; ++i) {
    rig.fake->deliver(classic_rx(0, 0x10, 0));
    rig.fake->deliver(classic_rx(kGsUsbRxEchoId, 0x20, 8));
  }
  CanFrame f;
  f.id = 0x10;
  CanFrame got;
  std::uint64_t sent = 0;
  std::uint64_t received = 0;
  radar_emu::test::start_counting_allocations();
  for (int i = 0; i < 200; ++i) {
    sent += rig.ep->send(f) ? 1U : 0U;
    received += rig.ep->receive(got) ? 1U : 0U;
  }
  const std::uint64_t allocations = radar_emu::test::stop_counting_allocations();
  EXPECT_EQ(allocations, 0U);
  EXPECT_EQ(sent, 200U);
  EXPECT_EQ(received, 200U);
  EXPECT_EQ(rig.ep->stats().echoes, 200U);
}

// ---- libusb ------------------------------------------------------------------------------------

TEST(GsUsbDevice, LibusbInitAndEnumerateRun) {
  // Runs libusb_init and the device enumeration for real. The build machines have no USB
  // adapters (buses.md), so open() must fail with the one-line message; on a bench with an
  // adapter plugged in the list is simply printed.
  const std::vector<GsUsbDeviceInfo> devices = list_gs_usb_devices();
  for (const GsUsbDeviceInfo& d : devices)
    std::printf("  gs_usb device bus %u address %u %04x:%04x serial '%s' %s\n", d.bus, d.address,
                d.vendor_id, d.product_id, d.serial.c_str(), d.open_error.c_str());
  if (!devices.empty())
    GTEST_SKIP() << devices.size() << " gs_usb device(s) present: the no-device message is not "
                 << "checked here";
  try {
    (void)GsUsbDevice::open();
    FAIL() << "opened a device that enumeration did not list";
  } catch (const std::runtime_error& e) {
    EXPECT_EQ(std::string(e.what()), "gsusb: no candleLight/gs_usb device (USB 1D50:606F) found");
  }
  try {
    (void)GsUsbEndpoint::open("0123456789AB");
    FAIL();
  } catch (const std::runtime_error& e) {
    EXPECT_EQ(std::string(e.what()), "gsusb: no candleLight/gs_usb device (USB 1D50:606F) found");
  }
}

}  // namespace
}  // namespace radar_emu::io
