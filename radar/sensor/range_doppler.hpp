#pragma once
// Signal synthesis and range-Doppler processing for one receive channel and one beam position.
//
// Two paths give the same range-Doppler image:
//  * exact: synthesise the baseband data cube (slow time x fast time) sample by sample from point
//    scatterers, then compress in range (pulsed: matched filter by FFT fast convolution; FMCW:
//    windowed FFT of the dechirped beat) and FFT across pulses (FFTW);
//  * direct: add each scatterer's response to the image from kernel tables computed at setup from
//    the same processing, over +-K bins around its peak. Exact inside that support up to the
//    tables' interpolation (64 steps a bin, linear: < 1e-3 relative); what it neglects is listed
//    in docs/architecture.md (sidelobes beyond K bins, range walk during the CPI, echoes that
//    straddle the swath's edges).
// Images are [velocity bin][range bin], range contiguous, scaled so that receiver noise of unit
// variance per fast-time sample gives unit mean power per cell: |cell|^2 is an SNR.

#include <complex>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <optional>
#include <span>
#include <utility>
#include <vector>

#include "radar/sensor/waveform.hpp"
#include "radar/sensor/window.hpp"

namespace radar_emu::radar {

struct PointScatterer {
  /// Complex amplitude of the echo at the receiver, in units of the noise standard deviation of
  /// one fast-time sample (|a|^2 = single-sample SNR), phase at the centre of the CPI.
  std::complex<double> amplitude{0.0, 0.0};
  double range_m = 0.0;              ///< at the centre of the CPI
  double radial_velocity_mps = 0.0;  ///< positive receding
};

/// A point scatterer's direct response, prepared once and added to several images with
/// different gains (the beams of a scan): range values on bins l0..l1, velocity values on `rows`.
struct Footprint {
  static constexpr int kMaxBins = 65;  ///< 2 K + 1 with K <= 32
  long l0 = 0, l1 = -1;
  int n_rows = 0;
  std::complex<double> range[kMaxBins];
  std::complex<double> velocity[kMaxBins];
  std::uint32_t rows[kMaxBins];
};

struct ProcessingConfig {
  Waveform waveform;
  WindowSpec range_window{WindowKind::kHann};
  WindowSpec doppler_window{WindowKind::kHann};
  int kernel_half_width_bins = 4;  ///< direct path support, +-K bins in range and in velocity
  double max_speed_mps = 700.0;    ///< direct path (pulsed): largest |v| its coupling table covers
};

/// Where a scatterer's response peaks on the image, in fractional bins (before folding the
/// velocity bin into [0, M)), and whether it lands on the image at all.
struct ImagePosition {
  double range_bin = 0.0;     ///< includes range folding (pulsed) and range-Doppler coupling
  double velocity_bin = 0.0;  ///< v / dv + M/2
  bool in_swath = false;
};

class RangeDopplerProcessor {
 public:
  /// Setup: validates, builds windows, FFTW plans (FFTW_ESTIMATE: deterministic) and tables.
  explicit RangeDopplerProcessor(const ProcessingConfig& config);
  ~RangeDopplerProcessor();
  RangeDopplerProcessor(const RangeDopplerProcessor&) = delete;
  RangeDopplerProcessor& operator=(const RangeDopplerProcessor&) = delete;

  class RawSynthesiser;

  [[nodiscard]] const ProcessingConfig& config() const noexcept { return config_; }
  [[nodiscard]] std::size_t range_bins() const noexcept { return n_range_; }
  [[nodiscard]] std::size_t velocity_bins() const noexcept { return n_pulses_; }
  [[nodiscard]] std::size_t image_cells() const noexcept { return n_range_ * n_pulses_; }
  /// Fast-time samples per pulse in the raw cube: the swath plus one pulse (pulsed), N (FMCW).
  [[nodiscard]] std::size_t cube_fast_samples() const noexcept { return n_fast_; }
  [[nodiscard]] std::size_t cube_samples() const noexcept { return n_fast_ * n_pulses_; }

  /// The range taper (the matched filter's reference weights, pulsed; the beat samples', FMCW)
  /// and the Doppler taper (one weight a pulse), as the processing applies them.
  [[nodiscard]] std::span<const double> range_weights() const noexcept { return w_range_; }
  [[nodiscard]] std::span<const double> doppler_weights() const noexcept { return w_doppler_; }
  [[nodiscard]] double range_of_bin(double bin) const noexcept;
  [[nodiscard]] double velocity_of_bin(double bin) const noexcept;
  /// Peak SNR gain of the processing for an on-grid scatterer: |peak|^2 / |a|^2 =
  /// (sum w_r)^2 / sum w_r^2 * (sum w_d)^2 / sum w_d^2 (pulse samples x pulses / ENBWs).
  [[nodiscard]] double processing_gain() const noexcept { return processing_gain_; }
  [[nodiscard]] ImagePosition position_of(double range_m,
                                          double radial_velocity_mps) const noexcept;

  /// Exact path, step 1: adds the scatterers' echoes to a raw cube [pulse][fast sample].
  void synthesize_cube(std::span<const PointScatterer> scatterers,
                       std::span<std::complex<double>> cube) const noexcept;
  /// Exact path, separable: one scatterer's echo as the fast-time samples of a pulse (`fast`,
  /// the samples from `first` on that the echo reaches) times one complex factor a pulse
  /// (`slow`, velocity_bins() values: the amplitude and the Doppler phase), the delay taken at
  /// the centre of the CPI (the range walk neglected, as the direct path does). Returns the
  /// number of fast samples written (0: outside the swath or `slow` too short); at most
  /// fast.size(). Real-time safe.
  std::size_t echo(const PointScatterer& s, std::span<std::complex<double>> fast,
                   std::size_t& first, std::span<std::complex<double>> slow) const noexcept;
  /// Exact path, step 2: range compression and Doppler FFT of a raw cube into an image. Uses this
  /// object's scratch buffers: one call at a time per object. Real-time safe.
  void process_cube(std::span<const std::complex<double>> cube,
                    std::span<std::complex<double>> image) noexcept;

  /// Direct path: adds the scatterer's response times `gain` to the image (+-K bins; velocity
  /// wraps). Returns false (adds nothing) when the scatterer is outside the swath.
  bool add_direct(const PointScatterer& s, std::span<std::complex<double>> image,
                  int half_width_bins = -1) const noexcept;
  /// Prepares the direct response (support K <= 32); false outside the swath.
  bool footprint(std::complex<double> amplitude, const ImagePosition& pos,
                 double radial_velocity_mps, Footprint& f) const noexcept;
  /// Adds a prepared response times `gain`.
  void add_footprint(const Footprint& f, double gain,
                     std::span<std::complex<double>> image) const noexcept;
  /// |velocity response|^2 at x bins from its peak (periodic): the Doppler taper's leakage of
  /// clutter power.
  [[nodiscard]] double velocity_power(double x) const noexcept;
  /// velocity_power at the bins jc + dj, dj = dj0..dj1, jc = round(velocity_bin), into `out`.
  void velocity_power_taps(double velocity_bin, long dj0, long dj1, double* out) const noexcept;
  /// The direct path's velocity support for a half width K: bin offsets dj0..dj1 around the
  /// nearest bin (+-K, or every bin once when K reaches half the period).
  [[nodiscard]] std::pair<long, long> velocity_support(long half_width) const noexcept;
  /// Offset of `velocity_bin` from the bin nearest `peak_bin` when it lies in the configured
  /// support (wrapping); nothing otherwise.
  [[nodiscard]] std::optional<long> velocity_offset(std::size_t velocity_bin,
                                                    double peak_bin) const noexcept;
  /// The direct response of `s` at one cell (zero outside add_direct's support), without
  /// touching an image: for channels that are needed only at detections.
  [[nodiscard]] std::complex<double> response_at(const PointScatterer& s, std::size_t range_bin,
                                                 std::size_t velocity_bin) const noexcept;

  /// RMS bandwidth beta [rad/s] of the range-weighted spectrum and RMS duration alpha [s] of the
  /// Doppler-weighted CPI: 2 pi B sqrt(sum x_n^2 w_n^2 / sum w_n^2), x_n the sample's position
  /// in the band (or CPI) from -1/2 to 1/2 (Skolnik 2001, sec. 6.3; pi B / sqrt(3) unweighted).
  [[nodiscard]] double rms_bandwidth_rad_s() const noexcept { return rms_bandwidth_; }
  [[nodiscard]] double rms_duration_rad() const noexcept { return rms_duration_; }
  /// sum over range bins of |range response|^2 for a unit scatterer (Parseval: N for FMCW).
  [[nodiscard]] double range_energy() const noexcept { return range_energy_; }

  /// |response|^2 at fractional offsets from the peak, normalised to 1 at the peak: the
  /// straddle loss an interpolating detector corrects (no coupling term).
  [[nodiscard]] double straddle_gain(double range_offset_bins,
                                     double velocity_offset_bins) const noexcept;

 private:
  ProcessingConfig config_;
  std::size_t n_range_ = 0, n_pulses_ = 0, n_fast_ = 0, n_fft_ = 0, n_pulse_samples_ = 0;
  bool pulsed_ = true;
  double range_bin_m_ = 0, first_range_m_ = 0, unamb_range_m_ = 0, fs_hz_ = 0, pri_s_ = 0;
  double dv_mps_ = 0, lambda_m_ = 0, chirp_rate_ = 0, processing_gain_ = 1, out_scale_ = 1;
  double range_norm_ = 1;  ///< 1 / sqrt(sum w_r^2)
  /// position_of's constants: 1 / dv, 1 / range bin, and the pulsed range-Doppler coupling
  /// 2 fs / (lambda k) [bins per m/s]
  double inv_dv_ = 1, inv_range_bin_ = 1, coupling_bins_per_mps_ = 0;
  double range_energy_ = 1;
  double rms_bandwidth_ = 0, rms_duration_ = 0;
  std::vector<double> w_range_, w_doppler_;
  // Kernel tables, kSteps entries a bin. Velocity: W_d(x) over one period [0, M). Range: FMCW
  // W_r(x) over one period [0, N); pulsed: G(x; f_d) on +-(K+1) bins around the coupled peak, for
  // a grid of f_d.
  std::vector<std::complex<double>> table_v_, table_r_;
  std::size_t table_r_span_ = 0;  ///< pulsed: entries per Doppler row
  std::size_t n_fd_rows_ = 0;
  double fd_row_step_hz_ = 0, fd_min_hz_ = 0;
  // FFT scratch and plans (opaque FFTW types).
  struct Plans;
  std::unique_ptr<Plans> plans_;
  std::complex<double> velocity_kernel(double x) const noexcept;
  std::complex<double> range_kernel(double x, double fd_hz) const noexcept;
  std::complex<double> pulse_mf_exact(double x, double fd_hz) const noexcept;
};

/// Raw samples of many point echoes at once, pulsed LFM (the data cubes of docs/cube.md): each
/// echo's delay, with the range-Doppler coupling (tau - f_d / k), is rounded to 1/kPhases of a
/// fast-time sample; echoes in the same sample and phase add their slow-time factors (amplitude
/// and Doppler phase a pulse), and each phase's sum is convolved with the pulse sampled at that
/// phase (FFT). The delay at the centre of the CPI (no range walk, as the direct path). One
/// object a thread: setup allocates and plans; clear(), add() and render() do neither.
class RangeDopplerProcessor::RawSynthesiser {
 public:
  static constexpr std::size_t kPhases = 8;
  RawSynthesiser(const RangeDopplerProcessor& processor, std::size_t channels);
  ~RawSynthesiser();
  RawSynthesiser(const RawSynthesiser&) = delete;
  RawSynthesiser& operator=(const RawSynthesiser&) = delete;

  /// False for FMCW (the caller synthesises those echoes one by one, RangeDopplerProcessor::echo).
  [[nodiscard]] bool supported() const noexcept { return supported_; }
  void clear() noexcept;
  /// Adds one echo to every channel with its gain (gains.size() >= channels). Outside the swath:
  /// nothing.
  void add(const PointScatterer& s, std::span<const double> gains) noexcept;
  /// Adds the echoes added since clear() to `cube` [channel][pulse][fast sample]
  /// (channels x velocity_bins() x cube_fast_samples() values).
  void render(std::span<std::complex<float>> cube) noexcept;

 private:
  struct Fft;
  const RangeDopplerProcessor& p_;
  std::size_t channels_ = 1, taps_ = 0, len_ = 0, n_fft_ = 0;
  bool supported_ = false;
  std::vector<std::complex<float>> acc_;         ///< [channel][phase][pulse][len_]
  std::vector<std::uint8_t> used_;               ///< [channel][phase]: rows written since clear()
  std::vector<std::complex<double>> templates_;  ///< [phase][n_fft_]: FFT of the pulse
  std::unique_ptr<Fft> fft_;
};

}  // namespace radar_emu::radar
