#include "radar/sensor/detection_theory.hpp"

#include <cmath>

namespace radar_emu::radar {

double ca_cfar_alpha(std::size_t n_training, double pfa) noexcept {
  const auto n = static_cast<double>(n_training);
  return n * (std::pow(pfa, -1.0 / n) - 1.0);
}

double os_cfar_pfa(std::size_t n_training, std::size_t k, double alpha) noexcept {
  double log_p = 0.0;
  for (std::size_t i = 0; i < k; ++i) {
    const auto m = static_cast<double>(n_training - i);
    log_p += std::log(m / (m + alpha));
  }
  return std::exp(log_p);
}

double os_cfar_alpha(std::size_t n_training, std::size_t k, double pfa) noexcept {
  double lo = 0.0, hi = 1.0;
  while (os_cfar_pfa(n_training, k, hi) > pfa && hi < 1e12)
    hi *= 2.0;
  for (int it = 0; it < 200; ++it) {
    const double mid = 0.5 * (lo + hi);
    (os_cfar_pfa(n_training, k, mid) > pfa ? lo : hi) = mid;
  }
  return 0.5 * (lo + hi);
}

double marcum_q1(double a, double b) noexcept {
  if (b <= 0.0)
    return 1.0;
  const double x = 0.5 * a * a, y = 0.5 * b * b;
  // Q1 = sum_k Poisson(k; x) * P[Poisson(y) <= k]. Terms are summed outward from the mode of
  // Poisson(x) until both tails are negligible.
  const double log_x = x > 0.0 ? std::log(x) : 0.0;
  const double log_y = std::log(y);
  auto poisson = [](double lambda, double log_lambda, double k) {
    if (lambda == 0.0)
      return k == 0.0 ? 1.0 : 0.0;
    return std::exp(-lambda + k * log_lambda - std::lgamma(k + 1.0));
  };
  // cdf[k] of Poisson(y) computed incrementally upward from 0.
  const double k_max = std::ceil(x + 40.0 * std::sqrt(x + 1.0) + 60.0);
  double sum = 0.0, cdf = 0.0;
  for (double k = 0.0; k <= k_max; k += 1.0) {
    cdf += poisson(y, log_y, k);
    if (cdf > 1.0)
      cdf = 1.0;
    sum += poisson(x, log_x, k) * cdf;
  }
  return sum > 1.0 ? 1.0 : sum;
}

double pd_swerling0(double snr, double pfa) noexcept {
  return marcum_q1(std::sqrt(2.0 * snr), std::sqrt(-2.0 * std::log(pfa)));
}

double pd_swerling1(double snr, double pfa) noexcept {
  return std::pow(pfa, 1.0 / (1.0 + snr));
}

double pd_swerling1_ca(double snr, std::size_t n_training, double pfa) noexcept {
  const auto n = static_cast<double>(n_training);
  return std::pow(1.0 + ca_cfar_alpha(n_training, pfa) / (n * (1.0 + snr)), -n);
}

double pd_swerling1_os(double snr, std::size_t n_training, std::size_t k, double pfa) noexcept {
  return os_cfar_pfa(n_training, k, os_cfar_alpha(n_training, k, pfa) / (1.0 + snr));
}

double pd_swerling0_ca(double snr, std::size_t n_training, double pfa) noexcept {
  // y = mean of N unit exponentials ~ Gamma(shape N, scale 1/N); threshold T = alpha y.
  const auto n = static_cast<double>(n_training);
  const double alpha = ca_cfar_alpha(n_training, pfa);
  const double sd = 1.0 / std::sqrt(n);
  const double lo = std::max(1e-6, 1.0 - 12.0 * sd), hi = 1.0 + 16.0 * sd;
  const int steps = 4000;
  const double h = (hi - lo) / steps;
  double acc = 0.0, norm = 0.0;
  for (int i = 0; i <= steps; ++i) {
    const double y = lo + h * i;
    const double log_f = n * std::log(n) + (n - 1.0) * std::log(y) - n * y - std::lgamma(n);
    const double f = std::exp(log_f) * ((i == 0 || i == steps) ? 0.5 : 1.0);
    acc += f * marcum_q1(std::sqrt(2.0 * snr), std::sqrt(2.0 * alpha * y));
    norm += f;
  }
  return acc / norm;
}

}  // namespace radar_emu::radar
