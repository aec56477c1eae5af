#include "radar/sensor/window.hpp"

#include <cmath>

#include "radar/constants.hpp"

namespace radar_emu::radar {

namespace {

// Generalised cosine taper a0 - a1 cos(2 pi n/(N-1)) + a2 cos(4 pi n/(N-1)) (Harris 1978, eq. 32
// with the symmetric length N-1 in the argument).
void cosine_sum(double a0, double a1, double a2, std::span<double> w) noexcept {
  const std::size_t n = w.size();
  if (n == 1) {
    w[0] = 1.0;
    return;
  }
  const double step = 2.0 * kPi / static_cast<double>(n - 1);
  for (std::size_t i = 0; i < n; ++i) {
    const double x = step * static_cast<double>(i);
    w[i] = a0 - a1 * std::cos(x) + a2 * std::cos(2.0 * x);
  }
}

// Taylor taper coefficients F_m, m = 1 .. nbar-1 (Carrara, Goodman and Majewski 1995, App. D):
// sigma^2 = nbar^2 / (A^2 + (nbar - 1/2)^2), A = acosh(R)/pi, R = 10^(SLL/20);
// F_m = (-1)^(m+1)/2 prod_n [1 - m^2/(sigma^2 (A^2 + (n-1/2)^2))] / prod_{n != m} [1 - m^2/n^2];
// w(x) = 1 + 2 sum_m F_m cos(2 pi m x), x in [-1/2, 1/2].
void taylor(double sll_db, int nbar, std::span<double> w) noexcept {
  const double r = std::pow(10.0, sll_db / 20.0);
  const double a = std::acosh(r) / kPi;
  const double nb = static_cast<double>(nbar);
  const double sigma2 = nb * nb / (a * a + (nb - 0.5) * (nb - 0.5));
  constexpr int kMaxNbar = 64;
  double f[kMaxNbar] = {};
  const int terms = nbar < kMaxNbar ? nbar : kMaxNbar;
  for (int m = 1; m < terms; ++m) {
    const double md = static_cast<double>(m);
    double num = 1.0, den = 1.0;
    for (int k = 1; k < terms; ++k) {
      const double kd = static_cast<double>(k);
      num *= 1.0 - md * md / (sigma2 * (a * a + (kd - 0.5) * (kd - 0.5)));
      if (k != m)
        den *= 1.0 - md * md / (kd * kd);
    }
    f[m] = ((m % 2 == 1) ? 0.5 : -0.5) * num / den;
  }
  const std::size_t n = w.size();
  double peak = 0.0;
  for (std::size_t i = 0; i < n; ++i) {
    const double x =
        (static_cast<double>(i) - 0.5 * static_cast<double>(n - 1)) / static_cast<double>(n);
    double v = 1.0;
    for (int m = 1; m < terms; ++m)
      v += 2.0 * f[m] * std::cos(2.0 * kPi * static_cast<double>(m) * x);
    w[i] = v;
    peak = v > peak ? v : peak;
  }
  for (double& v : w)
    v /= peak;
}

}  // namespace

void fill_window(const WindowSpec& spec, std::span<double> w) noexcept {
  if (w.empty())
    return;
  switch (spec.kind) {
    case WindowKind::kRectangular:
      for (double& v : w)
        v = 1.0;
      return;
    case WindowKind::kHann:
      cosine_sum(0.5, 0.5, 0.0, w);
      return;
    case WindowKind::kHamming:
      cosine_sum(0.54, 0.46, 0.0, w);
      return;
    case WindowKind::kBlackman:
      cosine_sum(0.42, 0.5, 0.08, w);
      return;
    case WindowKind::kTaylor:
      taylor(spec.taylor_sidelobe_db, spec.taylor_nbar < 1 ? 1 : spec.taylor_nbar, w);
      return;
  }
}

double documented_peak_sidelobe_db(const WindowSpec& spec) noexcept {
  switch (spec.kind) {
    case WindowKind::kRectangular:
      return -13.26;
    case WindowKind::kHann:
      return -31.5;
    case WindowKind::kHamming:
      return -42.7;
    case WindowKind::kBlackman:
      return -58.1;
    case WindowKind::kTaylor:
      return -spec.taylor_sidelobe_db;
  }
  return 0.0;
}

int taylor_min_nbar(double sidelobe_db) noexcept {
  const double a = std::acosh(std::pow(10.0, sidelobe_db / 20.0)) / kPi;
  return static_cast<int>(std::ceil(2.0 * a * a + 0.5));
}

WindowMetrics window_metrics(std::span<const double> w) noexcept {
  double s = 0.0, s2 = 0.0;
  for (double v : w) {
    s += v;
    s2 += v * v;
  }
  WindowMetrics m;
  const auto n = static_cast<double>(w.size());
  if (w.empty() || s == 0.0)
    return m;
  m.coherent_gain = s / n;
  m.enbw_bins = n * s2 / (s * s);
  return m;
}

std::optional<WindowKind> parse_window_kind(std::string_view name) noexcept {
  if (name == "rectangular" || name == "rect" || name == "none")
    return WindowKind::kRectangular;
  if (name == "hann")
    return WindowKind::kHann;
  if (name == "hamming")
    return WindowKind::kHamming;
  if (name == "blackman")
    return WindowKind::kBlackman;
  if (name == "taylor")
    return WindowKind::kTaylor;
  return std::nullopt;
}

const char* window_name(WindowKind kind) noexcept {
  switch (kind) {
    case WindowKind::kRectangular:
      return "rectangular";
    case WindowKind::kHann:
      return "hann";
    case WindowKind::kHamming:
      return "hamming";
    case WindowKind::kBlackman:
      return "blackman";
    case WindowKind::kTaylor:
      return "taylor";
  }
  return "?";
}

}  // namespace radar_emu::radar
