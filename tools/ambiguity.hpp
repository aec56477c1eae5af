#pragma once
// `radar-emu ambiguity`: the ambiguity function of a configured waveform (a scenario's, the
// default's, or overridden on the command line): a heat map, the zero-Doppler and zero-delay cuts
// against the linear-FM closed form, and the figures theory predicts (resolution, range-Doppler
// coupling) measured on the computed surface.

#include <filesystem>
#include <optional>
#include <string>

namespace radar_emu::tools {

struct AmbiguityToolOptions {
  std::filesystem::path scenario;  ///< empty: the embedded default scenario's waveform
  std::optional<double> bandwidth_hz, pulse_width_s, prf_hz;
  std::optional<int> pulses;
  bool train = false;         ///< the coherent train of `pulses` (closed form) over +-2 PRI
  double delay_span = 1.0;    ///< single pulse: +- this many pulse widths
  double doppler_span = 8.0;  ///< single pulse: +- this many 1/T; train: this many PRFs
  int points = 201;           ///< grid points on each axis (odd: includes the origin)
  int oversample = 8;         ///< samples per 1/B in the numerical integral
  double dynamic_range_db = 40.0;
  std::filesystem::path out_dir = "ambiguity";
  bool quiet = false;
};

/// Writes ambiguity.csv (delay_s, doppler_hz, magnitude, magnitude_db), cuts.csv, summary.json,
/// ambiguity.png and cuts.png into out_dir. Throws std::invalid_argument for bad options.
int run_ambiguity_tool(const AmbiguityToolOptions& options);

}  // namespace radar_emu::tools
