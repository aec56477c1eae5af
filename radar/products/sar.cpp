#include "radar/products/sar.hpp"

#include <fftw3.h>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <memory>
#include <stdexcept>
#include <string>

#include "radar/constants.hpp"
#include "radar/fftw.hpp"

namespace radar_emu::radar {

namespace {

constexpr double kC = kSpeedOfLight_mps;
const glm::dvec3 kUp{0.0, 0.0, 1.0};

void require(bool ok, const std::string& what) {
  if (!ok)
    throw std::invalid_argument("sar: " + what);
}
bool positive(double x) {
  return std::isfinite(x) && x > 0.0;
}

// Hamming taper over u in [-1/2, 1/2] (Harris 1978, the Hamming window, centred).
double taper_weight(SarTaper t, double u) noexcept {
  if (t == SarTaper::kNone)
    return 1.0;
  return 0.54 + 0.46 * std::cos(2.0 * kPi * u);
}

using fftw::as_fftw;
using Buffer = fftw::ComplexBuffer;

// Smallest 2^a 3^b 5^c >= n (FFTW is fastest on these sizes).
std::size_t fft_size(std::size_t n) {
  std::size_t best = 1;
  while (best < n)
    best *= 2;
  for (std::size_t p5 = 1; p5 < best; p5 *= 5)
    for (std::size_t p3 = p5; p3 < best; p3 *= 3) {
      std::size_t v = p3;
      while (v < n)
        v *= 2;
      best = std::min(best, v);
    }
  return best;
}

// Pulse envelope at x = t - tau (header): 1 inside, raised-cosine edges, 0 outside |x| > T/2.
double envelope(double x, double duration_s) noexcept {
  const double edge = kSarPulseEdge * duration_s, flat = duration_s / 2 - edge;
  const double ax = std::abs(x);
  if (ax <= flat)
    return 1.0;
  if (ax >= duration_s / 2)
    return 0.0;
  return 0.5 * (1.0 + std::cos(kPi * (ax - flat) / edge));
}

}  // namespace

void validate(const SarParams& p) {
  require(positive(p.carrier_hz), "carrier_hz must be > 0");
  require(positive(p.bandwidth_hz) && p.bandwidth_hz < p.carrier_hz,
          "bandwidth_hz must be > 0 and below the carrier");
  require(positive(p.sample_rate_hz) && p.sample_rate_hz >= p.bandwidth_hz,
          "sample_rate_hz must be >= bandwidth_hz (complex sampling)");
  require(positive(p.pulse_duration_s), "pulse_duration_s must be > 0");
  require(
      p.pulse_duration_s * p.sample_rate_hz >= 8.0 && p.pulse_duration_s * p.sample_rate_hz <= 1e6,
      "pulse_duration_s * sample_rate_hz must be in 8..1e6 samples");
  require(positive(p.prf_hz), "prf_hz must be > 0");
  require(p.pulses >= 2 && p.pulses <= 1000000, "pulses must be in 2..1e6");
  require(p.gates >= 8 && p.gates <= 1000000, "gates must be in 8..1e6");
  require(positive(p.near_range_m), "near_range_m must be > 0");
  require(std::isfinite(p.start_position_m.x) && std::isfinite(p.start_position_m.y) &&
              std::isfinite(p.start_position_m.z),
          "start position must be finite");
  require(std::isfinite(p.velocity_mps.x) && std::isfinite(p.velocity_mps.y) &&
              std::abs(p.velocity_mps.z) < 1e-9 &&
              glm::length(glm::dvec2(p.velocity_mps.x, p.velocity_mps.y)) > 0.0,
          "velocity must be horizontal and non-zero");
  require(std::isfinite(p.incidence_rad) && p.incidence_rad > 0.0 && p.incidence_rad < kPi / 2,
          "incidence must be in (0, 90) deg");
  require(positive(p.azimuth_beamwidth_rad) && p.azimuth_beamwidth_rad < kPi / 2,
          "azimuth beamwidth must be in (0, 90) deg");
  require(positive(p.elevation_beamwidth_rad) && p.elevation_beamwidth_rad < kPi / 2,
          "elevation beamwidth must be in (0, 90) deg");
  require(positive(p.peak_gain), "peak gain must be > 0");
  require(positive(p.transmit_power_w), "transmit power must be > 0");
}

double sar_wavelength_m(const SarParams& p) noexcept {
  return kC / p.carrier_hz;
}
double sar_gate_m(const SarParams& p) noexcept {
  return kC / (2.0 * p.sample_rate_hz);
}
std::size_t sar_chirp_samples(const SarParams& p) noexcept {
  const auto half = static_cast<std::size_t>(std::floor(p.pulse_duration_s * p.sample_rate_hz / 2));
  return 2 * half + 1;
}
std::size_t sar_filter_half_length(const SarParams& p) noexcept {
  return sar_chirp_samples(p);
}
std::size_t sar_raw_samples(const SarParams& p) noexcept {
  return p.gates + sar_chirp_samples(p) - 1;
}
double sar_pulse_time_s(const SarParams& p, std::size_t pulse) noexcept {
  return static_cast<double>(pulse) / p.prf_hz;
}
glm::dvec3 sar_platform_m(const SarParams& p, double t_s) noexcept {
  return p.start_position_m + p.velocity_mps * t_s;
}
glm::dvec3 sar_track_dir(const SarParams& p) noexcept {
  return glm::normalize(p.velocity_mps);
}
glm::dvec3 sar_look_dir(const SarParams& p) noexcept {
  const glm::dvec3 t = sar_track_dir(p);
  return p.look_right ? glm::cross(t, kUp) : glm::cross(kUp, t);
}
glm::dmat3 sar_world_from_antenna(const SarParams& p) noexcept {
  const glm::dvec3 x =
      std::sin(p.incidence_rad) * sar_look_dir(p) - std::cos(p.incidence_rad) * kUp;
  const glm::dvec3 z = glm::normalize(-kUp + glm::dot(kUp, x) * x);  // down, perpendicular to x
  const glm::dvec3 y = glm::cross(z, x);
  return glm::dmat3(x, y, z);
}
double sar_two_way_gain(const SarParams& p, const glm::dvec3& d) noexcept {
  const glm::dvec3 a = glm::transpose(sar_world_from_antenna(p)) * d;
  const double az = std::atan2(a.y, a.x);
  const double el = std::atan2(-a.z, std::hypot(a.x, a.y));
  const double qa = az / p.azimuth_beamwidth_rad, qe = el / p.elevation_beamwidth_rad;
  return p.peak_gain * std::exp(-4.0 * std::log(2.0) * (qa * qa + qe * qe));
}

SarRaw make_raw(const SarParams& p) {
  validate(p);
  SarRaw r;
  r.pulses = p.pulses;
  r.samples = sar_raw_samples(p);
  r.data.assign(r.pulses * r.samples, std::complex<float>{});
  return r;
}

void add_echoes(const SarParams& p, std::span<const SarEcho> echoes,
                std::span<const glm::dvec3> directions, std::span<std::complex<float>> row) {
  require(echoes.size() == directions.size(), "echoes and directions differ in size");
  std::vector<std::complex<double>> acc(row.size());
  add_echoes_accumulate(p, echoes, directions, acc);
  finish_pulse(p, acc, row);
}

void add_echoes_accumulate(const SarParams& p, std::span<const SarEcho> echoes,
                           std::span<const glm::dvec3> directions,
                           std::span<std::complex<double>> acc) {
  require(echoes.size() == directions.size(), "echoes and directions differ in size");
  const double lambda = sar_wavelength_m(p), fs = p.sample_rate_hz, dt = 1.0 / fs;
  const double k_rate = p.bandwidth_hz / p.pulse_duration_s;  // K [Hz/s]
  const double half_t = p.pulse_duration_s / 2,
               flat_t = half_t - kSarPulseEdge * p.pulse_duration_s;
  const double h = static_cast<double>((sar_chirp_samples(p) - 1) / 2);
  const double scale = std::sqrt(p.transmit_power_w) * lambda / std::pow(4.0 * kPi, 1.5);
  const auto n_samples = static_cast<std::ptrdiff_t>(acc.size());
  // exp(j pi K (t_n - tau)^2) = exp(j pi K t_n^2) exp(-j 2 pi K tau t_n) exp(j pi K tau^2): the
  // first factor is common to every echo (finish_pulse applies it), the second a linear phase
  // (one complex multiplication per sample), restarted exactly every kExact samples.
  constexpr std::ptrdiff_t kExact = 64;
  for (std::size_t e = 0; e < echoes.size(); ++e) {
    const SarEcho& echo = echoes[e];
    if (!(echo.range_m > 0.0) || !std::isfinite(echo.range_m))
      continue;
    const double gain = sar_two_way_gain(p, directions[e]);
    const double tau = 2.0 * (echo.range_m - p.near_range_m) / kC;  // relative to gate 0
    const std::complex<double> amp = echo.amplitude_m *
                                     (scale * gain / (echo.range_m * echo.range_m)) *
                                     std::polar(1.0, kPi * k_rate * tau * tau);
    auto n0 = static_cast<std::ptrdiff_t>(std::ceil((tau - half_t) * fs + h));
    auto n1 = static_cast<std::ptrdiff_t>(std::floor((tau + half_t) * fs + h));
    n0 = std::max<std::ptrdiff_t>(n0, 0);
    n1 = std::min<std::ptrdiff_t>(n1, n_samples - 1);
    const double omega = -2.0 * kPi * k_rate * tau * dt;
    const std::complex<double> w = std::polar(1.0, omega);
    std::complex<double> z;
    for (std::ptrdiff_t n = n0; n <= n1; ++n) {
      const double t = (static_cast<double>(n) - h) * dt;
      if ((n - n0) % kExact == 0)
        z = amp * std::polar(1.0, -2.0 * kPi * k_rate * tau * t);
      const double x = std::abs(t - tau);
      acc[static_cast<std::size_t>(n)] += x <= flat_t ? z : z * envelope(x, p.pulse_duration_s);
      z *= w;
    }
  }
}

void finish_pulse(const SarParams& p, std::span<const std::complex<double>> acc,
                  std::span<std::complex<float>> row) {
  require(acc.size() == row.size(), "accumulator and row differ in size");
  const double dt = 1.0 / p.sample_rate_hz, k_rate = p.bandwidth_hz / p.pulse_duration_s;
  const double h = static_cast<double>((sar_chirp_samples(p) - 1) / 2);
  for (std::size_t n = 0; n < acc.size(); ++n) {
    if (acc[n] == std::complex<double>{})
      continue;
    const double t = (static_cast<double>(n) - h) * dt;
    row[n] += std::complex<float>(acc[n] * std::polar(1.0, kPi * k_rate * t * t));
  }
}

void synthesise_points(const SarParams& p, std::span<const SarScatterer> points, std::size_t begin,
                       std::size_t end, SarRaw& raw) {
  validate(p);
  require(raw.pulses == p.pulses && raw.samples == sar_raw_samples(p) &&
              raw.data.size() == raw.pulses * raw.samples,
          "raw matrix does not match the parameters");
  require(begin <= end && end <= p.pulses, "pulse range outside [0, pulses]");
  require(points.size() < 0xffffffffull, "too many points");
  const double k = 2.0 * kPi / sar_wavelength_m(p);
  const double far_m =
      p.near_range_m + static_cast<double>(p.gates) * sar_gate_m(p) + p.pulse_duration_s * kC / 2;
  const double near_m = p.near_range_m - p.pulse_duration_s * kC / 2;
  // Points sorted along track: a pulse visits only those within its beam's reach (two-way gain
  // >= 1e-3 of the peak: 1.58 azimuth beamwidths off boresight).
  const glm::dvec3 track = sar_track_dir(p);
  std::vector<std::pair<double, std::uint32_t>> order(points.size());
  for (std::size_t i = 0; i < points.size(); ++i)
    order[i] = {glm::dot(points[i].position_m - p.start_position_m, track),
                static_cast<std::uint32_t>(i)};
  std::sort(order.begin(), order.end());
  const double reach = far_m * std::tan(std::min(1.58 * p.azimuth_beamwidth_rad, 1.5)) + 1.0;
  tbb::parallel_for(
      tbb::blocked_range<std::size_t>(begin, end, 4),
      [&](const tbb::blocked_range<std::size_t>& r) {
        std::vector<SarEcho> echoes;
        std::vector<glm::dvec3> dirs;
        std::vector<std::complex<double>> acc(raw.samples);
        for (std::size_t i = r.begin(); i != r.end(); ++i) {
          const glm::dvec3 pos = sar_platform_m(p, sar_pulse_time_s(p, i));
          const double along = glm::dot(pos - p.start_position_m, track);
          auto it = std::lower_bound(order.begin(), order.end(),
                                     std::pair<double, std::uint32_t>{along - reach, 0});
          echoes.clear();
          dirs.clear();
          for (; it != order.end() && it->first <= along + reach; ++it) {
            const SarScatterer& s = points[it->second];
            const glm::dvec3 d = s.position_m - pos;
            const double range = glm::length(d);
            if (range < near_m || range > far_m)
              continue;
            const glm::dvec3 u = d / range;
            if (sar_two_way_gain(p, u) < 1e-3 * p.peak_gain)
              continue;
            echoes.push_back({s.amplitude_m * std::polar(1.0, -2.0 * k * range), range});
            dirs.push_back(u);
          }
          std::fill(acc.begin(), acc.end(), std::complex<double>{});
          add_echoes_accumulate(p, echoes, dirs, acc);
          finish_pulse(p, acc, std::span(raw.data).subspan(i * raw.samples, raw.samples));
        }
      });
}

SarCompressed range_compress(const SarParams& p, const SarRaw& raw, SarTaper taper) {
  validate(p);
  require(raw.pulses == p.pulses && raw.samples == sar_raw_samples(p) &&
              raw.data.size() == raw.pulses * raw.samples,
          "raw matrix does not match the parameters");
  const std::size_t nc = sar_chirp_samples(p), h = (nc - 1) / 2;
  // The filter's impulse response is kept to |k| <= m (header): an FFT of n >= samples + 2m + 1
  // points makes the circular convolution a linear one over every output gate (no wrap-around).
  const std::size_t m = sar_filter_half_length(p);
  const std::size_t n = fft_size(raw.samples + 2 * m + 1);
  const double fs = p.sample_rate_hz, k_rate = p.bandwidth_hz / p.pulse_duration_s;
  // Replica at circular index (k mod n), k in [-h, h].
  Buffer ref = fftw::complex_buffer(n);
  for (std::size_t j = 0; j < nc; ++j) {
    const double k = static_cast<double>(j) - static_cast<double>(h);
    const double t = k / fs;
    ref[(j + n - h) % n] = std::polar(envelope(t, p.pulse_duration_s), kPi * k_rate * t * t);
  }
  Buffer fil = fftw::complex_buffer(n);
  const fftw::Plan fwd_ref("sar", [&] {
    return fftw_plan_dft_1d(static_cast<int>(n), as_fftw(ref.get()), as_fftw(ref.get()),
                            FFTW_FORWARD, FFTW_ESTIMATE);
  });
  const fftw::Plan inv_fil("sar", [&] {
    return fftw_plan_dft_1d(static_cast<int>(n), as_fftw(fil.get()), as_fftw(fil.get()),
                            FFTW_BACKWARD, FFTW_ESTIMATE);
  });
  const fftw::Plan fwd_fil("sar", [&] {
    return fftw_plan_dft_1d(static_cast<int>(n), as_fftw(fil.get()), as_fftw(fil.get()),
                            FFTW_FORWARD, FFTW_ESTIMATE);
  });
  fwd_ref.execute();
  // Filter conj(S) W on |f| <= B/2.
  for (std::size_t j = 0; j < n; ++j) {
    const double f = (j < (n + 1) / 2 ? static_cast<double>(j)
                                      : static_cast<double>(j) - static_cast<double>(n)) *
                     fs / static_cast<double>(n);
    const double u = f / p.bandwidth_hz;
    if (std::abs(u) > 0.5)
      continue;
    // Equalised: conj(S) / |S|^2 = 1 / S, so that the compressed spectrum is the taper itself.
    const double mag2 = std::norm(ref[j]);
    if (mag2 <= 0.0)
      continue;
    fil[j] = std::conj(ref[j]) / mag2 * taper_weight(taper, u);
  }
  // Its impulse response, band-limited by a hard edge, rings as 1/k forever: kept to |k| <= m
  // with raised-cosine ends over the outer quarter (Tukey window; header).
  inv_fil.execute();
  const std::size_t flat = m - m / 4;
  for (std::size_t j = 0; j < n; ++j) {
    const std::size_t k = std::min(j, n - j);  // |lag|
    double w = 1.0;
    if (k > m)
      w = 0.0;
    else if (k > flat)
      w = 0.5 *
          (1.0 + std::cos(kPi * static_cast<double>(k - flat) / static_cast<double>(m + 1 - flat)));
    fil[j] *= w;
  }
  fwd_fil.execute();
  // Gain: the compressed peak of the replica itself (FFTW's transforms are unnormalised).
  std::vector<std::complex<double>> filter(n);
  double gain = 0.0;
  for (std::size_t j = 0; j < n; ++j) {
    filter[j] = fil[j] / static_cast<double>(n);
    gain += (filter[j] * ref[j]).real();
  }
  gain /= static_cast<double>(n);
  for (auto& v : filter)
    v /= gain * static_cast<double>(n);  // FFTW's inverse is unnormalised

  SarCompressed out;
  out.pulses = p.pulses;
  out.gates = p.gates;
  out.data.assign(out.pulses * out.gates, std::complex<float>{});
  Buffer probe = fftw::complex_buffer(n);
  const fftw::Plan fwd("sar", [&] {
    return fftw_plan_dft_1d(static_cast<int>(n), as_fftw(probe.get()), as_fftw(probe.get()),
                            FFTW_FORWARD, FFTW_ESTIMATE);
  });
  const fftw::Plan inv("sar", [&] {
    return fftw_plan_dft_1d(static_cast<int>(n), as_fftw(probe.get()), as_fftw(probe.get()),
                            FFTW_BACKWARD, FFTW_ESTIMATE);
  });
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, p.pulses, 8),
                    [&](const tbb::blocked_range<std::size_t>& r) {
                      Buffer b = fftw::complex_buffer(n);
                      for (std::size_t i = r.begin(); i != r.end(); ++i) {
                        std::fill(b.get(), b.get() + n, std::complex<double>{});
                        const std::complex<float>* row = &raw.data[i * raw.samples];
                        for (std::size_t s = 0; s < raw.samples; ++s)
                          b[s] = std::complex<double>(row[s]);
                        fwd.execute(b.get(), b.get());
                        for (std::size_t j = 0; j < n; ++j)
                          b[j] *= filter[j];
                        inv.execute(b.get(), b.get());
                        for (std::size_t g = 0; g < p.gates; ++g)
                          out.data[i * p.gates + g] = std::complex<float>(b[g + h]);
                      }
                    });
  return out;
}

SarImage backproject(const SarParams& p, const SarCompressed& rc, const SarImageGrid& grid,
                     const BackprojectionOptions& o) {
  validate(p);
  require(rc.pulses == p.pulses && rc.gates == p.gates && rc.data.size() == rc.pulses * rc.gates,
          "range-compressed matrix does not match the parameters");
  require(grid.rows >= 1 && grid.cols >= 1 && grid.rows * grid.cols <= 400000000ull,
          "image grid must have 1..4e8 pixels");
  require(grid.height_m.empty() || grid.height_m.size() == grid.rows * grid.cols,
          "image grid heights must be empty or one per pixel");
  require(positive(grid.azimuth_spacing_m) && positive(grid.ground_range_spacing_m),
          "image pixel spacings must be > 0");
  require(positive(o.integration_angle_rad) && o.integration_angle_rad < 1.0,
          "integration angle must be in (0, 1) rad");
  require(o.upsample >= 1 && o.upsample <= 64, "upsample must be in 1..64");
  require(
      std::isfinite(o.min_relative_gain) && o.min_relative_gain > 0.0 && o.min_relative_gain <= 1.0,
      "min_relative_gain must be in (0, 1]");

  const std::size_t ng = p.gates, nu = ng * o.upsample;
  const double gate_up = sar_gate_m(p) / static_cast<double>(o.upsample);
  const double lambda = sar_wavelength_m(p), k2 = 4.0 * kPi / lambda;
  const double cal = std::pow(4.0 * kPi, 1.5) / (std::sqrt(p.transmit_power_w) * lambda);
  const double sin_half = std::sin(o.integration_angle_rad / 2);
  const glm::dvec3 track = sar_track_dir(p), look = sar_look_dir(p);

  Buffer probe_in = fftw::complex_buffer(ng), probe_out = fftw::complex_buffer(nu);
  const fftw::Plan fwd("sar", [&] {
    return fftw_plan_dft_1d(static_cast<int>(ng), as_fftw(probe_in.get()), as_fftw(probe_in.get()),
                            FFTW_FORWARD, FFTW_ESTIMATE);
  });
  const fftw::Plan inv("sar", [&] {
    return fftw_plan_dft_1d(static_cast<int>(nu), as_fftw(probe_out.get()),
                            as_fftw(probe_out.get()), FFTW_BACKWARD, FFTW_ESTIMATE);
  });

  std::vector<std::complex<double>> acc(grid.rows * grid.cols);
  std::vector<double> wsum(grid.rows * grid.cols, 0.0);
  std::vector<std::uint32_t> looks(grid.rows * grid.cols, 0);
  double far_range = p.near_range_m + static_cast<double>(ng) * sar_gate_m(p);

  constexpr std::size_t kBlock = 32;
  std::vector<std::vector<std::complex<float>>> lines(kBlock, std::vector<std::complex<float>>(nu));
  for (std::size_t b0 = 0; b0 < p.pulses; b0 += kBlock) {
    const std::size_t b1 = std::min(p.pulses, b0 + kBlock);
    // Upsample the block's pulses (spectrum zero-padded in the middle: baseband data).
    tbb::parallel_for(std::size_t{b0}, b1, [&](std::size_t i) {
      Buffer a = fftw::complex_buffer(ng), u = fftw::complex_buffer(nu);
      for (std::size_t g = 0; g < ng; ++g)
        a[g] = std::complex<double>(rc.data[i * ng + g]);
      fwd.execute(a.get(), a.get());
      const std::size_t pos = (ng + 1) / 2, neg = ng - pos;
      for (std::size_t j = 0; j < pos; ++j)
        u[j] = a[j];
      for (std::size_t j = 0; j < neg; ++j)
        u[nu - neg + j] = a[pos + j];
      inv.execute(u.get(), u.get());
      auto& line = lines[i - b0];
      for (std::size_t j = 0; j < nu; ++j)
        line[j] = std::complex<float>(u[j] / static_cast<double>(ng));
    });
    tbb::parallel_for(
        tbb::blocked_range<std::size_t>(0, grid.rows, 4),
        [&](const tbb::blocked_range<std::size_t>& rr) {
          for (std::size_t row = rr.begin(); row != rr.end(); ++row) {
            const glm::dvec3 row0 =
                grid.origin_m + static_cast<double>(row) * grid.azimuth_spacing_m * track;
            for (std::size_t i = b0; i < b1; ++i) {
              const glm::dvec3 pos = sar_platform_m(p, sar_pulse_time_s(p, i));
              const double along = glm::dot(pos - row0, track);
              if (std::abs(along) > far_range * sin_half)
                continue;
              const auto& line = lines[i - b0];
              for (std::size_t col = 0; col < grid.cols; ++col) {
                glm::dvec3 x = row0 + static_cast<double>(col) * grid.ground_range_spacing_m * look;
                if (!grid.height_m.empty())
                  x.z = static_cast<double>(grid.height_m[row * grid.cols + col]);
                const glm::dvec3 d = x - pos;
                const double range = glm::length(d);
                const double s = along / range;  // sin of the angle off broadside
                if (std::abs(s) > sin_half)
                  continue;
                const double q = (range - p.near_range_m) / gate_up;
                if (!(q >= 0.0) || q >= static_cast<double>(nu - 1))
                  continue;
                const double g = sar_two_way_gain(p, d / range);
                if (g < o.min_relative_gain * p.peak_gain)
                  continue;
                const auto i0 = static_cast<std::size_t>(q);
                const double f = q - static_cast<double>(i0);
                const std::complex<double> v = (1.0 - f) * std::complex<double>(line[i0]) +
                                               f * std::complex<double>(line[i0 + 1]);
                const double w = taper_weight(o.taper, std::asin(s) / o.integration_angle_rad);
                const std::size_t idx = row * grid.cols + col;
                acc[idx] += v * std::polar(w * cal * range * range / g, k2 * range);
                wsum[idx] += w;
                ++looks[idx];
              }
            }
          }
        });
  }
  SarImage img;
  img.grid = grid;
  img.pixels.resize(acc.size());
  // Basebanded to the zero-Doppler range R0 of each pixel (its distance from the track line).
  for (std::size_t row = 0; row < grid.rows; ++row)
    for (std::size_t col = 0; col < grid.cols; ++col) {
      const std::size_t i = row * grid.cols + col;
      if (!(wsum[i] > 0.0))
        continue;
      glm::dvec3 x = grid.origin_m + static_cast<double>(row) * grid.azimuth_spacing_m * track +
                     static_cast<double>(col) * grid.ground_range_spacing_m * look;
      if (!grid.height_m.empty())
        x.z = static_cast<double>(grid.height_m[i]);
      const glm::dvec3 d = x - p.start_position_m;
      const double r0 = glm::length(d - glm::dot(d, track) * track);
      img.pixels[i] = std::complex<float>(acc[i] / wsum[i] * std::polar(1.0, -k2 * r0));
    }
  img.looks = std::move(looks);
  return img;
}

double sar_azimuth_quadratic_phase(const SarParams& p, double range_m,
                                   double azimuth_spacing_m) noexcept {
  const double k = 2.0 * kPi / sar_wavelength_m(p);
  return -k * azimuth_spacing_m * azimuth_spacing_m / range_m;
}

double theory_range_resolution_m(const SarParams& p, SarTaper t) noexcept {
  return (t == SarTaper::kNone ? 0.886 : 1.30) * kC / (2.0 * p.bandwidth_hz);
}
double theory_azimuth_resolution_m(const SarParams& p, double theta_rad, SarTaper t) noexcept {
  return (t == SarTaper::kNone ? 0.886 : 1.30) * sar_wavelength_m(p) / (2.0 * theta_rad);
}

}  // namespace radar_emu::radar
