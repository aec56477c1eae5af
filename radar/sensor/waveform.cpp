#include "radar/sensor/waveform.hpp"

#include <cmath>
#include <complex>
#include <stdexcept>
#include <string>

#include "radar/constants.hpp"

namespace radar_emu::radar {

namespace {
void require(bool ok, const char* field, const std::string& rule) {
  if (!ok)
    throw std::invalid_argument(std::string("waveform: ") + field + " " + rule);
}
}  // namespace

double wavelength_m(const Waveform& w) noexcept {
  return kSpeedOfLight_mps / w.carrier_hz;
}
double chirp_rate_hz_per_s(const Waveform& w) noexcept {
  return w.bandwidth_hz / w.pulse_width_s;
}
double fast_sample_rate_hz(const Waveform& w) noexcept {
  if (w.sample_rate_hz > 0.0)
    return w.sample_rate_hz;
  return w.kind == WaveformKind::kPulsedLfm ? w.bandwidth_hz
                                            : static_cast<double>(w.range_bins) / w.pulse_width_s;
}
double range_resolution_m(const Waveform& w) noexcept {
  return kSpeedOfLight_mps / (2.0 * w.bandwidth_hz);
}
double range_bin_m(const Waveform& w) noexcept {
  const double fs = fast_sample_rate_hz(w);
  if (w.kind == WaveformKind::kPulsedLfm)
    return kSpeedOfLight_mps / (2.0 * fs);
  // Beat f_b = 2 k R / c; an N-point FFT of samples at fs has bins fs / N.
  return kSpeedOfLight_mps * fs /
         (2.0 * chirp_rate_hz_per_s(w) * static_cast<double>(w.range_bins));
}
double first_range_m(const Waveform& w) noexcept {
  return w.kind == WaveformKind::kPulsedLfm ? w.swath_start_m : 0.0;
}
double unambiguous_range_m(const Waveform& w) noexcept {
  if (w.kind == WaveformKind::kPulsedLfm)
    return kSpeedOfLight_mps * w.pri_s / 2.0;
  return range_bin_m(w) * static_cast<double>(w.range_bins);
}
double blind_range_m(const Waveform& w) noexcept {
  return w.kind == WaveformKind::kPulsedLfm ? kSpeedOfLight_mps * w.pulse_width_s / 2.0 : 0.0;
}
double unambiguous_velocity_mps(const Waveform& w) noexcept {
  return wavelength_m(w) / (4.0 * w.pri_s);
}
double velocity_bin_mps(const Waveform& w) noexcept {
  return wavelength_m(w) / (2.0 * static_cast<double>(w.pulses) * w.pri_s);
}
std::size_t pulse_samples(const Waveform& w) noexcept {
  if (w.kind == WaveformKind::kFmcw)
    return static_cast<std::size_t>(w.range_bins);
  return static_cast<std::size_t>(std::llround(w.pulse_width_s * fast_sample_rate_hz(w)));
}
double fold_velocity_mps(const Waveform& w, double v_mps) noexcept {
  const double v_ua = unambiguous_velocity_mps(w);
  const double period = 2.0 * v_ua;
  double f = std::fmod(v_mps + v_ua, period);
  if (f < 0.0)
    f += period;
  return f - v_ua;
}

void validate(const Waveform& w) {
  auto finite_pos = [](double x) { return std::isfinite(x) && x > 0.0; };
  require(finite_pos(w.carrier_hz), "carrier_hz", "must be a finite number > 0");
  require(finite_pos(w.bandwidth_hz), "bandwidth_hz", "must be a finite number > 0");
  require(finite_pos(w.pulse_width_s), "pulse_width_s", "must be a finite number > 0");
  require(finite_pos(w.pri_s), "pri_s", "must be a finite number > 0");
  require(w.pulses >= 1 && w.pulses <= 65536, "pulses", "must be in [1, 65536]");
  require(w.range_bins >= 2 && w.range_bins <= (1 << 20), "range_bins", "must be in [2, 2^20]");
  require(std::isfinite(w.sample_rate_hz) && w.sample_rate_hz >= 0.0, "sample_rate_hz",
          "must be >= 0 (0 selects the default)");
  const double fs = fast_sample_rate_hz(w);
  if (w.kind == WaveformKind::kPulsedLfm) {
    require(fs >= w.bandwidth_hz * (1.0 - 1e-9), "sample_rate_hz",
            "must be >= bandwidth_hz (complex sampling of the chirp)");
    require(pulse_samples(w) >= 1 && pulse_samples(w) <= (1u << 20), "pulse_width_s",
            "gives " + std::to_string(pulse_samples(w)) + " samples per pulse (1 .. 2^20)");
    require(w.pulse_width_s < w.pri_s, "pulse_width_s", "must be shorter than pri_s");
    require(std::isfinite(w.swath_start_m) && w.swath_start_m >= blind_range_m(w) * (1 - 1e-12),
            "swath_start_m",
            "must be >= the blind range c T / 2 = " + std::to_string(blind_range_m(w)) + " m");
    // The receive window (swath plus one pulse length) must end before the next transmission.
    const double window_end_s = 2.0 * w.swath_start_m / kSpeedOfLight_mps +
                                static_cast<double>(w.range_bins) / fs + w.pulse_width_s;
    require(window_end_s <= w.pri_s * (1 + 1e-9), "range_bins",
            "swath ends at " + std::to_string(window_end_s * 1e6) +
                " us after transmission, past the next pulse at pri_s = " +
                std::to_string(w.pri_s * 1e6) + " us");
  } else {
    require(w.pulse_width_s <= w.pri_s, "pulse_width_s", "(chirp ramp) must be <= pri_s");
  }
}

const char* waveform_name(WaveformKind kind) noexcept {
  return kind == WaveformKind::kPulsedLfm ? "pulsed_lfm" : "fmcw";
}
bool parse_waveform_kind(std::string_view name, WaveformKind& out) noexcept {
  if (name == "pulsed_lfm") {
    out = WaveformKind::kPulsedLfm;
    return true;
  }
  if (name == "fmcw") {
    out = WaveformKind::kFmcw;
    return true;
  }
  return false;
}

namespace {
double sinc(double x) {
  return std::abs(x) < 1e-12 ? 1.0 : std::sin(x) / x;
}
}  // namespace

double lfm_ambiguity(double tau_s, double doppler_hz, double pulse_width_s,
                     double chirp_rate_hz_per_s) noexcept {
  const double a = std::abs(tau_s) / pulse_width_s;
  if (a >= 1.0)
    return 0.0;
  const double t_eff = pulse_width_s * (1.0 - a);
  return std::abs((1.0 - a) * sinc(kPi * t_eff * (doppler_hz + chirp_rate_hz_per_s * tau_s)));
}

double lfm_train_ambiguity(double tau_s, double doppler_hz, double pulse_width_s,
                           double chirp_rate_hz_per_s, double pri_s, int pulses) noexcept {
  const int m = pulses < 1 ? 1 : pulses;
  const double s1 = std::sin(kPi * doppler_hz * pri_s);
  double sum = 0.0;
  for (int p = -(m - 1); p <= m - 1; ++p) {
    const double single =
        lfm_ambiguity(tau_s - p * pri_s, doppler_hz, pulse_width_s, chirp_rate_hz_per_s);
    if (single == 0.0)
      continue;
    const int count = m - (p < 0 ? -p : p);
    const double ratio = std::abs(s1) < 1e-12
                             ? static_cast<double>(count)
                             : std::abs(std::sin(kPi * doppler_hz * count * pri_s) / s1);
    sum += single * ratio;
  }
  return sum / m;
}

void ambiguity_numerical(const Waveform& w, std::span<const double> delays_s,
                         std::span<const double> dopplers_hz, std::span<double> out, int oversample,
                         bool train) noexcept {
  const double t_pulse = w.pulse_width_s;
  const double k = chirp_rate_hz_per_s(w);
  const int n_pulses = train ? (w.pulses < 1 ? 1 : w.pulses) : 1;
  const double span_s = train ? (n_pulses - 1) * w.pri_s + t_pulse : t_pulse;
  const double dt = 1.0 / (w.bandwidth_hz * (oversample < 1 ? 1 : oversample));
  const auto n = static_cast<std::size_t>(std::ceil(span_s / dt)) + 1;
  auto envelope = [&](double t) -> std::complex<double> {
    if (t < 0.0 || t > span_s)
      return {0.0, 0.0};
    const double p = train ? std::floor(t / w.pri_s) : 0.0;
    const double tl = t - p * w.pri_s;
    if (tl > t_pulse)
      return {0.0, 0.0};
    const double x = tl - 0.5 * t_pulse;
    return std::polar(1.0, kPi * k * x * x);
  };
  const double energy = static_cast<double>(n_pulses) * t_pulse;
  for (std::size_t id = 0; id < delays_s.size(); ++id) {
    const double tau = delays_s[id];
    for (std::size_t jd = 0; jd < dopplers_hz.size(); ++jd) {
      const double fd = dopplers_hz[jd];
      std::complex<double> acc{0.0, 0.0};
      for (std::size_t i = 0; i < n; ++i) {
        const double t = static_cast<double>(i) * dt;
        const std::complex<double> a = envelope(t);
        if (a == std::complex<double>{0.0, 0.0})
          continue;
        const std::complex<double> b = envelope(t - tau);
        if (b == std::complex<double>{0.0, 0.0})
          continue;
        const double wgt = (i == 0 || i + 1 == n) ? 0.5 : 1.0;
        acc += wgt * a * std::conj(b) * std::polar(1.0, 2.0 * kPi * fd * t);
      }
      out[jd * delays_s.size() + id] = std::abs(acc) * dt / energy;
    }
  }
}

}  // namespace radar_emu::radar
