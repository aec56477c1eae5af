#pragma once
// Antenna patterns, gain, scanning and amplitude-comparison monopulse.
//
// Patterns are one-way voltage patterns relative to the peak, separable in azimuth and elevation
// (E(az, el) = E_az(az) E_el(el)). Beamwidths are one-way 3-dB widths of the power pattern.
//   uniform aperture  E = sin(pi u)/(pi u),            u = (L/lambda) sin(theta)
//   cosine aperture   E = cos(pi u) / (1 - 4 u^2)        (the Fourier transforms of a uniform and
//                                                        a cosine line-source illumination;
//                                                        3-dB widths 0.886 and 1.19 lambda/L,
//                                                        first sidelobes -13.3 and -23 dB:
//                                                        Skolnik 2001, sec. 9.4)
//   Gaussian          E = exp(-2 ln 2 (theta / theta3)^2)
//   table             one-way gain [dB] vs angle, linear in dB between samples
// The aperture length L/lambda of the uniform and cosine patterns is set so that the 3-dB width is
// the configured one.
//
// Monopulse: two beams of the configured pattern squinted by +-d in a plane; sum and difference
// Sigma = (E(t - d) + E(t + d)) / (2 E(d)), Delta = (E(t - d) - E(t + d)) / (2 E(d)), so Sigma is 1
// on the sum beam's boresight and Delta / Sigma is odd and rises with t (Sherman and Barton,
// Monopulse Principles and Techniques, 2nd ed. 2011, ch. 4). For the Gaussian beam
// Delta / Sigma = tanh(4 ln 2 d t / theta3^2) exactly.

#include <cstddef>
#include <span>
#include <string_view>
#include <vector>

namespace radar_emu::radar {

enum class PatternKind { kUniform, kCosine, kGaussian, kTable };

struct PatternCut {
  PatternKind kind = PatternKind::kGaussian;
  double beamwidth_rad = 0.0175;        ///< one-way 3-dB width of the power pattern
  std::vector<double> table_angle_rad;  ///< kTable: increasing angles off boresight
  std::vector<double> table_gain_db;    ///< kTable: one-way gain relative to the peak [dB]
};

struct AntennaConfig {
  PatternCut azimuth;
  PatternCut elevation{PatternKind::kGaussian, 0.14, {}, {}};
  double peak_gain = 31623.0;  ///< one-way power gain of the (sum) beam, linear
  bool monopulse = true;
  double squint_fraction = 0.5;  ///< monopulse squint d / beamwidth (0.5: beams cross at -3 dB)
  /// Beam positions of one frame (scan), azimuth of each beam's boresight in the antenna frame.
  std::vector<double> beam_azimuth_rad{0.0};
  double beam_elevation_rad = 0.0;
};

/// Directivity from beamwidths: D = 4 pi / (theta_az theta_el) (Kraus's approximation for a
/// pencil beam, Balanis, Antenna Theory, 3rd ed. 2005, sec. 2.7), times an aperture efficiency.
[[nodiscard]] double gain_from_beamwidths(double az_rad, double el_rad, double efficiency) noexcept;
/// Gain of an aperture: G = 4 pi eta A / lambda^2 (Skolnik, Introduction to Radar Systems, 3rd
/// ed. 2001, sec. 9.2).
[[nodiscard]] double gain_from_aperture(double area_m2, double efficiency,
                                        double wavelength_m) noexcept;

[[nodiscard]] bool parse_pattern_kind(std::string_view name, PatternKind& out) noexcept;
[[nodiscard]] const char* pattern_name(PatternKind kind) noexcept;

class Antenna {
 public:
  /// Setup: validates (throws std::invalid_argument naming the field), builds the monopulse
  /// inversion tables.
  explicit Antenna(const AntennaConfig& config);

  [[nodiscard]] const AntennaConfig& config() const noexcept { return config_; }
  [[nodiscard]] std::size_t beams() const noexcept { return config_.beam_azimuth_rad.size(); }

  /// One-way voltage of a single (component) beam at an angle off its boresight.
  [[nodiscard]] double component_az(double off_rad) const noexcept;
  [[nodiscard]] double component_el(double off_rad) const noexcept;
  /// Sum-channel voltage (1 on boresight) and normalised differences at (az, el) off boresight.
  [[nodiscard]] double sum_az(double off_rad) const noexcept;
  [[nodiscard]] double delta_az(double off_rad) const noexcept;
  [[nodiscard]] double sum_el(double off_rad) const noexcept;
  [[nodiscard]] double delta_el(double off_rad) const noexcept;
  /// Sum and normalised difference voltages together (each component beam evaluated once).
  void channels_az(double off_rad, double& sum, double& delta) const noexcept;
  void channels_el(double off_rad, double& sum, double& delta) const noexcept;
  /// Offset from boresight whose Delta/Sigma is `ratio`, on the principal cut (monotone
  /// inversion over the main lobe; clamps beyond it). Real-time safe.
  [[nodiscard]] double offset_from_ratio_az(double ratio) const noexcept;
  [[nodiscard]] double offset_from_ratio_el(double ratio) const noexcept;
  /// Monopulse slope d(Delta/Sigma)/d(theta/theta3) on boresight.
  [[nodiscard]] double monopulse_slope_az() const noexcept { return slope_az_; }
  [[nodiscard]] double monopulse_slope_el() const noexcept { return slope_el_; }
  /// One-way 3-dB width of the sum beam (wider than a component beam when squinted).
  [[nodiscard]] double sum_beamwidth_az_rad() const noexcept { return sum_bw_az_; }
  [[nodiscard]] double sum_beamwidth_el_rad() const noexcept { return sum_bw_el_; }
  /// Largest offset at which the sum beam's one-way gain is still above `floor_db` (< 0).
  [[nodiscard]] double extent_az_rad(double floor_db) const noexcept;

 private:
  struct Cut {
    PatternCut pattern;
    double aperture_wavelengths = 0.0;  ///< L / lambda (uniform, cosine)
    double squint_rad = 0.0;
    double norm = 1.0;  ///< 1 / (2 E(d)), or 1 without monopulse
    bool monopulse = false;
    // Delta/Sigma inversion over [-t_max, t_max].
    std::vector<double> ratio, angle;
    double component(double off) const noexcept;
    double sum(double off) const noexcept;
    double delta(double off) const noexcept;
    double invert(double r) const noexcept;
    void channels(double off, double& s, double& d) const noexcept;
  };
  AntennaConfig config_;
  Cut az_, el_;
  double slope_az_ = 0, slope_el_ = 0, sum_bw_az_ = 0, sum_bw_el_ = 0;
  static void build(Cut& cut, const PatternCut& p, bool monopulse, double squint_fraction,
                    const char* plane);
};

}  // namespace radar_emu::radar
