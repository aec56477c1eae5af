#include "radar/sensor/range_doppler.hpp"

#include <fftw3.h>

#include <algorithm>
#include <cmath>
#include <optional>
#include <stdexcept>
#include <string>

#include "radar/constants.hpp"
#include "radar/fftw.hpp"

namespace radar_emu::radar {

namespace {

using fftw::as_fftw;

constexpr int kSteps = 64;  // table entries a bin

// Smallest 2^a 3^b 5^c 7^d >= n: sizes FFTW transforms fastest.
std::size_t good_fft_size(std::size_t n) {
  for (std::size_t m = n;; ++m) {
    std::size_t r = m;
    for (std::size_t p : {2u, 3u, 5u, 7u})
      while (r % p == 0)
        r /= p;
    if (r == 1)
      return m;
  }
}

std::complex<double> lerp(const std::complex<double>& a, const std::complex<double>& b, double t) {
  return a + (b - a) * t;
}

}  // namespace

// FFTW buffers and plans (radar/fftw.hpp: made and destroyed under the one planner lock).
struct RangeDopplerProcessor::Plans {
  fftw::ComplexBuffer fast;    // n_fft
  fftw::ComplexBuffer filter;  // n_fft, conj(FFT(h)) / n_fft (pulsed)
  fftw::ComplexBuffer slow;    // M x N_r, [pulse][range]
  fftw::Plan fast_forward, fast_backward, doppler;
};

RangeDopplerProcessor::RangeDopplerProcessor(const ProcessingConfig& config) : config_(config) {
  const Waveform& w = config.waveform;
  validate(w);
  if (config.kernel_half_width_bins < 0 || config.kernel_half_width_bins > 4096)
    throw std::invalid_argument("processing: kernel_half_width_bins must be in [0, 4096]");
  if (!(config.max_speed_mps > 0.0) || !std::isfinite(config.max_speed_mps))
    throw std::invalid_argument("processing: max_speed_mps must be a finite number > 0");
  for (const WindowSpec* s : {&config.range_window, &config.doppler_window}) {
    if (s->kind == WindowKind::kTaylor &&
        (!(s->taylor_sidelobe_db >= 13.3 && s->taylor_sidelobe_db <= 120.0) || s->taylor_nbar < 1 ||
         s->taylor_nbar > 63))
      throw std::invalid_argument(
          "processing: Taylor window needs sidelobe level in [13.3, 120] dB and nbar in [1, 63]");
  }
  pulsed_ = w.kind == WaveformKind::kPulsedLfm;
  n_range_ = static_cast<std::size_t>(w.range_bins);
  n_pulses_ = static_cast<std::size_t>(w.pulses);
  n_pulse_samples_ = pulse_samples(w);
  n_fast_ = pulsed_ ? n_range_ + n_pulse_samples_ - 1 : n_range_;
  n_fft_ = pulsed_ ? good_fft_size(n_fast_) : n_range_;
  range_bin_m_ = range_bin_m(w);
  first_range_m_ = first_range_m(w);
  unamb_range_m_ = unambiguous_range_m(w);
  fs_hz_ = fast_sample_rate_hz(w);
  pri_s_ = w.pri_s;
  dv_mps_ = velocity_bin_mps(w);
  lambda_m_ = wavelength_m(w);
  chirp_rate_ = chirp_rate_hz_per_s(w);
  inv_dv_ = 1.0 / dv_mps_;
  inv_range_bin_ = 1.0 / range_bin_m_;
  coupling_bins_per_mps_ = 2.0 * fs_hz_ / (lambda_m_ * chirp_rate_);

  // Windows: the range taper weights the matched filter's reference (pulsed) or the beat samples
  // (FMCW); the Doppler taper weights the pulses.
  w_range_.resize(n_pulse_samples_);
  w_doppler_.resize(n_pulses_);
  fill_window(config.range_window, w_range_);
  fill_window(config.doppler_window, w_doppler_);
  double sr = 0, sr2 = 0, sd = 0, sd2 = 0;
  for (double v : w_range_) {
    sr += v;
    sr2 += v * v;
  }
  for (double v : w_doppler_) {
    sd += v;
    sd2 += v * v;
  }
  processing_gain_ = (sr * sr / sr2) * (sd * sd / sd2);
  // Effective (RMS) bandwidth and CPI duration of the weighted signal: both waveforms map fast
  // time linearly onto the swept band, and slow time onto the CPI.
  auto rms_position = [](const std::vector<double>& taper) {
    double num = 0.0, den = 0.0;
    const auto n = static_cast<double>(taper.size());
    for (std::size_t i = 0; i < taper.size(); ++i) {
      const double x = (static_cast<double>(i) + 0.5) / n - 0.5;
      num += x * x * taper[i] * taper[i];
      den += taper[i] * taper[i];
    }
    return den > 0.0 ? std::sqrt(num / den) : 0.0;
  };
  rms_bandwidth_ = 2.0 * kPi * w.bandwidth_hz * rms_position(w_range_);
  rms_duration_ = 2.0 * kPi * static_cast<double>(w.pulses) * w.pri_s * rms_position(w_doppler_);
  const double noise_norm = 1.0 / std::sqrt(sr2 * sd2);
  out_scale_ = pulsed_ ? noise_norm / static_cast<double>(n_fft_) : noise_norm;

  plans_ = std::make_unique<Plans>();
  plans_->fast = fftw::complex_buffer(n_fft_);
  plans_->filter = fftw::complex_buffer(n_fft_);
  plans_->slow = fftw::complex_buffer(n_pulses_ * n_range_);
  {
    const int nfft = static_cast<int>(n_fft_);
    std::complex<double>* fast = plans_->fast.get();
    plans_->fast_forward = fftw::Plan("processing", [&] {
      return fftw_plan_dft_1d(nfft, as_fftw(fast), as_fftw(fast), FFTW_FORWARD, FFTW_ESTIMATE);
    });
    plans_->fast_backward = fftw::Plan("processing", [&] {
      return fftw_plan_dft_1d(nfft, as_fftw(fast), as_fftw(fast), FFTW_BACKWARD, FFTW_ESTIMATE);
    });
    // Doppler: one length-M transform per range bin, stride N_r, in place on `slow`.
    const int m = static_cast<int>(n_pulses_);
    const int howmany = static_cast<int>(n_range_);
    std::complex<double>* slow = plans_->slow.get();
    plans_->doppler = fftw::Plan("processing", [&] {
      return fftw_plan_many_dft(1, &m, howmany, as_fftw(slow), nullptr, howmany, 1, as_fftw(slow),
                                nullptr, howmany, 1, FFTW_BACKWARD, FFTW_ESTIMATE);
    });
  }
  if (pulsed_) {
    // Matched filter reference h[i] = w_r[i] u(i / fs); store conj(FFT(h)).
    std::fill(plans_->fast.get(), plans_->fast.get() + n_fft_, std::complex<double>{0.0, 0.0});
    const double t_pulse = w.pulse_width_s;
    for (std::size_t i = 0; i < n_pulse_samples_; ++i) {
      const double x = (static_cast<double>(i) + 0.5) / fs_hz_ - 0.5 * t_pulse;
      plans_->fast[i] = w_range_[i] * std::polar(1.0, kPi * chirp_rate_ * x * x);
    }
    plans_->fast_forward.execute();
    for (std::size_t i = 0; i < n_fft_; ++i)
      plans_->filter[i] = std::conj(plans_->fast[i]);
  }

  // Velocity kernel table: W_d(x) = sum_m w_d[m] exp(j 2 pi x m / M) at x = i / kSteps over one
  // period, by a zero-padded FFT of the taper.
  const double nd = 1.0 / std::sqrt(sd2), nr = 1.0 / std::sqrt(sr2);
  range_norm_ = nr;
  auto periodic_table = [](const std::vector<double>& taper, std::size_t period, double scale) {
    const std::size_t n = period * kSteps;
    std::vector<std::complex<double>> table(n + 1);
    fftw::ComplexBuffer buf = fftw::complex_buffer(n);
    const fftw::Plan plan("processing", [&] {
      return fftw_plan_dft_1d(static_cast<int>(n), as_fftw(buf.get()), as_fftw(buf.get()),
                              FFTW_BACKWARD, FFTW_ESTIMATE);
    });
    for (std::size_t i = 0; i < taper.size(); ++i)
      buf[i] = taper[i];
    plan.execute();
    for (std::size_t i = 0; i < n; ++i)
      table[i] = buf[i] * scale;
    table[n] = table[0];  // closes the period for interpolation
    return table;
  };
  table_v_ = periodic_table(w_doppler_, n_pulses_, nd);
  if (!pulsed_) {
    table_r_ = periodic_table(w_range_, n_range_, nr);
    range_energy_ = static_cast<double>(n_range_);  // Parseval
  } else {
    range_energy_ = 0.0;
    const auto np = static_cast<long>(n_pulse_samples_);
    for (long x = -np; x <= np; ++x)
      range_energy_ += std::norm(pulse_mf_exact(static_cast<double>(x), 0.0) * nr);
    // Pulsed: G on offsets x in [-(K+1), K+1] from the coupled peak, for Doppler rows spanning
    // +-2 v_max / lambda.
    const auto k = static_cast<std::size_t>(config.kernel_half_width_bins) + 1;
    table_r_span_ = 2 * k * kSteps + 1;
    const double fd_max = 2.0 * config.max_speed_mps / lambda_m_;
    n_fd_rows_ = std::clamp<std::size_t>(
        static_cast<std::size_t>(std::ceil(2.0 * fd_max * w.pulse_width_s * kSteps)) + 1, 3, 4097);
    fd_min_hz_ = -fd_max;
    fd_row_step_hz_ = 2.0 * fd_max / static_cast<double>(n_fd_rows_ - 1);
    table_r_.resize(table_r_span_ * n_fd_rows_);
    for (std::size_t row = 0; row < n_fd_rows_; ++row) {
      const double fd = fd_min_hz_ + fd_row_step_hz_ * static_cast<double>(row);
      for (std::size_t i = 0; i < table_r_span_; ++i) {
        const double x = (static_cast<double>(i) - static_cast<double>(k * kSteps)) / kSteps;
        table_r_[row * table_r_span_ + i] = pulse_mf_exact(x - fd * fs_hz_ / chirp_rate_, fd) * nr;
      }
    }
  }
}

RangeDopplerProcessor::~RangeDopplerProcessor() = default;

std::pair<long, long> RangeDopplerProcessor::velocity_support(long half_width) const noexcept {
  // +-K bins, or every bin once when K reaches half the period.
  const auto nv = static_cast<long>(n_pulses_);
  return {std::max<long>(-half_width, -nv / 2), std::min<long>(half_width, nv - nv / 2 - 1)};
}

std::optional<long> RangeDopplerProcessor::velocity_offset(std::size_t velocity_bin,
                                                           double peak_bin) const noexcept {
  const auto nv = static_cast<long>(n_pulses_);
  const auto [dj0, dj1] = velocity_support(config_.kernel_half_width_bins);
  const long jc = std::lround(peak_bin);
  long d = ((static_cast<long>(velocity_bin) - jc) % nv + nv) % nv;  // [0, nv)
  if (d > dj1)
    d -= nv;
  if (d < dj0 || d > dj1)
    return std::nullopt;
  return d;
}

double RangeDopplerProcessor::range_of_bin(double bin) const noexcept {
  return first_range_m_ + bin * range_bin_m_;
}
double RangeDopplerProcessor::velocity_of_bin(double bin) const noexcept {
  return (bin - static_cast<double>(n_pulses_ / 2)) * dv_mps_;
}

// G(x; f_d) = sum_i w_r[i] u(t_i + x/fs) conj(u(t_i)) exp(j 2 pi f_d (t_i + x/fs - T/2)),
// t_i = (i + 1/2)/fs: the matched filter's output x samples after the echo's start
// (unnormalised). Sampling mid-interval keeps the pulse's samples symmetric about T/2.
std::complex<double> RangeDopplerProcessor::pulse_mf_exact(double x, double fd_hz) const noexcept {
  const double t_pulse = config_.waveform.pulse_width_s;
  std::complex<double> acc{0.0, 0.0};
  for (std::size_t i = 0; i < n_pulse_samples_; ++i) {
    const double t_echo = (static_cast<double>(i) + 0.5 + x) / fs_hz_;
    if (t_echo < 0.0 || t_echo >= t_pulse)
      continue;
    const double a = t_echo - 0.5 * t_pulse;
    const double b = (static_cast<double>(i) + 0.5) / fs_hz_ - 0.5 * t_pulse;
    acc +=
        w_range_[i] * std::polar(1.0, kPi * chirp_rate_ * (a * a - b * b) + 2.0 * kPi * fd_hz * a);
  }
  return acc;
}

std::complex<double> RangeDopplerProcessor::velocity_kernel(double x) const noexcept {
  const auto period = static_cast<double>(n_pulses_);
  double u = x - period * std::floor(x / period);
  if (!(u >= 0.0 && u < period))
    u = 0.0;
  const double f = u * kSteps;
  auto i = static_cast<std::size_t>(f);
  if (i >= n_pulses_ * kSteps)
    i = n_pulses_ * kSteps - 1;
  return lerp(table_v_[i], table_v_[i + 1], f - static_cast<double>(i));
}

std::complex<double> RangeDopplerProcessor::range_kernel(double x, double fd_hz) const noexcept {
  if (!pulsed_) {
    const auto period = static_cast<double>(n_range_);
    double u = std::fmod(x, period);
    if (u < 0.0)
      u += period;
    const double f = u * kSteps;
    auto i = static_cast<std::size_t>(f);
    if (i >= n_range_ * kSteps)
      i = n_range_ * kSteps - 1;
    return lerp(table_r_[i], table_r_[i + 1], f - static_cast<double>(i));
  }
  // Pulsed: x is the offset from the coupled peak; the echo starts at x + f_d fs / k.
  const auto k = static_cast<double>(config_.kernel_half_width_bins + 1);
  if (std::abs(x) >= k)  // outside the table: the exact sum (tests with wide supports)
    return pulse_mf_exact(x - fd_hz * fs_hz_ / chirp_rate_, fd_hz) * range_norm_;
  double row = (fd_hz - fd_min_hz_) / fd_row_step_hz_;
  row = std::clamp(row, 0.0, static_cast<double>(n_fd_rows_ - 1) - 1e-9);
  const auto r0 = static_cast<std::size_t>(row);
  const double tr = row - static_cast<double>(r0);
  const double f = (x + k) * kSteps;
  auto i = static_cast<std::size_t>(f);
  if (i >= table_r_span_ - 1)
    i = table_r_span_ - 2;
  const double ti = f - static_cast<double>(i);
  const std::complex<double>* a = &table_r_[r0 * table_r_span_];
  const std::complex<double>* b = a + table_r_span_;
  return lerp(lerp(a[i], a[i + 1], ti), lerp(b[i], b[i + 1], ti), tr);
}

ImagePosition RangeDopplerProcessor::position_of(double range_m,
                                                 double radial_velocity_mps) const noexcept {
  ImagePosition p;
  // Per return (every return of a frame): the divisions by setup constants are products by
  // their reciprocals (rounding-level).
  p.velocity_bin = radial_velocity_mps * inv_dv_ + static_cast<double>(n_pulses_ / 2);
  if (!std::isfinite(range_m) || !std::isfinite(radial_velocity_mps) || range_m < 0.0)
    return p;
  if (pulsed_) {
    // Echoes fold modulo the unambiguous range (second-time-around returns); fmod is the
    // identity below it (exact), so it is called only beyond.
    const double r_fold = range_m < unamb_range_m_ ? range_m : std::fmod(range_m, unamb_range_m_);
    const double start_bin = (r_fold - first_range_m_) * inv_range_bin_;
    // Range-Doppler coupling: - f_d fs / k with f_d = -2 v / lambda (Richards 2014, eqs.
    // 4.105-4.106), as one product by 2 fs / (lambda k).
    p.range_bin = start_bin + radial_velocity_mps * coupling_bins_per_mps_;
    p.in_swath = start_bin >= 0.0 && start_bin <= static_cast<double>(n_range_ - 1);
  } else {
    const double fd = -2.0 * radial_velocity_mps / lambda_m_;
    const double tau = 2.0 * range_m / kSpeedOfLight_mps;
    p.range_bin = static_cast<double>(n_range_) * (chirp_rate_ * tau - fd) / fs_hz_;
    p.in_swath = p.range_bin >= 0.0 && p.range_bin < static_cast<double>(n_range_);
  }
  return p;
}

void RangeDopplerProcessor::synthesize_cube(std::span<const PointScatterer> scatterers,
                                            std::span<std::complex<double>> cube) const noexcept {
  if (cube.size() < cube_samples())
    return;
  const double t_pulse = config_.waveform.pulse_width_s;
  const double t0 = 2.0 * first_range_m_ / kSpeedOfLight_mps;
  for (const PointScatterer& s : scatterers) {
    if (!position_of(s.range_m, s.radial_velocity_mps).in_swath)
      continue;
    const double fd = -2.0 * s.radial_velocity_mps / lambda_m_;
    for (std::size_t m = 0; m < n_pulses_; ++m) {
      const double tm =
          (static_cast<double>(m) - 0.5 * static_cast<double>(n_pulses_ - 1)) * pri_s_;
      const double tau = 2.0 * (s.range_m + s.radial_velocity_mps * tm) / kSpeedOfLight_mps;
      const std::complex<double> a = s.amplitude * std::polar(1.0, 2.0 * kPi * fd * tm);
      std::complex<double>* row = cube.data() + m * n_fast_;
      if (pulsed_) {
        const double tau_f = std::fmod(tau, pri_s_);
        for (std::size_t n = 0; n < n_fast_; ++n) {
          // The receiver samples mid-interval, t0 + (n + 1/2) / fs, as the reference does.
          const double te = t0 + (static_cast<double>(n) + 0.5) / fs_hz_ - tau_f;
          if (te < 0.0 || te >= t_pulse)
            continue;
          const double x = te - 0.5 * t_pulse;
          row[n] += a * std::polar(1.0, kPi * chirp_rate_ * x * x + 2.0 * kPi * fd * x);
        }
      } else {
        // Dechirped beat rx conj(tx): frequency f_d - k tau, phase of `a` at n = 0.
        const double f_beat = fd - chirp_rate_ * tau;
        for (std::size_t n = 0; n < n_fast_; ++n)
          row[n] += a * std::polar(1.0, 2.0 * kPi * f_beat * static_cast<double>(n) / fs_hz_);
      }
    }
  }
}

std::size_t RangeDopplerProcessor::echo(const PointScatterer& s,
                                        std::span<std::complex<double>> fast, std::size_t& first,
                                        std::span<std::complex<double>> slow) const noexcept {
  first = 0;
  if (slow.size() < n_pulses_ || fast.empty() ||
      !position_of(s.range_m, s.radial_velocity_mps).in_swath)
    return 0;
  const double fd = -2.0 * s.radial_velocity_mps / lambda_m_;
  for (std::size_t m = 0; m < n_pulses_; ++m) {
    const double tm = (static_cast<double>(m) - 0.5 * static_cast<double>(n_pulses_ - 1)) * pri_s_;
    slow[m] = s.amplitude * std::polar(1.0, 2.0 * kPi * fd * tm);
  }
  const double tau = 2.0 * s.range_m / kSpeedOfLight_mps;
  std::size_t count = 0;
  if (pulsed_) {
    // As synthesize_cube: samples at t0 + (n + 1/2) / fs inside the pulse [tau, tau + T).
    const double t_pulse = config_.waveform.pulse_width_s;
    const double t0 = 2.0 * first_range_m_ / kSpeedOfLight_mps;
    const double tau_f = std::fmod(tau, pri_s_);
    const double n_lo = std::ceil((tau_f - t0) * fs_hz_ - 0.5) - 1.0;
    for (auto n = static_cast<std::size_t>(std::max(0.0, n_lo)); n < n_fast_; ++n) {
      const double te = t0 + (static_cast<double>(n) + 0.5) / fs_hz_ - tau_f;
      if (te < 0.0)
        continue;
      if (te >= t_pulse || count >= fast.size())
        break;
      if (count == 0)
        first = n;
      const double x = te - 0.5 * t_pulse;
      fast[count++] = std::polar(1.0, kPi * chirp_rate_ * x * x + 2.0 * kPi * fd * x);
    }
    return count;
  }
  const double f_beat = fd - chirp_rate_ * tau;
  for (std::size_t n = 0; n < n_fast_ && count < fast.size(); ++n)
    fast[count++] = std::polar(1.0, 2.0 * kPi * f_beat * static_cast<double>(n) / fs_hz_);
  return count;
}

void RangeDopplerProcessor::process_cube(std::span<const std::complex<double>> cube,
                                         std::span<std::complex<double>> image) noexcept {
  if (cube.size() < cube_samples() || image.size() < image_cells())
    return;
  Plans& p = *plans_;
  for (std::size_t m = 0; m < n_pulses_; ++m) {
    const std::complex<double>* row = cube.data() + m * n_fast_;
    if (pulsed_) {
      std::copy(row, row + n_fast_, p.fast.get());
      std::fill(p.fast.get() + n_fast_, p.fast.get() + n_fft_, std::complex<double>{0.0, 0.0});
      p.fast_forward.execute();
      for (std::size_t i = 0; i < n_fft_; ++i)
        p.fast[i] *= p.filter[i];
      p.fast_backward.execute();  // correlation: y[l] = sum_i x[l + i] conj(h[i]) * n_fft
    } else {
      for (std::size_t n = 0; n < n_fast_; ++n)
        p.fast[n] = row[n] * w_range_[n];
      p.fast_backward.execute();
    }
    const double wd = w_doppler_[m] * out_scale_;
    std::complex<double>* slow_row = p.slow.get() + m * n_range_;
    for (std::size_t l = 0; l < n_range_; ++l)
      slow_row[l] = p.fast[l] * wd;
  }
  p.doppler.execute();
  // FFT bin k holds velocity k dv (mod M); image row j = (k + M/2) mod M.
  const std::size_t half = n_pulses_ / 2;
  for (std::size_t k = 0; k < n_pulses_; ++k) {
    const std::size_t j = (k + half) % n_pulses_;
    std::copy(p.slow.get() + k * n_range_, p.slow.get() + (k + 1) * n_range_,
              image.data() + j * n_range_);
  }
}

bool RangeDopplerProcessor::add_direct(const PointScatterer& s,
                                       std::span<std::complex<double>> image,
                                       int half_width_bins) const noexcept {
  const ImagePosition pos = position_of(s.range_m, s.radial_velocity_mps);
  const double radial_velocity_mps = s.radial_velocity_mps;
  const std::complex<double> amplitude = s.amplitude;
  if (!pos.in_swath || image.size() < image_cells())
    return false;
  const int k = half_width_bins < 0 ? config_.kernel_half_width_bins : half_width_bins;
  const double fd = -2.0 * radial_velocity_mps / lambda_m_;
  const double nu = radial_velocity_mps / dv_mps_;
  const auto m = static_cast<double>(n_pulses_);
  const std::complex<double> a = amplitude * std::polar(1.0, kPi * nu * (m - 1.0) / m);
  const auto lc = static_cast<long>(std::lround(pos.range_bin));
  const auto jc = static_cast<long>(std::lround(pos.velocity_bin));
  const auto nr = static_cast<long>(n_range_);
  const auto nv = static_cast<long>(n_pulses_);
  const long l0 = std::max<long>(0, lc - k), l1 = std::min<long>(nr - 1, lc + k);
  // The range response once per bin (it does not depend on the velocity bin).
  constexpr long kCached = 65;
  std::complex<double> range_values[kCached];
  const bool cached = l1 - l0 + 1 <= kCached;
  if (cached)
    for (long l = l0; l <= l1; ++l)
      range_values[l - l0] = range_kernel(static_cast<double>(l) - pos.range_bin, fd);
  const auto [dj0, dj1] = velocity_support(k);
  for (long dj = dj0; dj <= dj1; ++dj) {
    const long j = ((jc + dj) % nv + nv) % nv;
    const std::complex<double> kv =
        a * velocity_kernel(static_cast<double>(jc + dj) - pos.velocity_bin);
    std::complex<double>* row = image.data() + static_cast<std::size_t>(j) * n_range_;
    for (long l = l0; l <= l1; ++l)
      row[l] += kv * (cached ? range_values[l - l0]
                             : range_kernel(static_cast<double>(l) - pos.range_bin, fd));
  }
  return true;
}

bool RangeDopplerProcessor::footprint(std::complex<double> amplitude, const ImagePosition& pos,
                                      double radial_velocity_mps, Footprint& f) const noexcept {
  f.n_rows = 0;
  f.l1 = f.l0 - 1;
  if (!pos.in_swath)
    return false;
  const long k = std::min<long>(config_.kernel_half_width_bins, (Footprint::kMaxBins - 1) / 2);
  const double fd = -2.0 * radial_velocity_mps / lambda_m_;
  const double nu = radial_velocity_mps / dv_mps_;
  const auto m = static_cast<double>(n_pulses_);
  const std::complex<double> a = amplitude * std::polar(1.0, kPi * nu * (m - 1.0) / m);
  const long lc = std::lround(pos.range_bin), jc = std::lround(pos.velocity_bin);
  const auto nr = static_cast<long>(n_range_), nv = static_cast<long>(n_pulses_);
  f.l0 = std::max<long>(0, lc - k);
  f.l1 = std::min<long>(nr - 1, lc + k);
  // Successive bins are one bin apart: one fractional position, then steps of kSteps entries
  // through the tables (the same interpolation weight for every bin).
  const double x0 = static_cast<double>(f.l0) - pos.range_bin;
  if (!pulsed_) {
    const std::size_t period = n_range_ * kSteps;
    const auto pr = static_cast<double>(n_range_);
    double u = x0 - pr * std::floor(x0 / pr);
    double fi = u * kSteps;
    auto i = std::min(static_cast<std::size_t>(fi), period - 1);
    const double t = fi - static_cast<double>(i);
    for (long l = f.l0; l <= f.l1; ++l) {
      f.range[l - f.l0] = lerp(table_r_[i], table_r_[i + 1], t);
      i += kSteps;
      if (i >= period)
        i -= period;
    }
  } else {
    const auto kk = static_cast<double>(config_.kernel_half_width_bins + 1);
    double row = (fd - fd_min_hz_) / fd_row_step_hz_;
    row = std::clamp(row, 0.0, static_cast<double>(n_fd_rows_ - 1) - 1e-9);
    const auto r0 = static_cast<std::size_t>(row);
    const double tr = row - static_cast<double>(r0);
    const std::complex<double>* ra = &table_r_[r0 * table_r_span_];
    const std::complex<double>* rb = ra + table_r_span_;
    const double fi = (x0 + kk) * kSteps;
    const double base = std::floor(fi);
    const double t = fi - base;
    auto i = static_cast<long>(base);
    for (long l = f.l0; l <= f.l1; ++l, i += kSteps) {
      if (i >= 0 && i + 1 < static_cast<long>(table_r_span_)) {
        const auto u = static_cast<std::size_t>(i);
        f.range[l - f.l0] = lerp(lerp(ra[u], ra[u + 1], t), lerp(rb[u], rb[u + 1], t), tr);
      } else {
        f.range[l - f.l0] = range_kernel(static_cast<double>(l) - pos.range_bin, fd);
      }
    }
  }
  const auto [dj0, dj1] = velocity_support(k);
  const std::size_t period_v = n_pulses_ * kSteps;
  const double xv = static_cast<double>(jc + dj0) - pos.velocity_bin;
  const double uv = xv - m * std::floor(xv / m);
  const double fv = uv * kSteps;
  auto iv = std::min(static_cast<std::size_t>(fv), period_v - 1);
  const double tv = fv - static_cast<double>(iv);
  for (long dj = dj0; dj <= dj1; ++dj) {
    f.rows[f.n_rows] = static_cast<std::uint32_t>(((jc + dj) % nv + nv) % nv);
    f.velocity[f.n_rows] = a * lerp(table_v_[iv], table_v_[iv + 1], tv);
    ++f.n_rows;
    iv += kSteps;
    if (iv >= period_v)
      iv -= period_v;
  }
  return true;
}

void RangeDopplerProcessor::add_footprint(const Footprint& f, double gain,
                                          std::span<std::complex<double>> image) const noexcept {
  if (image.size() < image_cells())
    return;
  const long n = f.l1 - f.l0 + 1;
  for (int r = 0; r < f.n_rows; ++r) {
    const std::complex<double> kv = f.velocity[r] * gain;
    std::complex<double>* row = image.data() + static_cast<std::size_t>(f.rows[r]) * n_range_ +
                                static_cast<std::size_t>(f.l0);
    // row[i] += kv * range[i], the product written out as the fast path of std::complex's
    // (a + ib)(c + id) = (ac - bd) + i(ad + bc): the same operations, so the same result for
    // finite values, without the NaN branch that keeps the compiler from vectorising the loop.
    const double a = kv.real(), b = kv.imag();
    const std::complex<double>* x = f.range;
    for (long i = 0; i < n; ++i) {
      const double c = x[i].real(), d = x[i].imag();
      row[i] = {row[i].real() + (a * c - b * d), row[i].imag() + (a * d + b * c)};
    }
  }
}

void RangeDopplerProcessor::velocity_power_taps(double velocity_bin, long dj0, long dj1,
                                                double* out) const noexcept {
  const auto m = static_cast<double>(n_pulses_);
  const std::size_t period = n_pulses_ * kSteps;
  const double x = static_cast<double>(std::lround(velocity_bin) + dj0) - velocity_bin;
  const double fv = (x - m * std::floor(x / m)) * kSteps;
  auto i = std::min(static_cast<std::size_t>(fv), period - 1);
  const double t = fv - static_cast<double>(i);
  for (long dj = dj0; dj <= dj1; ++dj) {
    *out++ = std::norm(lerp(table_v_[i], table_v_[i + 1], t));
    i += kSteps;
    if (i >= period)
      i -= period;
  }
}

double RangeDopplerProcessor::velocity_power(double x) const noexcept {
  return std::norm(velocity_kernel(x));
}

std::complex<double> RangeDopplerProcessor::response_at(const PointScatterer& s,
                                                        std::size_t range_bin,
                                                        std::size_t velocity_bin) const noexcept {
  // The same support as add_direct: +-K bins around the nearest bin in range and velocity.
  const ImagePosition pos = position_of(s.range_m, s.radial_velocity_mps);
  const long k = config_.kernel_half_width_bins;
  if (!pos.in_swath || std::labs(static_cast<long>(range_bin) - std::lround(pos.range_bin)) > k)
    return {0.0, 0.0};
  const std::optional<long> d = velocity_offset(velocity_bin, pos.velocity_bin);
  if (!d)
    return {0.0, 0.0};
  const long jc = std::lround(pos.velocity_bin);
  const double fd = -2.0 * s.radial_velocity_mps / lambda_m_;
  const double nu = s.radial_velocity_mps / dv_mps_;
  const auto m = static_cast<double>(n_pulses_);
  const std::complex<double> a = s.amplitude * std::polar(1.0, kPi * nu * (m - 1.0) / m);
  return a * velocity_kernel(static_cast<double>(jc + *d) - pos.velocity_bin) *
         range_kernel(static_cast<double>(range_bin) - pos.range_bin, fd);
}

double RangeDopplerProcessor::straddle_gain(double range_offset_bins,
                                            double velocity_offset_bins) const noexcept {
  const double r0 = std::norm(range_kernel(0.0, 0.0));
  const double v0 = std::norm(velocity_kernel(0.0));
  if (r0 == 0.0 || v0 == 0.0)
    return 0.0;
  return std::norm(range_kernel(range_offset_bins, 0.0)) / r0 *
         std::norm(velocity_kernel(velocity_offset_bins)) / v0;
}

// ---- RawSynthesiser ----

struct RangeDopplerProcessor::RawSynthesiser::Fft {
  fftw::ComplexBuffer buf;  // n_fft
  fftw::ComplexBuffer sum;  // n_fft
  fftw::Plan forward, backward;
};

RangeDopplerProcessor::RawSynthesiser::RawSynthesiser(const RangeDopplerProcessor& processor,
                                                      std::size_t channels)
    : p_(processor), channels_(std::max<std::size_t>(channels, 1)) {
  supported_ = p_.pulsed_;
  if (!supported_)
    return;
  taps_ = p_.n_pulse_samples_ + 1;  // a pulse at a fractional delay spans one more sample
  len_ = p_.n_fast_ + taps_;        // echoes may start up to taps_ samples before sample 0
  n_fft_ = good_fft_size(len_ + taps_);
  acc_.assign(channels_ * kPhases * p_.n_pulses_ * len_, std::complex<float>{});
  used_.assign(channels_ * kPhases, 0);
  templates_.assign(kPhases * n_fft_, std::complex<double>{});
  fft_ = std::make_unique<Fft>();
  fft_->buf = fftw::complex_buffer(n_fft_);
  fft_->sum = fftw::complex_buffer(n_fft_);
  {
    const int n = static_cast<int>(n_fft_);
    std::complex<double>* buf = fft_->buf.get();
    fft_->forward = fftw::Plan("raw synthesis", [&] {
      return fftw_plan_dft_1d(n, as_fftw(buf), as_fftw(buf), FFTW_FORWARD, FFTW_ESTIMATE);
    });
    fft_->backward = fftw::Plan("raw synthesis", [&] {
      return fftw_plan_dft_1d(n, as_fftw(buf), as_fftw(buf), FFTW_BACKWARD, FFTW_ESTIMATE);
    });
  }
  // The pulse at phase q: an echo whose delay is (n0 + q / kPhases) samples after the first
  // sample's time reaches sample n0 + i at t_e = (i + 1/2 - q / kPhases) / fs into the pulse.
  const double t_pulse = p_.config_.waveform.pulse_width_s;
  for (std::size_t q = 0; q < kPhases; ++q) {
    std::fill(fft_->buf.get(), fft_->buf.get() + n_fft_, std::complex<double>{});
    for (std::size_t i = 0; i < taps_; ++i) {
      const double te =
          (static_cast<double>(i) + 0.5 - static_cast<double>(q) / static_cast<double>(kPhases)) /
          p_.fs_hz_;
      if (te < 0.0 || te >= t_pulse)
        continue;
      const double x = te - 0.5 * t_pulse;
      fft_->buf[i] = std::polar(1.0, kPi * p_.chirp_rate_ * x * x);
    }
    fft_->forward.execute();
    std::copy(fft_->buf.get(), fft_->buf.get() + n_fft_,
              templates_.begin() + static_cast<long>(q * n_fft_));
  }
}

RangeDopplerProcessor::RawSynthesiser::~RawSynthesiser() = default;

void RangeDopplerProcessor::RawSynthesiser::clear() noexcept {
  const std::size_t row = p_.n_pulses_ * len_;
  for (std::size_t k = 0; k < used_.size(); ++k) {
    if (used_[k] != 0)
      std::fill(acc_.begin() + static_cast<long>(k * row),
                acc_.begin() + static_cast<long>((k + 1) * row), std::complex<float>{});
    used_[k] = 0;
  }
}

void RangeDopplerProcessor::RawSynthesiser::add(const PointScatterer& s,
                                                std::span<const double> gains) noexcept {
  if (!supported_ || gains.size() < channels_ ||
      !p_.position_of(s.range_m, s.radial_velocity_mps).in_swath)
    return;
  const double fd = -2.0 * s.radial_velocity_mps / p_.lambda_m_;
  const double tau_f = std::fmod(2.0 * s.range_m / kSpeedOfLight_mps, p_.pri_s_);
  const double t0 = 2.0 * p_.first_range_m_ / kSpeedOfLight_mps;
  // exp(j pi k x^2 + j 2 pi fd x) = exp(j pi k (x + fd/k)^2) exp(-j pi fd^2 / k): the pulse
  // delayed by tau - fd / k, times a constant phase (its envelope moves by fd / k, < 0.1 sample
  // at 94 GHz and 100 m/s, neglected).
  const double d = (tau_f - fd / p_.chirp_rate_ - t0) * p_.fs_hz_;
  auto n0 = static_cast<long>(std::floor(d));
  auto q = static_cast<std::size_t>(std::lround((d - static_cast<double>(n0)) * kPhases));
  if (q == kPhases) {
    q = 0;
    ++n0;
  }
  const long a = n0 + static_cast<long>(taps_);
  if (a < 0 || a >= static_cast<long>(len_))
    return;
  const double tm0 = -0.5 * static_cast<double>(p_.n_pulses_ - 1) * p_.pri_s_;
  std::complex<double> v =
      s.amplitude * std::polar(1.0, 2.0 * kPi * fd * tm0 - kPi * fd * fd / p_.chirp_rate_);
  const std::complex<double> step = std::polar(1.0, 2.0 * kPi * fd * p_.pri_s_);
  const std::size_t row = p_.n_pulses_ * len_;
  for (std::size_t ch = 0; ch < channels_; ++ch)
    used_[ch * kPhases + q] = gains[ch] != 0.0 ? 1 : used_[ch * kPhases + q];
  for (std::size_t m = 0; m < p_.n_pulses_; ++m) {
    for (std::size_t ch = 0; ch < channels_; ++ch) {
      if (gains[ch] == 0.0)
        continue;
      std::complex<float>& cell =
          acc_[(ch * kPhases + q) * row + m * len_ + static_cast<std::size_t>(a)];
      cell += std::complex<float>(v * gains[ch]);
    }
    v *= step;
  }
}

void RangeDopplerProcessor::RawSynthesiser::render(std::span<std::complex<float>> cube) noexcept {
  const std::size_t nf = p_.n_fast_, np = p_.n_pulses_;
  if (!supported_ || cube.size() < channels_ * np * nf)
    return;
  const std::size_t row = np * len_;
  const double scale = 1.0 / static_cast<double>(n_fft_);
  for (std::size_t ch = 0; ch < channels_; ++ch) {
    bool any = false;
    for (std::size_t q = 0; q < kPhases; ++q)
      any = any || used_[ch * kPhases + q] != 0;
    if (!any)
      continue;
    for (std::size_t m = 0; m < np; ++m) {
      std::fill(fft_->sum.get(), fft_->sum.get() + n_fft_, std::complex<double>{});
      for (std::size_t q = 0; q < kPhases; ++q) {
        if (used_[ch * kPhases + q] == 0)
          continue;
        const std::complex<float>* in = acc_.data() + (ch * kPhases + q) * row + m * len_;
        for (std::size_t i = 0; i < len_; ++i)
          fft_->buf[i] = std::complex<double>(in[i]);
        std::fill(fft_->buf.get() + len_, fft_->buf.get() + n_fft_, std::complex<double>{});
        fft_->forward.execute();
        const std::complex<double>* h = templates_.data() + q * n_fft_;
        for (std::size_t i = 0; i < n_fft_; ++i) {  // written out: no NaN branches
          const double br = fft_->buf[i].real(), bi = fft_->buf[i].imag();
          const double hr = h[i].real(), hi = h[i].imag();
          fft_->sum[i] += std::complex<double>(br * hr - bi * hi, br * hi + bi * hr);
        }
      }
      std::copy(fft_->sum.get(), fft_->sum.get() + n_fft_, fft_->buf.get());
      fft_->backward.execute();
      // Sample n of the pulse is the convolution's output n + taps_.
      std::complex<float>* out = cube.data() + (ch * np + m) * nf;
      for (std::size_t n = 0; n < nf; ++n)
        out[n] += std::complex<float>(fft_->buf[n + taps_] * scale);
    }
  }
}

}  // namespace radar_emu::radar
