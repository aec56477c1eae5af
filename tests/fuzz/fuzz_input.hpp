#pragma once
// Shared by the libFuzzer harnesses (tests/fuzz/README.md): a reader that turns the fuzzer's
// bytes into structured values, and the check that turns a broken invariant into a crash the
// fuzzer reports (and the replay test fails on).

#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <span>

namespace radar_emu::fuzz {

/// Consumes the input front to back; reads past the end give zeros (so every input is valid).
class FuzzInput {
 public:
  FuzzInput(const std::uint8_t* data, std::size_t size) noexcept : data_(data), size_(size) {}

  [[nodiscard]] bool empty() const noexcept { return pos_ >= size_; }
  [[nodiscard]] std::size_t remaining() const noexcept { return empty() ? 0 : size_ - pos_; }
  std::uint8_t u8() noexcept { return pos_ < size_ ? data_[pos_++] : 0; }
  std::uint16_t u16() noexcept {
    const auto hi = static_cast<std::uint16_t>(u8() << 8);
    return static_cast<std::uint16_t>(hi | u8());
  }
  std::uint32_t u32() noexcept {
    const std::uint32_t hi = u16();
    return (hi << 16) | u16();
  }
  std::uint64_t u64() noexcept {
    const std::uint64_t hi = u32();
    return (hi << 32) | u32();
  }
  /// Copies up to out.size() bytes (zeros past the end of the input).
  void bytes(std::span<std::uint8_t> out) noexcept {
    for (std::uint8_t& b : out)
      b = u8();
  }
  /// The rest of the input.
  [[nodiscard]] std::span<const std::uint8_t> rest() noexcept {
    const std::span<const std::uint8_t> r(data_ + (empty() ? size_ : pos_), remaining());
    pos_ = size_;
    return r;
  }

 private:
  const std::uint8_t* data_;
  std::size_t size_;
  std::size_t pos_ = 0;
};

[[noreturn]] inline void check_failed(const char* what, const char* file, int line) noexcept {
  std::fprintf(stderr, "fuzz invariant broken: %s (%s:%d)\n", what, file, line);
  std::abort();
}

}  // namespace radar_emu::fuzz

/// An invariant of the code under test; a violation aborts (a finding, like a sanitizer report).
#define FUZZ_CHECK(cond)                                          \
  do {                                                            \
    if (!(cond))                                                  \
      ::radar_emu::fuzz::check_failed(#cond, __FILE__, __LINE__); \
  } while (false)
