// candump log lines (can-utils `candump -L` format, as read by python-can and canplayer).

#include "io/candump.hpp"

#include <gtest/gtest.h>

#include <array>
#include <filesystem>
#include <fstream>
#include <random>
#include <string>

namespace io = radar_emu::io;

namespace {
std::string format(const io::CanFrame& f, std::string_view iface = "can0") {
  std::array<char, io::kCandumpMaxLine> buf{};
  const std::size_t n = io::format_candump(f, iface, buf);
  return std::string(buf.data(), n);
}
}  // namespace

TEST(Candump, FormatsClassicExtendedAndFdLikeCandump) {
  io::CanFrame f;
  f.id = 0x123;
  f.len = 4;
  f.data = {0xDE, 0xAD, 0xBE, 0xEF};
  f.timestamp_ns = 1'700'000'000'123'456'789;  // microseconds are truncated like candump
  EXPECT_EQ(format(f), "(1700000000.123456) can0 123#DEADBEEF\n");
  f.extended = true;
  f.id = 0x1ABCDEF0;
  f.len = 1;
  f.data[0] = 0;
  f.timestamp_ns = 5'000'001'000;
  EXPECT_EQ(format(f, "vcan1"), "(5.000001) vcan1 1ABCDEF0#00\n");
  io::CanFrame fd;
  fd.fd = true;
  fd.fd_flags = 1;
  fd.id = 0x7FF;
  fd.len = 12;
  for (std::size_t i = 0; i < 12; ++i)
    fd.data[i] = static_cast<std::uint8_t>(i);
  EXPECT_EQ(format(fd), "(0.000000) can0 7FF##1000102030405060708090A0B\n");
  io::CanFrame empty;
  empty.id = 0x1;
  EXPECT_EQ(format(empty), "(0.000000) can0 001#\n");
}

TEST(Candump, ParsesHandWrittenLines) {
  io::CandumpLine l;
  std::string err;
  ASSERT_TRUE(io::parse_candump("(1700000000.123456) can0 123#DEADBEEF\n", l, err)) << err;
  EXPECT_EQ(l.interface_name, "can0");
  EXPECT_EQ(l.frame.id, 0x123u);
  EXPECT_FALSE(l.frame.extended);
  EXPECT_EQ(l.frame.len, 4);
  EXPECT_EQ(l.frame.data[3], 0xEF);
  EXPECT_EQ(l.frame.timestamp_ns, 1'700'000'000'123'456'000);
  ASSERT_TRUE(io::parse_candump("(0.000001) vcan0 1FFFFFFF#0102", l, err)) << err;
  EXPECT_TRUE(l.frame.extended);
  EXPECT_EQ(l.frame.id, 0x1FFFFFFFu);
  ASSERT_TRUE(io::parse_candump("(1.000000) can1 456##3aabb", l, err)) << err;
  EXPECT_TRUE(l.frame.fd);
  EXPECT_EQ(l.frame.fd_flags, 3);
  EXPECT_EQ(l.frame.len, 2);
  EXPECT_EQ(l.frame.data[0], 0xAA);
}

TEST(Candump, RejectsMalformedLinesWithAReason) {
  const char* bad[] = {
      "",
      "no stamp can0 123#00",
      "(1700000000.123456 can0 123#00",
      "(1700000000.12345) can0 123#00",  // 5 decimals
      "(abc.123456) can0 123#00",
      "(1.000000)can0 123#00",
      "(1.000000) can0",
      "(1.000000) can0 123",
      "(1.000000) can0 12#00",   // 2-digit id
      "(1.000000) can0 800#00",  // > 0x7FF in 3 digits
      "(1.000000) can0 G23#00",
      "(1.000000) can0 123#0",  // odd hex count
      "(1.000000) can0 123#0011223344556677889",
      "(1.000000) can0 123#001122334455667788",  // 9 bytes classic
      ("(1.000000) can0 123##1"
       "00112233445566778899"),  // FD length 10 not allowed
      "(1.000000) can0 123##",
      "(1.000000) can0 123#R",
      "(1.000000) averyveryverylongname 123#00",
      "(1.000000) can0 123#zz",
  };
  for (const char* line : bad) {
    io::CandumpLine l;
    std::string err;
    EXPECT_FALSE(io::parse_candump(line, l, err)) << "accepted: " << line;
    EXPECT_FALSE(err.empty()) << line;
    EXPECT_EQ(err.find('\n'), std::string::npos);
  }
}

TEST(Candump, FormatParseRoundTripAtFixedSeed) {
  const std::uint32_t seed = 777;
  std::cout << "seed " << seed << "\n";
  std::mt19937 rng(seed);
  const std::uint8_t fd_lengths[] = {0, 1, 5, 8, 12, 16, 20, 24, 32, 48, 64};
  for (int i = 0; i < 5000; ++i) {
    io::CanFrame f;
    f.fd = rng() % 3 == 0;
    f.extended = rng() % 2 == 0;
    f.id = f.extended ? rng() & 0x1FFFFFFF : rng() & 0x7FF;
    f.len = f.fd ? fd_lengths[rng() % std::size(fd_lengths)] : static_cast<std::uint8_t>(rng() % 9);
    f.fd_flags = f.fd ? static_cast<std::uint8_t>(rng() % 16) : 0;
    for (std::size_t b = 0; b < f.len; ++b)
      f.data[b] = static_cast<std::uint8_t>(rng());
    f.timestamp_ns = static_cast<std::int64_t>(rng() % 2'000'000'000) * 1'000'000'000 +
                     static_cast<std::int64_t>(rng() % 1'000'000) * 1000;
    io::CandumpLine l;
    std::string err;
    const std::string line = format(f);
    ASSERT_TRUE(io::parse_candump(line, l, err)) << line << ": " << err;
    ASSERT_EQ(l.frame.id, f.id);
    ASSERT_EQ(l.frame.len, f.len);
    ASSERT_EQ(l.frame.extended, f.extended);
    ASSERT_EQ(l.frame.fd, f.fd);
    ASSERT_EQ(l.frame.fd_flags, f.fd_flags);
    ASSERT_EQ(l.frame.timestamp_ns, f.timestamp_ns);
    ASSERT_TRUE(std::equal(f.data.begin(), f.data.begin() + f.len, l.frame.data.begin()));
  }
}

TEST(Candump, RandomBytesNeverCrashAtFixedSeed) {
  const std::uint32_t seed = 4711;
  std::cout << "seed " << seed << "\n";
  std::mt19937 rng(seed);
  const std::string alphabet = "()0123456789.#abcdefABCDEF can0R\n\r";
  for (int i = 0; i < 100'000; ++i) {
    std::string s(rng() % 120, ' ');
    for (auto& c : s)
      c = alphabet[rng() % alphabet.size()];
    io::CandumpLine l;
    std::string err;
    if (io::parse_candump(s, l, err)) {
      ASSERT_LE(l.frame.len, io::kCanFdMaxBytes);
    }
  }
}

TEST(Candump, RecorderWritesAndReaderReportsFileAndLine) {
  const auto dir = std::filesystem::temp_directory_path() / "radar_emu_candump_test";
  std::filesystem::create_directories(dir);
  io::CandumpRecorder rec("can0", 2);
  io::CanFrame f;
  f.id = 0x10;
  f.len = 1;
  EXPECT_TRUE(rec.record(f));
  EXPECT_TRUE(rec.record(f));
  EXPECT_FALSE(rec.record(f));
  EXPECT_EQ(rec.overflowed(), 1u);
  rec.write_file(dir / "a.log");
  const auto lines = io::read_candump_file(dir / "a.log");
  ASSERT_EQ(lines.size(), 2u);
  EXPECT_EQ(lines[1].frame.id, 0x10u);
  {
    std::ofstream out(dir / "bad.log");
    out << "(1.000000) can0 010#00\n(1.000000) can0 010#0\n";
  }
  try {
    (void)io::read_candump_file(dir / "bad.log");
    FAIL() << "no error";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("bad.log:2:"), std::string::npos) << e.what();
  }
  EXPECT_THROW((void)io::read_candump_file(dir / "missing.log"), std::runtime_error);
}
