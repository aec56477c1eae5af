#include "radar/products/irf.hpp"

#include <fftw3.h>

#include <algorithm>
#include <cmath>
#include <memory>
#include <stdexcept>
#include <string>

#include "common/units.hpp"
#include "radar/constants.hpp"
#include "radar/fftw.hpp"

namespace radar_emu::radar {

namespace {

void require(bool ok, const std::string& what) {
  if (!ok)
    throw std::invalid_argument("point target analysis: " + what);
}

double db10(double x) {
  return common::db_from_power(std::max(x, 1e-300));
}

// -3 dB crossing between samples a (above half) and b (below), linear in power: offset from a.
double crossing(double a, double b, double half) {
  return (a - half) / (a - b);
}

}  // namespace

IrfCut analyse_cut(std::span<const double> power, double oversample, double sidelobe_widths) {
  require(power.size() >= 8, "cut too short");
  require(oversample >= 1.0 && sidelobe_widths > 0.0, "bad oversample or sidelobe widths");
  const auto n = static_cast<std::ptrdiff_t>(power.size());
  const auto peak_it = std::max_element(power.begin(), power.end());
  const std::ptrdiff_t k = peak_it - power.begin();
  const double peak = *peak_it;
  require(peak > 0.0, "the cut is all zero");
  IrfCut out;
  // -3 dB points.
  const double half = peak / 2;
  std::ptrdiff_t r = k, l = k;
  while (r + 1 < n && power[static_cast<std::size_t>(r + 1)] > half)
    ++r;
  while (l > 0 && power[static_cast<std::size_t>(l - 1)] > half)
    --l;
  require(r + 1 < n && l > 0, "the main lobe reaches the chip's edge");
  const double right =
      static_cast<double>(r) +
      crossing(power[static_cast<std::size_t>(r)], power[static_cast<std::size_t>(r + 1)], half);
  const double left =
      static_cast<double>(l) -
      crossing(power[static_cast<std::size_t>(l)], power[static_cast<std::size_t>(l - 1)], half);
  out.resolution_px = (right - left) / oversample;
  // First nulls: the first local minima each side.
  std::ptrdiff_t nr = k, nl = k;
  while (nr + 1 < n &&
         power[static_cast<std::size_t>(nr + 1)] < power[static_cast<std::size_t>(nr)])
    ++nr;
  while (nl > 0 && power[static_cast<std::size_t>(nl - 1)] < power[static_cast<std::size_t>(nl)])
    --nl;
  require(nr + 1 < n && nl > 0, "no first null inside the chip");
  const double width = static_cast<double>(std::max(nr - k, k - nl));
  const auto span = static_cast<std::ptrdiff_t>(std::llround(sidelobe_widths * width));
  const std::ptrdiff_t s0 = std::max<std::ptrdiff_t>(0, nl - span);
  const std::ptrdiff_t s1 = std::min<std::ptrdiff_t>(n - 1, nr + span);
  double main = 0.0, side = 0.0, side_peak = 0.0;
  for (std::ptrdiff_t i = s0; i <= s1; ++i) {
    const double v = power[static_cast<std::size_t>(i)];
    if (i >= nl && i <= nr) {
      main += v;
    } else {
      side += v;
      side_peak = std::max(side_peak, v);
    }
  }
  out.pslr_db = db10(side_peak / peak);
  out.islr_db = db10(side / main);
  out.power_db.resize(power.size());
  for (std::size_t i = 0; i < power.size(); ++i)
    out.power_db[i] = db10(power[i] / peak);
  return out;
}

IrfResult analyse_point_target(std::span<const std::complex<float>> image, std::size_t rows,
                               std::size_t cols, std::size_t row, std::size_t col,
                               const IrfOptions& o) {
  require(image.size() == rows * cols && rows > 0 && cols > 0, "image size mismatch");
  require(row < rows && col < cols, "expected peak outside the image");
  require(o.chip >= 8 && o.chip <= 1024 && o.chip % 2 == 0, "chip must be even, 8..1024");
  require(o.oversample >= 1 && o.oversample <= 64, "oversample must be in 1..64");
  const std::size_t n = o.chip, m = n * o.oversample;
  const auto r0 = static_cast<std::ptrdiff_t>(row) - static_cast<std::ptrdiff_t>(n / 2);
  const auto c0 = static_cast<std::ptrdiff_t>(col) - static_cast<std::ptrdiff_t>(n / 2);
  std::vector<std::complex<double>> chip(n * n);
  IrfResult res;
  for (std::size_t i = 0; i < n; ++i)
    for (std::size_t j = 0; j < n; ++j) {
      const std::ptrdiff_t rr = r0 + static_cast<std::ptrdiff_t>(i);
      const std::ptrdiff_t cc = c0 + static_cast<std::ptrdiff_t>(j);
      if (rr < 0 || cc < 0 || rr >= static_cast<std::ptrdiff_t>(rows) ||
          cc >= static_cast<std::ptrdiff_t>(cols))
        continue;
      chip[i * n + j] = std::complex<double>(
          image[static_cast<std::size_t>(rr) * cols + static_cast<std::size_t>(cc)]);
      res.chip_energy += std::norm(chip[i * n + j]);
    }
  // A known quadratic phase along each axis (IrfOptions), removed about the chip's centre.
  {
    const double c = static_cast<double>(n / 2);
    for (std::size_t i = 0; i < n; ++i)
      for (std::size_t j = 0; j < n; ++j) {
        const double di = static_cast<double>(i) - c, dj = static_cast<double>(j) - c;
        chip[i * n + j] *= std::polar(
            1.0, -(o.quadratic_phase_col_rad * dj * dj + o.quadratic_phase_row_rad * di * di));
      }
  }
  // Linear phase ramps: mean phase step between neighbours along each axis.
  std::complex<double> sx{}, sy{};
  for (std::size_t i = 0; i < n; ++i)
    for (std::size_t j = 0; j + 1 < n; ++j)
      sx += chip[i * n + j + 1] * std::conj(chip[i * n + j]);
  for (std::size_t i = 0; i + 1 < n; ++i)
    for (std::size_t j = 0; j < n; ++j)
      sy += chip[(i + 1) * n + j] * std::conj(chip[i * n + j]);
  const double fx = std::arg(sx), fy = std::arg(sy);
  for (std::size_t i = 0; i < n; ++i)
    for (std::size_t j = 0; j < n; ++j)
      chip[i * n + j] *=
          std::polar(1.0, -(fx * static_cast<double>(j) + fy * static_cast<double>(i)));

  fftw::ComplexBuffer a = fftw::complex_buffer(n * n), b = fftw::complex_buffer(m * m);
  for (std::size_t i = 0; i < n * n; ++i)
    a[i] = chip[i];
  fftw::Plan("irf", [&] {
    return fftw_plan_dft_2d(static_cast<int>(n), static_cast<int>(n), fftw::as_fftw(a.get()),
                            fftw::as_fftw(a.get()), FFTW_FORWARD, FFTW_ESTIMATE);
  }).execute();
  const std::size_t h = n / 2;
  auto dst = [&](std::size_t k) { return k < h ? k : m - n + k; };
  for (std::size_t i = 0; i < n; ++i)
    for (std::size_t j = 0; j < n; ++j) {
      if (i == h || j == h)
        continue;  // the Nyquist row and column: ambiguous, left out
      b[dst(i) * m + dst(j)] = a[i * n + j];
    }
  fftw::Plan("irf", [&] {
    return fftw_plan_dft_2d(static_cast<int>(m), static_cast<int>(m), fftw::as_fftw(b.get()),
                            fftw::as_fftw(b.get()), FFTW_BACKWARD, FFTW_ESTIMATE);
  }).execute();
  const double norm = 1.0 / static_cast<double>(n * n);
  std::vector<double> power(m * m);
  for (std::size_t i = 0; i < m * m; ++i)
    power[i] = (b[i].real() * b[i].real() + b[i].imag() * b[i].imag()) * norm * norm;
  const std::size_t k =
      static_cast<std::size_t>(std::max_element(power.begin(), power.end()) - power.begin());
  const std::size_t pi = k / m, pj = k % m;
  const double ov = static_cast<double>(o.oversample);
  res.peak_power = power[k];
  res.peak_row = static_cast<double>(r0) + static_cast<double>(pi) / ov;
  res.peak_col = static_cast<double>(c0) + static_cast<double>(pj) / ov;
  std::vector<double> cut(m);
  for (std::size_t j = 0; j < m; ++j)
    cut[j] = power[pi * m + j];
  res.range = analyse_cut(cut, ov, o.sidelobe_widths);
  for (std::size_t i = 0; i < m; ++i)
    cut[i] = power[i * m + pj];
  res.azimuth = analyse_cut(cut, ov, o.sidelobe_widths);
  return res;
}

}  // namespace radar_emu::radar
