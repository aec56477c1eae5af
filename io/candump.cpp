#include "io/candump.hpp"

#include <charconv>
#include <cstdio>
#include <fstream>
#include <stdexcept>

namespace radar_emu::io {

namespace {

constexpr char kHex[] = "0123456789ABCDEF";

int hex_value(char c) noexcept {
  if (c >= '0' && c <= '9')
    return c - '0';
  if (c >= 'a' && c <= 'f')
    return c - 'a' + 10;
  if (c >= 'A' && c <= 'F')
    return c - 'A' + 10;
  return -1;
}

class Writer {
 public:
  explicit Writer(std::span<char> out) noexcept : out_(out) {}
  bool put(char c) noexcept {
    if (n_ >= out_.size())
      return ok_ = false;
    out_[n_++] = c;
    return true;
  }
  void put(std::string_view s) noexcept {
    for (char c : s)
      put(c);
  }
  void hex(std::uint32_t v, int digits) noexcept {
    for (int i = digits - 1; i >= 0; --i)
      put(kHex[(v >> (4 * i)) & 0xF]);
  }
  void decimal(std::int64_t v, int min_digits) noexcept {
    char buf[24];
    auto [end, ec] = std::to_chars(buf, buf + sizeof buf, v);
    const auto len = static_cast<int>(end - buf);
    for (int i = len; i < min_digits; ++i)
      put('0');
    put(std::string_view(buf, static_cast<std::size_t>(end - buf)));
  }
  [[nodiscard]] std::size_t size() const noexcept { return ok_ ? n_ : 0; }

 private:
  std::span<char> out_;
  std::size_t n_ = 0;
  bool ok_ = true;
};

}  // namespace

std::size_t format_candump(const CanFrame& frame, std::string_view interface_name,
                           std::span<char> out) noexcept {
  if (interface_name.empty() || interface_name.size() > 15)
    return 0;
  if (frame.len > (frame.fd ? kCanFdMaxBytes : kCanClassicMaxBytes))
    return 0;
  std::int64_t sec = frame.timestamp_ns / 1'000'000'000;
  std::int64_t ns = frame.timestamp_ns % 1'000'000'000;
  if (ns < 0) {
    ns += 1'000'000'000;
    --sec;
  }
  Writer w(out);
  w.put('(');
  w.decimal(sec, 1);
  w.put('.');
  w.decimal(ns / 1000, 6);
  w.put(") ");
  w.put(interface_name);
  w.put(' ');
  if (frame.extended) {
    w.hex(frame.id & 0x1FFFFFFFu, 8);
  } else {
    w.hex(frame.id & 0x7FFu, 3);
  }
  w.put('#');
  if (frame.fd) {
    w.put('#');
    w.hex(frame.fd_flags & 0xFu, 1);
  }
  for (std::size_t i = 0; i < frame.len; ++i)
    w.hex(frame.data[i], 2);
  w.put('\n');
  return w.size();
}

bool parse_candump(std::string_view line, CandumpLine& out, std::string& error) {
  while (!line.empty() && (line.back() == '\n' || line.back() == '\r'))
    line.remove_suffix(1);
  out = CandumpLine{};
  // (SEC.USEC)
  if (line.size() < 3 || line.front() != '(') {
    error = "expected '(' time stamp";
    return false;
  }
  const std::size_t close = line.find(')');
  if (close == std::string_view::npos) {
    error = "unterminated time stamp";
    return false;
  }
  const std::string_view stamp = line.substr(1, close - 1);
  const std::size_t dot = stamp.find('.');
  if (dot == std::string_view::npos || dot == 0 || stamp.size() - dot - 1 != 6) {
    error = "time stamp must be SECONDS.MICROSECONDS with 6 decimals";
    return false;
  }
  std::int64_t sec = 0, usec = 0;
  {
    auto r1 = std::from_chars(stamp.data(), stamp.data() + dot, sec);
    auto r2 = std::from_chars(stamp.data() + dot + 1, stamp.data() + stamp.size(), usec);
    if (r1.ec != std::errc() || r1.ptr != stamp.data() + dot || r2.ec != std::errc() ||
        r2.ptr != stamp.data() + stamp.size() || sec < 0 || usec < 0 || sec > 9'000'000'000LL) {
      error = "bad time stamp digits";
      return false;
    }
  }
  out.frame.timestamp_ns = sec * 1'000'000'000 + usec * 1000;
  // " IFACE "
  std::string_view rest = line.substr(close + 1);
  if (rest.empty() || rest.front() != ' ') {
    error = "expected ' ' after time stamp";
    return false;
  }
  rest.remove_prefix(1);
  const std::size_t space = rest.find(' ');
  if (space == std::string_view::npos || space == 0 || space > 15) {
    error = "expected interface name (1-15 characters) and ' '";
    return false;
  }
  out.interface_name.assign(rest.substr(0, space));
  rest.remove_prefix(space + 1);
  // ID#DATA or ID##FDATA
  const std::size_t hash = rest.find('#');
  if (hash == std::string_view::npos) {
    error = "expected ID#DATA";
    return false;
  }
  const std::string_view id = rest.substr(0, hash);
  if (id.size() != 3 && id.size() != 8) {
    error = "identifier must have 3 (standard) or 8 (extended) hex digits";
    return false;
  }
  std::uint32_t id_value = 0;
  for (char c : id) {
    const int h = hex_value(c);
    if (h < 0) {
      error = "identifier is not hexadecimal";
      return false;
    }
    id_value = (id_value << 4) | static_cast<std::uint32_t>(h);
  }
  out.frame.extended = id.size() == 8;
  if ((!out.frame.extended && id_value > 0x7FF) || id_value > 0x1FFFFFFF) {
    error = "identifier out of range";
    return false;
  }
  out.frame.id = id_value;
  std::string_view data = rest.substr(hash + 1);
  if (!data.empty() && data.front() == '#') {
    out.frame.fd = true;
    if (data.size() < 2) {
      error = "CAN FD frame needs a flags nibble after '##'";
      return false;
    }
    const int flags = hex_value(data[1]);
    if (flags < 0) {
      error = "CAN FD flags nibble is not hexadecimal";
      return false;
    }
    out.frame.fd_flags = static_cast<std::uint8_t>(flags);
    data.remove_prefix(2);
  }
  if (!data.empty() && (data.front() == 'R' || data.front() == 'r')) {
    error = "remote frames are not supported";
    return false;
  }
  if (data.size() % 2 != 0) {
    error = "odd number of hex digits in data";
    return false;
  }
  const std::size_t n = data.size() / 2;
  if (n > (out.frame.fd ? kCanFdMaxBytes : kCanClassicMaxBytes) ||
      (out.frame.fd && !is_can_fd_length(n))) {
    error = "data length " + std::to_string(n) + " not allowed";
    return false;
  }
  for (std::size_t i = 0; i < n; ++i) {
    const int hi = hex_value(data[2 * i]), lo = hex_value(data[2 * i + 1]);
    if (hi < 0 || lo < 0) {
      error = "data is not hexadecimal";
      return false;
    }
    out.frame.data[i] = static_cast<std::uint8_t>((hi << 4) | lo);
  }
  out.frame.len = static_cast<std::uint8_t>(n);
  return true;
}

CandumpRecorder::CandumpRecorder(std::string interface_name, std::size_t capacity_frames)
    : interface_name_(std::move(interface_name)), capacity_(capacity_frames) {
  if (interface_name_.empty() || interface_name_.size() > 15) {
    throw std::invalid_argument("candump recorder: interface name must have 1-15 characters");
  }
  frames_.reserve(capacity_frames);
}

bool CandumpRecorder::record(const CanFrame& frame) noexcept {
  if (frames_.size() >= capacity_) {
    ++overflowed_;
    return false;
  }
  frames_.push_back(frame);
  return true;
}

void CandumpRecorder::write_file(const std::filesystem::path& path) const {
  std::ofstream out(path, std::ios::binary);
  if (!out)
    throw std::runtime_error(path.string() + ": cannot open for writing");
  std::array<char, kCandumpMaxLine> line{};
  for (const CanFrame& f : frames_) {
    const std::size_t n = format_candump(f, interface_name_, line);
    if (n == 0)
      throw std::runtime_error(path.string() + ": frame cannot be formatted");
    out.write(line.data(), static_cast<std::streamsize>(n));
  }
  if (!out)
    throw std::runtime_error(path.string() + ": write failed");
}

std::vector<CandumpLine> read_candump_file(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in)
    throw std::runtime_error(path.string() + ": cannot open");
  std::vector<CandumpLine> lines;
  std::string text, error;
  std::size_t number = 0;
  while (std::getline(in, text)) {
    ++number;
    if (text.empty() || text == "\r")
      continue;
    CandumpLine l;
    if (!parse_candump(text, l, error)) {
      throw std::runtime_error(path.string() + ":" + std::to_string(number) + ": " + error);
    }
    lines.push_back(std::move(l));
  }
  return lines;
}

}  // namespace radar_emu::io
