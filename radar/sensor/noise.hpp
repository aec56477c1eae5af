#pragma once
// Reproducible random numbers for the sensor: xoshiro256** (Blackman and Vigna, "Scrambled
// linear pseudorandom number generators", ACM TOMS 47(4), 2021) seeded through splitmix64, and
// exact complex Gaussian samples by Marsaglia's polar method (Marsaglia and Bray, SIAM Review
// 6(3), 1964). Streams are keyed by (seed, frame, beam, channel, ...) so that a result does not
// depend on the order in which threads run. Header-only, allocation-free.

#include <cmath>
#include <complex>
#include <cstdint>

namespace radar_emu::radar {

constexpr std::uint64_t splitmix64(std::uint64_t& state) noexcept {
  std::uint64_t z = (state += 0x9e3779b97f4a7c15ull);
  z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ull;
  z = (z ^ (z >> 27)) * 0x94d049bb133111ebull;
  return z ^ (z >> 31);
}

/// Mixes a stream key into one 64-bit seed.
constexpr std::uint64_t stream_key(std::uint64_t seed, std::uint64_t a, std::uint64_t b = 0,
                                   std::uint64_t c = 0, std::uint64_t d = 0) noexcept {
  std::uint64_t s = seed;
  std::uint64_t h = splitmix64(s);
  for (std::uint64_t v : {a, b, c, d}) {
    s = h ^ (v * 0xd1342543de82ef95ull + 0x2545f4914f6cdd1dull);
    h = splitmix64(s);
  }
  return h;
}

class NoiseRng {
 public:
  explicit NoiseRng(std::uint64_t key) noexcept {
    std::uint64_t s = key;
    for (auto& v : s_)
      v = splitmix64(s);
  }
  std::uint64_t next() noexcept {
    const std::uint64_t result = rotl(s_[1] * 5, 7) * 9;
    const std::uint64_t t = s_[1] << 17;
    s_[2] ^= s_[0];
    s_[3] ^= s_[1];
    s_[1] ^= s_[2];
    s_[0] ^= s_[3];
    s_[2] ^= t;
    s_[3] = rotl(s_[3], 45);
    return result;
  }
  /// Uniform in (-1, 1).
  double symmetric() noexcept {
    return (static_cast<double>(next() >> 11) + 0.5) * 0x1.0p-52 - 1.0;
  }
  /// Uniform in (0, 1).
  double uniform() noexcept { return (static_cast<double>(next() >> 11) + 0.5) * 0x1.0p-53; }
  /// Circular complex Gaussian with E|z|^2 = 1 (each part variance 1/2).
  std::complex<double> complex_normal() noexcept {
    double u, v, s;
    do {
      u = symmetric();
      v = symmetric();
      s = u * u + v * v;
    } while (s >= 1.0 || s == 0.0);
    const double f = std::sqrt(-std::log(s) / s);  // polar method with variance 1/2 a part
    return {u * f, v * f};
  }

 private:
  static constexpr std::uint64_t rotl(std::uint64_t x, int k) noexcept {
    return (x << k) | (x >> (64 - k));
  }
  std::uint64_t s_[4];
};

}  // namespace radar_emu::radar
