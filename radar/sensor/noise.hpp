#pragma once
// Reproducible random numbers for the sensor: xoshiro256** (Blackman and Vigna, "Scrambled
// linear pseudorandom number generators", ACM TOMS 47(4), 2021) seeded through splitmix64, and
// exact complex Gaussian samples by Marsaglia's polar method (Marsaglia and Bray, SIAM Review
// 6(3), 1964), and exact exponential variates by the ziggurat method (Marsaglia and Tsang, "The
// ziggurat method for generating random variables", J. Stat. Softw. 5(8), 2000; the layer
// index and the uniform from disjoint bits of one 64-bit draw, as Doornik, "An improved ziggurat
// method to generate normal random samples", 2005, recommends). Streams are keyed by (seed, frame,
// beam, channel, ...) so that a result does not depend on the order in which threads run.
// Header-only, allocation-free.

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

/// The ziggurat of the unit exponential density f(x) = exp(-x) (Marsaglia and Tsang 2000, sec. 2
/// and their exponential set-up): 256 layers of equal area v, the base layer holding the tail
/// beyond r. Layer i (0..255) is [0, x[i]] x [f(x[i]), f(x[i + 1])], x[1] = r > x[2] > ... >
/// x[256] = 0, and x[0] = v / f(r) the base layer's width as if its tail were a rectangle. Built
/// once at setup (log and exp); read-only afterwards.
struct ExponentialZiggurat {
  static constexpr int kLayers = 256;
  static constexpr double kR = 7.69711747013104972;   ///< Marsaglia and Tsang's r for 256 layers
  static constexpr double kV = 3.949659822581572e-3;  ///< their v: each layer's area
  double x[kLayers + 1];
  double f[kLayers + 1];  ///< exp(-x[i])
  ExponentialZiggurat() noexcept {
    x[0] = kV / std::exp(-kR);
    x[1] = kR;
    for (int i = 1; i < kLayers - 1; ++i)
      x[i + 1] = -std::log(kV / x[i] + std::exp(-x[i]));
    x[kLayers] = 0.0;
    for (int i = 0; i <= kLayers; ++i)
      f[i] = std::exp(-x[i]);
  }
};

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
  /// Unit exponential (mean 1) by the ziggurat `z`: about 99 % of the draws take one 64-bit
  /// number, a table look-up, a product and a comparison; the rest test the layer's wedge
  /// against exp(-x) or, in the base layer beyond r, add r to a fresh variate (the exponential
  /// is memoryless). The law is exactly the exponential one, as -log(U) (up to the 53-bit
  /// uniform's resolution); the draws differ.
  double exponential(const ExponentialZiggurat& z) noexcept {
    double offset = 0.0;
    for (;;) {
      const std::uint64_t bits = next();
      const auto i = static_cast<int>(bits & 0xff);
      const double u = static_cast<double>(bits >> 11) * 0x1.0p-53;  // [0, 1)
      const double xv = u * z.x[i];
      if (xv < z.x[i + 1])
        return offset + xv;
      if (i == 0) {  // beyond r: r plus an exponential
        offset += ExponentialZiggurat::kR;
        continue;
      }
      const double y = z.f[i] + uniform() * (z.f[i + 1] - z.f[i]);
      if (y < std::exp(-xv))
        return offset + xv;
    }
  }
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
