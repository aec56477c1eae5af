#include "radar/products/range_profile.hpp"

#include <fftw3.h>

#include <cmath>
#include <memory>
#include <stdexcept>
#include <string>

#include "radar/constants.hpp"
#include "radar/fftw.hpp"

namespace radar_emu::radar {

namespace {

void require(bool ok, const std::string& what) {
  if (!ok)
    throw std::invalid_argument("range profile: " + what);
}

void check_grid(const FrequencyGrid& g, std::size_t samples, std::size_t oversample) {
  require(g.count >= 2, "needs at least 2 frequencies");
  require(std::isfinite(g.start_hz) && g.start_hz > 0.0, "start frequency must be > 0");
  require(std::isfinite(g.step_hz) && g.step_hz > 0.0, "frequency step must be > 0");
  require(samples == g.count, "number of samples differs from the frequency count");
  require(oversample >= 1 && oversample <= 64, "oversample must be in 1..64");
}

using fftw::as_fftw;

// Sample m of an M-point transform sits at signed index m - M/2 after the shift.
std::vector<double> axis(std::size_t m, double spacing) {
  std::vector<double> out(m);
  for (std::size_t i = 0; i < m; ++i)
    out[i] = (static_cast<double>(i) - static_cast<double>(m / 2)) * spacing;
  return out;
}

// The taper's n samples (symmetric, peak 1; the transforms divide by their sum).
std::vector<double> window_samples(Window window, std::size_t n) {
  std::vector<double> w(n, 1.0);
  fill_window(WindowSpec{window, 35.0, 4}, w);
  return w;
}

}  // namespace

RangeProfile range_profile(std::span<const std::complex<double>> samples, const FrequencyGrid& g,
                           Window window, std::size_t oversample) {
  check_grid(g, samples.size(), oversample);
  const std::size_t n = g.count, m = n * oversample;
  const std::vector<double> w = window_samples(window, n);
  double w_sum = 0.0;
  for (double x : w)
    w_sum += x;
  fftw::ComplexBuffer buf = fftw::complex_buffer(m);
  for (std::size_t i = 0; i < n; ++i) {
    require(std::isfinite(samples[i].real()) && std::isfinite(samples[i].imag()),
            "sample " + std::to_string(i) + " is not finite");
    buf[i] = {w[i] * samples[i].real(), w[i] * samples[i].imag()};
  }
  {
    // FFTW_BACKWARD computes sum_n x_n exp(+j 2 pi n q / M): the exp(+j 2 k_n R) kernel.
    const fftw::Plan plan("range profile", [&] {
      return fftw_plan_dft_1d(static_cast<int>(m), as_fftw(buf.get()), as_fftw(buf.get()),
                              FFTW_BACKWARD, FFTW_ESTIMATE);
    });
    plan.execute();
  }
  RangeProfile p;
  p.resolution_m = kSpeedOfLight_mps / (2.0 * g.step_hz * static_cast<double>(n));
  p.bin_m = kSpeedOfLight_mps / (2.0 * g.step_hz * static_cast<double>(m));
  p.unambiguous_m = kSpeedOfLight_mps / (2.0 * g.step_hz);
  p.range_m = axis(m, p.bin_m);
  p.amplitude_m.resize(m);
  const double k0 = 2.0 * kPi * g.start_hz / kSpeedOfLight_mps;
  for (std::size_t i = 0; i < m; ++i) {
    const std::size_t src = (i + m - m / 2) % m;  // signed index i - M/2, modulo M
    const double carrier = 2.0 * k0 * p.range_m[i];
    p.amplitude_m[i] = buf[src] * std::polar(1.0 / w_sum, carrier);
  }
  return p;
}

IsarImage isar_image(std::span<const std::complex<double>> samples, const FrequencyGrid& g,
                     double angle_step_rad, std::size_t angle_count, Window window,
                     std::size_t oversample) {
  require(angle_count >= 2, "ISAR needs at least 2 angles");
  require(std::isfinite(angle_step_rad) && angle_step_rad > 0.0,
          "angle step must be > 0 (order the angles ascending)");
  require(samples.size() == angle_count * g.count, "samples must be angle_count x frequency count");
  check_grid(g, g.count, oversample);
  const std::size_t nf = g.count, na = angle_count;
  const std::size_t mf = nf * oversample, ma = na * oversample;
  const std::vector<double> wf = window_samples(window, nf), wa = window_samples(window, na);
  double w_sum = 0.0;
  for (double a : wa) {
    for (double f : wf)
      w_sum += a * f;
  }
  fftw::ComplexBuffer buf = fftw::complex_buffer(ma * mf);  // [angle][frequency]
  for (std::size_t a = 0; a < na; ++a) {
    for (std::size_t f = 0; f < nf; ++f) {
      const std::complex<double> s = samples[a * nf + f];
      require(std::isfinite(s.real()) && std::isfinite(s.imag()), "a sample is not finite");
      buf[a * mf + f] = {wa[a] * wf[f] * s.real(), wa[a] * wf[f] * s.imag()};
    }
  }
  {
    // Range: exp(+j 2 k_n R) along each row (only the na filled rows need it).
    const int len = static_cast<int>(mf);
    const fftw::Plan rows("ISAR range", [&] {
      return fftw_plan_many_dft(1, &len, static_cast<int>(na), as_fftw(buf.get()), nullptr, 1, len,
                                as_fftw(buf.get()), nullptr, 1, len, FFTW_BACKWARD, FFTW_ESTIMATE);
    });
    rows.execute();
    // Cross-range: exp(-j 2 k_c dtheta_m y) along each column.
    const int lena = static_cast<int>(ma);
    const fftw::Plan cols("ISAR cross-range", [&] {
      return fftw_plan_many_dft(1, &lena, len, as_fftw(buf.get()), nullptr, len, 1,
                                as_fftw(buf.get()), nullptr, len, 1, FFTW_FORWARD, FFTW_ESTIMATE);
    });
    cols.execute();
  }
  IsarImage img;
  const double bin_r = kSpeedOfLight_mps / (2.0 * g.step_hz * static_cast<double>(mf));
  const double f_c = g.start_hz + 0.5 * g.step_hz * static_cast<double>(nf - 1);
  const double k_c = 2.0 * kPi * f_c / kSpeedOfLight_mps;
  // 2 k_c step dy ma = 2 pi.
  const double bin_y = kPi / (k_c * angle_step_rad * static_cast<double>(ma));
  img.range_resolution_m = kSpeedOfLight_mps / (2.0 * g.step_hz * static_cast<double>(nf));
  img.cross_range_resolution_m =
      kSpeedOfLight_mps / f_c / (2.0 * angle_step_rad * static_cast<double>(na));
  img.range_m = axis(mf, bin_r);
  img.cross_range_m = axis(ma, bin_y);
  img.pixels_m.resize(ma * mf);
  const double k0 = 2.0 * kPi * g.start_hz / kSpeedOfLight_mps;
  const double centre = 0.5 * static_cast<double>(na - 1);
  for (std::size_t r = 0; r < ma; ++r) {
    const std::size_t src_r = (r + ma - ma / 2) % ma;
    // The angle index m counts from the sweep's start; the model's offset is m - (M-1)/2.
    const double shift = 2.0 * k_c * centre * angle_step_rad * img.cross_range_m[r];
    for (std::size_t c = 0; c < mf; ++c) {
      const std::size_t src_c = (c + mf - mf / 2) % mf;
      const double carrier = 2.0 * k0 * img.range_m[c] + shift;
      img.pixels_m[r * mf + c] = buf[src_r * mf + src_c] * std::polar(1.0 / w_sum, carrier);
    }
  }
  return img;
}

}  // namespace radar_emu::radar
