#pragma once
// Tapers for range and Doppler processing. Symmetric (filter-design) form over N samples, peak 1.
// Sidelobe levels and widths: F. J. Harris, "On the use of windows for harmonic analysis with the
// discrete Fourier transform", Proc. IEEE 66(1), 51-83, 1978, Table 1; the Taylor taper:
// T. T. Taylor, IRE Trans. AP-3(1), 16-28, 1955, in the sampled form of Carrara, Goodman and
// Majewski, Spotlight Synthetic Aperture Radar, Artech House 1995, App. D.

#include <optional>
#include <span>
#include <string_view>

namespace radar_emu::radar {

enum class WindowKind { kRectangular, kHann, kHamming, kBlackman, kTaylor };

struct WindowSpec {
  WindowKind kind = WindowKind::kHann;
  double taylor_sidelobe_db = 35.0;  ///< design peak sidelobe below the mainlobe (positive dB)
  int taylor_nbar = 5;               ///< constant-level sidelobes next to the mainlobe
};

/// Fills `w` (any length >= 1) with the taper. Real-time safe.
void fill_window(const WindowSpec& spec, std::span<double> w) noexcept;

/// Peak sidelobe a radar engineer expects of the taper [dB, negative]: Harris 1978 Table 1
/// (rectangular -13.26, Hann -31.5, Hamming -42.7, Blackman -58.1, computed from the definitions
/// at large N and rounded by Harris to -13, -32, -43, -58) or the Taylor design level.
[[nodiscard]] double documented_peak_sidelobe_db(const WindowSpec& spec) noexcept;

/// Smallest nbar for which a Taylor taper of this level is monotone (no "ears"):
/// nbar >= 2 A^2 + 0.5 with A = acosh(10^(SLL/20)) / pi (Carrara et al. 1995, App. D).
[[nodiscard]] int taylor_min_nbar(double sidelobe_db) noexcept;

/// Coherent gain sum(w)/N and equivalent noise bandwidth N sum(w^2)/sum(w)^2 [bins].
struct WindowMetrics {
  double coherent_gain = 1.0;
  double enbw_bins = 1.0;
};
[[nodiscard]] WindowMetrics window_metrics(std::span<const double> w) noexcept;

[[nodiscard]] std::optional<WindowKind> parse_window_kind(std::string_view name) noexcept;
[[nodiscard]] const char* window_name(WindowKind kind) noexcept;

}  // namespace radar_emu::radar
