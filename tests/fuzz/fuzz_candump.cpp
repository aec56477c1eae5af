// Harness: the candump log parser (io/candump.hpp) on arbitrary text, line by line.
//
// Oracles: a line that parses gives a frame inside CAN's limits (11-bit identifier unless
// extended, 29-bit if extended; at most 8 bytes classic, a CAN FD length (0..8, 12, 16, 20, 24,
// 32, 48, 64) on FD; bytes past the length zero); formatting it again gives a line that parses
// to the same frame and interface name (the recorder's logs replay exactly); a line that does
// not parse has an error message.

#include <array>
#include <string>
#include <string_view>

#include "io/candump.hpp"
#include "tests/fuzz/fuzz_input.hpp"
#include "tests/fuzz/harnesses.hpp"

namespace radar_emu::fuzz {

namespace {

bool fd_length(std::size_t n) {
  return n <= 8 || n == 12 || n == 16 || n == 20 || n == 24 || n == 32 || n == 48 || n == 64;
}

bool same(const io::CanFrame& a, const io::CanFrame& b) {
  return a.id == b.id && a.len == b.len && a.extended == b.extended && a.fd == b.fd &&
         a.fd_flags == b.fd_flags && a.data == b.data && a.timestamp_ns == b.timestamp_ns;
}

void one_line(std::string_view line) {
  io::CandumpLine parsed;
  std::string error;
  if (!io::parse_candump(line, parsed, error)) {
    FUZZ_CHECK(!error.empty());
    return;
  }
  const io::CanFrame& f = parsed.frame;
  FUZZ_CHECK(f.id <= (f.extended ? 0x1FFFFFFFu : 0x7FFu));
  FUZZ_CHECK(f.fd ? fd_length(f.len) : f.len <= io::kCanClassicMaxBytes);
  FUZZ_CHECK(f.fd || f.fd_flags == 0);
  FUZZ_CHECK(f.fd_flags <= 0xF);
  FUZZ_CHECK(f.timestamp_ns >= 0);
  for (std::size_t i = f.len; i < f.data.size(); ++i)
    FUZZ_CHECK(f.data[i] == 0);
  FUZZ_CHECK(!parsed.interface_name.empty() && parsed.interface_name.size() <= 15);

  std::array<char, io::kCandumpMaxLine> text{};
  const std::size_t n = io::format_candump(f, parsed.interface_name, text);
  FUZZ_CHECK(n > 0 && n <= text.size());
  io::CandumpLine again;
  FUZZ_CHECK(io::parse_candump(std::string_view(text.data(), n), again, error));
  FUZZ_CHECK(same(again.frame, f));
  FUZZ_CHECK(again.interface_name == parsed.interface_name);
}

}  // namespace

int candump(const std::uint8_t* data, std::size_t size) {
  std::string_view text(reinterpret_cast<const char*>(data), size);
  while (!text.empty()) {
    const std::size_t nl = text.find('\n');
    one_line(text.substr(0, nl));
    if (nl == std::string_view::npos)
      break;
    text.remove_prefix(nl + 1);
  }
  return 0;
}

}  // namespace radar_emu::fuzz
