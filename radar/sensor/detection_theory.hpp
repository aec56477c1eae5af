#pragma once
// Detection theory in closed form (square-law detector, complex white Gaussian noise): threshold
// factors of CA- and OS-CFAR, the Marcum Q function, and probability of detection of Swerling 0
// and 1 targets. Used by the sensor at setup (thresholds) and by tests as the reference.

#include <cstddef>

namespace radar_emu::radar {

/// CA-CFAR multiplier of the mean of N training cells for a design Pfa:
/// alpha = N (Pfa^(-1/N) - 1) (Richards, Fundamentals of Radar Signal Processing, 2nd ed., 2014,
/// eqs. 6.134-6.135).
[[nodiscard]] double ca_cfar_alpha(std::size_t n_training, double pfa) noexcept;

/// OS-CFAR false-alarm probability for the k-th smallest of N cells times alpha:
/// Pfa = prod_{i=0}^{k-1} (N - i) / (N - i + alpha) (Rohling, IEEE Trans. AES-19(4), 1983;
/// Richards 2014, eqs. 6.158-6.168).
[[nodiscard]] double os_cfar_pfa(std::size_t n_training, std::size_t k, double alpha) noexcept;
/// The alpha that gives `pfa` (bisection on log Pfa, which falls monotonically with alpha).
[[nodiscard]] double os_cfar_alpha(std::size_t n_training, std::size_t k, double pfa) noexcept;

/// Marcum Q function Q1(a, b), by its Poisson-mixture series
/// Q1(a, b) = sum_k e^{-a^2/2} (a^2/2)^k / k! * sum_{j<=k} e^{-b^2/2} (b^2/2)^j / j!
/// (Marcum 1948; Shnidman, IEEE Trans. AES-25(1), 1989, eq. 2). Accurate to ~1e-12 for
/// a^2/2, b^2/2 up to ~700.
[[nodiscard]] double marcum_q1(double a, double b) noexcept;

/// Single-sample Pd of a non-fluctuating (Swerling 0) target with a known-noise threshold:
/// Pd = Q1(sqrt(2 SNR), sqrt(-2 ln Pfa)) (Richards 2014, sec. 6.3.2).
[[nodiscard]] double pd_swerling0(double snr, double pfa) noexcept;
/// Single-sample Pd of a Swerling 1 target, known noise: Pd = Pfa^(1/(1+SNR)) (Richards 2014,
/// eq. 6.99).
[[nodiscard]] double pd_swerling1(double snr, double pfa) noexcept;
/// Swerling 1 with CA-CFAR over N cells: Pd = (1 + alpha / (N (1 + SNR)))^(-N) (Richards 2014,
/// eq. 6.137).
[[nodiscard]] double pd_swerling1_ca(double snr, std::size_t n_training, double pfa) noexcept;
/// Swerling 1 with OS-CFAR (k-th of N): Pd = prod_{i<k} (N - i) / (N - i + alpha / (1 + SNR))
/// (Rohling 1983; Richards 2014, sec. 6.5.6).
[[nodiscard]] double pd_swerling1_os(double snr, std::size_t n_training, std::size_t k,
                                     double pfa) noexcept;
/// Swerling 0 with CA-CFAR over N cells: Pd averaged over the Gamma(N, 1/N)-distributed noise
/// estimate, E_y[Q1(sqrt(2 SNR), sqrt(2 alpha y))], by Gauss-Laguerre-free trapezoid quadrature on
/// y (the estimate is the mean of N unit exponentials).
[[nodiscard]] double pd_swerling0_ca(double snr, std::size_t n_training, double pfa) noexcept;

}  // namespace radar_emu::radar
