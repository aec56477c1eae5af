#pragma once
// Radar waveforms: a pulsed linear-FM train and an FMCW chirp sequence, the quantities a radar
// engineer derives from them (resolution, bin sizes, ambiguities), and the ambiguity function.
//
// Conventions: complex envelope u(t) = exp(j pi k (t - T/2)^2) on 0 <= t < T (up-chirp, rate
// k = B/T); Doppler f_d = -2 v / lambda with v the range rate (positive receding), so an
// approaching target has positive Doppler (Richards 2014, eq. 2.93). Velocity bins are indexed
// j = 0..M-1 with v = (j - M/2) dv.

#include <cstddef>
#include <span>
#include <string_view>

namespace radar_emu::radar {

enum class WaveformKind { kPulsedLfm, kFmcw };

struct Waveform {
  WaveformKind kind = WaveformKind::kPulsedLfm;
  double carrier_hz = 94e9;
  double bandwidth_hz = 50e6;
  /// Pulsed: transmitted pulse length. FMCW: ramp time over which the ADC samples the beat.
  double pulse_width_s = 2e-6;
  double pri_s = 50e-6;  ///< pulse (or chirp) repetition interval
  int pulses = 64;       ///< pulses or chirps per coherent processing interval (CPI)
  /// Complex fast-time sample rate; 0 selects the bandwidth (pulsed) or range_bins / pulse_width_s
  /// (FMCW, so that the range bin is c / 2B).
  double sample_rate_hz = 0.0;
  int range_bins = 256;        ///< pulsed: range bins in the swath; FMCW: ADC samples per chirp
  double swath_start_m = 0.0;  ///< pulsed: range of bin 0 (>= the blind range c T / 2)
};

/// Validates (setup): throws std::invalid_argument naming the field and the rule it breaks.
void validate(const Waveform& w);

[[nodiscard]] double wavelength_m(const Waveform& w) noexcept;
[[nodiscard]] double chirp_rate_hz_per_s(const Waveform& w) noexcept;
[[nodiscard]] double fast_sample_rate_hz(const Waveform& w) noexcept;
/// Rayleigh range resolution c / 2B.
[[nodiscard]] double range_resolution_m(const Waveform& w) noexcept;
/// Spacing of the range bins: c / (2 fs) pulsed; c fs / (2 k N) FMCW.
[[nodiscard]] double range_bin_m(const Waveform& w) noexcept;
[[nodiscard]] double first_range_m(const Waveform& w) noexcept;
/// Pulsed: c PRI / 2 (echoes fold modulo it). FMCW: the largest beat the complex ADC resolves,
/// N range bins.
[[nodiscard]] double unambiguous_range_m(const Waveform& w) noexcept;
/// Pulsed: c T / 2, echoes closer arrive while the transmitter is on. FMCW: 0.
[[nodiscard]] double blind_range_m(const Waveform& w) noexcept;
/// lambda / (4 PRI): velocities fold into [-v_ua, v_ua).
[[nodiscard]] double unambiguous_velocity_mps(const Waveform& w) noexcept;
/// lambda / (2 M PRI), one Doppler bin.
[[nodiscard]] double velocity_bin_mps(const Waveform& w) noexcept;
/// Samples in one pulse, round(T fs) (pulsed); the chirp's samples N (FMCW).
[[nodiscard]] std::size_t pulse_samples(const Waveform& w) noexcept;
/// Velocity folded into [-v_ua, v_ua), as the slow-time sampling at the PRF aliases it.
[[nodiscard]] double fold_velocity_mps(const Waveform& w, double v_mps) noexcept;

[[nodiscard]] const char* waveform_name(WaveformKind kind) noexcept;
[[nodiscard]] bool parse_waveform_kind(std::string_view name, WaveformKind& out) noexcept;

/// Ambiguity function |chi(tau, f_d)| of one pulse or chirp (the envelope above), normalised to 1
/// at the origin, with chi(tau, f_d) = (1/T) integral u(t) u*(t - tau) exp(j 2 pi f_d t) dt
/// (Richards 2014, eq. 4.30 with this sign of tau). Computed numerically by the trapezoid rule
/// on `oversample` samples per 1/B. `out` is row-major [doppler][delay]; delays and dopplers are
/// the grid's axes. With `train`, u is the coherent train of w.pulses pulses at w.pri_s (cost grows
/// with the train's length: for tests and short trains).
void ambiguity_numerical(const Waveform& w, std::span<const double> delays_s,
                         std::span<const double> dopplers_hz, std::span<double> out,
                         int oversample = 8, bool train = false) noexcept;

/// Closed form of the linear-FM pulse: |chi| = |(1 - |tau|/T) sinc(pi T (f_d + k tau)
/// (1 - |tau|/T))| for |tau| <= T, else 0 (Richards 2014, eq. 4.98), sinc(x) = sin(x)/x. With this
/// convention the ridge runs along f_d = -k tau: a Doppler shift f_d moves the matched filter's
/// peak by tau = -f_d / k.
[[nodiscard]] double lfm_ambiguity(double tau_s, double doppler_hz, double pulse_width_s,
                                   double chirp_rate_hz_per_s) noexcept;

/// Coherent train of M identical pulses at repetition T_r (N. Levanon and E. Mozeson, Radar
/// Signals, Wiley 2004, ch. 6; checked against the numerical ambiguity of a sampled train in
/// tests/radar/waveform_test.cpp):
/// |chi_M(tau, f_d)| = (1/M) sum_{p=-(M-1)}^{M-1} |chi_1(tau - p T_r, f_d)|
///                     |sin(pi f_d (M - |p|) T_r) / sin(pi f_d T_r)|.
/// Valid when T_r >= 2 T (the single-pulse terms do not overlap).
[[nodiscard]] double lfm_train_ambiguity(double tau_s, double doppler_hz, double pulse_width_s,
                                         double chirp_rate_hz_per_s, double pri_s,
                                         int pulses) noexcept;

}  // namespace radar_emu::radar
