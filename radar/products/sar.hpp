#pragma once
// Stripmap synthetic aperture radar: pulse geometry, raw-echo synthesis, matched-filter range
// compression (FFTW3) and time-domain backprojection (the reference image former).
//
// Geometry. The platform flies a straight track, position P(t) = start + v t, pulse i at
// t_i = i / PRF ("stop and hop": the platform is taken as still while a pulse travels; the
// error is the along-track shift v 2R/c, a few millimetres here, the same in synthesis and
// processing). The antenna looks to one side, perpendicular to the track, its boresight at
// `incidence_rad` from the vertical; its antenna frame is radar::RadarPose's (x boresight,
// y right, z down), so the SBR tracer (radar/em/sbr.hpp) sees the same beam.
//
// Antenna. A Gaussian main beam (a model assumption, not a measured pattern): one-way power gain
// G(az, el) = G0 exp(-4 ln 2 ((az / theta_az)^2 + (el / theta_el)^2)), -3 dB at +-theta / 2.
//
// Echo. A scatterer of complex scattering amplitude A [m] (|A|^2 = sigma, phase exp(-j k L) of
// its whole path L = 2R, radar/em/sbr.hpp's Contribution::amplitude) at range R gives the
// demodulated voltage (the radar equation's received power P_r = P_t G^2 lambda^2 sigma /
// ((4 pi)^3 R^4), Richards, Fundamentals of Radar Signal Processing, 2nd ed., 2014, the
// numerator of eq. 2.84 as in radar/sensor/sensor.cpp, as an amplitude into 1 ohm)
//   s(t) = sqrt(P_t) G lambda / ((4 pi)^(3/2) R^2) A e((t - tau) / T) exp(j pi K (t - tau)^2),
// tau = 2R/c, K = B/T, the linear FM (chirp) pulse centred on its delay (Cumming & Wong, Digital
// Processing of Synthetic Aperture Radar Data, 2005, ch. 3), its envelope e a
// rectangle with raised-cosine edges over kSarPulseEdge of T at each end (a transmitter's finite
// rise time; it also keeps the sampled pulse free of the aliased spectral tails of a hard-edged
// one, which would otherwise differ from pulse to pulse with the fractional delay). The carrier
// phase exp(-j 2 pi f_c tau) is A's own phase (sbr.hpp: exp(-j k L)); point scatterers given
// without a path phase (SarScatterer) get it from their range here.
//
// Range compression: the replica's matched filter conj(S(f)) (Cumming & Wong 2005, ch. 3),
// amplitude-equalised over the band, H(f) = conj(S(f)) / |S(f)|^2 W(f / B) on |f| <= B/2 (W: none
// or Hamming, 0.54 + 0.46 cos(2 pi f / B), Harris, Proc. IEEE 66(1), 1978): the compressed
// spectrum is then exactly the taper, without the Fresnel ripple of a chirp's spectrum (which
// raises the sidelobes of a short chirp by a dB and more); normalised so that a point scatterer's
// peak is its amplitude whatever the taper. That H, cut hard at +-B/2, has an impulse response
// that rings as 1/k without end (the sinc of a rectangular spectrum): a point's compressed
// sidelobes then spread over the whole swath (-62 dB at 300 gates unweighted, so a 60 dBsm return
// drew a line over the speckle), and the FFT's finite length wrapped them around. The filter is
// therefore kept to taps |k| <= m = sar_filter_half_length() (one replica length), with
// raised-cosine ends over its outer quarter (a Tukey window, Harris 1978), and applied by an FFT
// long enough for a linear convolution: a point's compressed response ends within (replica - 1)
// / 2 + m gates of it, a matched filter's own reach (its autocorrelation spans +-T) plus half,
// while the main lobe and first sidelobes keep the equalised ones (unit-tested PSLR and ISLR).
// Gate g is at slant range near_range + g c / (2 f_s).
//
// Backprojection (time-domain correlation; Soumekh, Synthetic Aperture Radar Signal Processing
// with MATLAB Algorithms, 1999; Cumming & Wong 2005, ch. 1): pixel X gets
//   I(X) = sum_i w_i c_i(R_i) exp(+j 4 pi R_i / lambda) (4 pi)^(3/2) R_i^2 / (sqrt(P_t) G_i
//          lambda) / sum_i w_i * exp(-j 4 pi R0(X) / lambda),   R_i = |P_i - X|,
// (the last factor basebands the image to each pixel's zero-Doppler range R0, its distance from
// the track: a point target's pixels then carry the phase -4 pi R0_T / lambda, as in a
// zero-Doppler SLC, instead of the carrier's ramp, curved in ground range, which no pixel grid
// samples without aliasing) over the pulses whose line of sight to X is within +-Theta/2 of
// broadside (Theta: the processed integration angle; azimuth resolution 0.886 lambda / (2 Theta)
// for w = 1), with w_i = 1 or Hamming in the pulse's angle over Theta, c_i the range-compressed
// pulse read by linear interpolation after an FFT upsampling by `upsample`. So a point scatterer at
// X images to its amplitude A (peak |I|^2 = sigma) and a distributed one of backscatter coefficient
// sigma0 to a mean intensity sigma0 rho_r_ground rho_a (rho = c/(2B) / sin(incidence), lambda / (2
// Theta): the integral of the unweighted impulse response's |h|^2 over the ground).
//
// Offline: these functions allocate and plan FFTs; they throw std::invalid_argument for bad input.
// synthesise_* write pulses [begin, end) of a preallocated raw matrix, so that ranks or threads
// can share the pulses.

#include <complex>
#include <cstddef>
#include <functional>
#include <glm/glm.hpp>
#include <span>
#include <vector>

namespace radar_emu::radar {

enum class SarTaper { kNone, kHamming };

/// Raised-cosine rise and fall of the transmitted pulse, as a fraction of its duration.
inline constexpr double kSarPulseEdge = 0.05;

struct SarParams {
  double carrier_hz = 35e9;
  double bandwidth_hz = 66.4e6;
  double pulse_duration_s = 4e-6;
  double sample_rate_hz = 74.9481145e6;  ///< complex; gate = c / (2 f_s)
  double prf_hz = 200.0;
  std::size_t pulses = 256;
  std::size_t gates = 512;
  double near_range_m = 4000.0;                 ///< slant range of gate 0
  glm::dvec3 start_position_m{0.0, 0.0, 2000};  ///< platform at pulse 0, world ENU
  glm::dvec3 velocity_mps{100.0, 0.0, 0.0};     ///< horizontal, constant
  bool look_right = true;
  double incidence_rad = 1.0995574287564276;  ///< boresight, from the vertical (63 deg)
  double azimuth_beamwidth_rad = 0.0035;      ///< one-way -3 dB, real antenna
  double elevation_beamwidth_rad = 0.2269;    ///< one-way -3 dB
  double peak_gain = 1.0;                     ///< G0 (linear)
  double transmit_power_w = 1.0;
};

/// Throws std::invalid_argument with a one-line reason naming the field.
void validate(const SarParams& p);

[[nodiscard]] double sar_wavelength_m(const SarParams& p) noexcept;
[[nodiscard]] double sar_gate_m(const SarParams& p) noexcept;  ///< c / (2 f_s)
/// Samples in one chirp replica (odd, centred), and in one raw pulse (gates + replica - 1).
[[nodiscard]] std::size_t sar_chirp_samples(const SarParams& p) noexcept;
[[nodiscard]] std::size_t sar_raw_samples(const SarParams& p) noexcept;
/// Half length m of the range-compression filter's impulse response (taps |k| <= m).
[[nodiscard]] std::size_t sar_filter_half_length(const SarParams& p) noexcept;
[[nodiscard]] double sar_pulse_time_s(const SarParams& p, std::size_t pulse) noexcept;
[[nodiscard]] glm::dvec3 sar_platform_m(const SarParams& p, double t_s) noexcept;
/// World from antenna (x boresight, y right, z down), the same for every pulse.
[[nodiscard]] glm::dmat3 sar_world_from_antenna(const SarParams& p) noexcept;
/// Unit along-track and horizontal cross-track (toward the look side) directions.
[[nodiscard]] glm::dvec3 sar_track_dir(const SarParams& p) noexcept;
[[nodiscard]] glm::dvec3 sar_look_dir(const SarParams& p) noexcept;
/// Two-way voltage gain G(az, el) toward world direction `d` (unit) from the antenna.
[[nodiscard]] double sar_two_way_gain(const SarParams& p, const glm::dvec3& d) noexcept;

/// One echo of one pulse: complex scattering amplitude A [m] with its path phase, range [m].
struct SarEcho {
  std::complex<double> amplitude_m{0.0, 0.0};
  double range_m = 0.0;
};

/// Raw data: pulses x sar_raw_samples, row-major, volts into 1 ohm; sample n of a pulse at
/// t = 2 near_range / c + (n - (replica - 1) / 2) / f_s.
struct SarRaw {
  std::size_t pulses = 0, samples = 0;
  std::vector<std::complex<float>> data;
};
[[nodiscard]] SarRaw make_raw(const SarParams& p);

/// Adds the chirps of `echoes` (amplitudes A, ranges; the antenna gain and the radar equation
/// applied here from the direction of `directions[k]`, unit, world, platform to scatterer) to
/// pulse row `row` (sar_raw_samples long). Echoes outside the recorded window are clipped.
void add_echoes(const SarParams& p, std::span<const SarEcho> echoes,
                std::span<const glm::dvec3> directions, std::span<std::complex<float>> row);

/// The same in two steps, for many echoes of one pulse: accumulate their linear-phase parts into
/// `acc` (sar_raw_samples long, double precision), then finish_pulse() applies the chirp's common
/// quadratic phase and adds the pulse to `row`.
void add_echoes_accumulate(const SarParams& p, std::span<const SarEcho> echoes,
                           std::span<const glm::dvec3> directions,
                           std::span<std::complex<double>> acc);
void finish_pulse(const SarParams& p, std::span<const std::complex<double>> acc,
                  std::span<std::complex<float>> row);

/// A point scatterer fixed in the world (its path phase from its range): the test's and the
/// clutter's building block. amplitude_m: sqrt(sigma) times any fixed phase (speckle).
struct SarScatterer {
  glm::dvec3 position_m{0.0};
  std::complex<double> amplitude_m{1.0, 0.0};
};
/// Synthesises pulses [begin, end) of the point scatterers into `raw` (added), threads over
/// pulses (TBB). Scatterers where the two-way voltage gain is under 1e-3 of the peak (-60 dB in
/// power) are skipped.
void synthesise_points(const SarParams& p, std::span<const SarScatterer> points, std::size_t begin,
                       std::size_t end, SarRaw& raw);

/// Range-compressed data: pulses x gates (gate g at near_range + g gate_m).
struct SarCompressed {
  std::size_t pulses = 0, gates = 0;
  std::vector<std::complex<float>> data;
};
[[nodiscard]] SarCompressed range_compress(const SarParams& p, const SarRaw& raw, SarTaper taper);

/// A ground image grid: pixel (row r, column c) at origin + r d_az track + c d_gr look (rows
/// along track, columns away from the track), at height origin.z, or at height_m[r cols + c]
/// when height_m is given (backprojection onto a DEM: radar/products/sar_terrain.hpp sar_dem).
struct SarImageGrid {
  glm::dvec3 origin_m{0.0};
  double azimuth_spacing_m = 1.0, ground_range_spacing_m = 1.0;
  std::size_t rows = 0, cols = 0;
  std::vector<float> height_m{};  ///< empty, or rows x cols world heights [m]
};

struct BackprojectionOptions {
  double integration_angle_rad = 0.00174;  ///< Theta
  SarTaper taper = SarTaper::kNone;
  std::size_t upsample = 16;  ///< of the range-compressed pulses before interpolation
  /// Pulses seen below this two-way gain relative to G0 are left out (no division by a null).
  double min_relative_gain = 0.01;
};

struct SarImage {
  SarImageGrid grid;
  std::vector<std::complex<float>> pixels;  ///< row-major, scattering amplitude [m]
  std::vector<std::uint32_t> looks;         ///< pulses that reached each pixel
};
[[nodiscard]] SarImage backproject(const SarParams& p, const SarCompressed& rc,
                                   const SarImageGrid& grid, const BackprojectionOptions& o);

/// Theory for the processed image: -3 dB slant-range resolution 0.886 c / (2B) (none) or
/// 1.30 c / (2B) (Hamming) (Harris 1978, Table 1: 3 dB widths 0.89 and 1.30 bins), azimuth the
/// same factors times lambda / (2 Theta).
/// The azimuth quadratic phase of a point target's image [rad per (azimuth pixel)^2]: pixel-centred
/// apertures give I(x) ~ exp(-j k (x - x_T)^2 / R) sinc: the two-way path difference
/// ((x_p - x)^2 - (x_p - x_T)^2) / (2R) summed over x_p in x +- L/2 (Fresnel approximation).
[[nodiscard]] double sar_azimuth_quadratic_phase(const SarParams& p, double range_m,
                                                 double azimuth_spacing_m) noexcept;

[[nodiscard]] double theory_range_resolution_m(const SarParams& p, SarTaper t) noexcept;
[[nodiscard]] double theory_azimuth_resolution_m(const SarParams& p, double theta_rad,
                                                 SarTaper t) noexcept;

}  // namespace radar_emu::radar
