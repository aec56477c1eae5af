#pragma once
// `radar-emu sar`: stripmap SAR over a scene. A TOML case (examples/sar_seed.toml documents every
// key) gives the platform track and speed, the waveform (carrier, bandwidth, pulse, PRF), the
// antenna (beamwidths, incidence, side), the processing (gates, synthetic beamwidth, taper) and
// the scene (flat ground of a terrain-catalogue material with its sigma0 and speckle, trihedrals
// and other canonical targets, moving ones with a velocity). Raw echoes are synthesised per pulse:
// the targets (single and multiple bounces, the target-ground double bounce, moving targets where
// the scene puts them at the pulse's time) from the SBR frame tracer (radar/em/sbr.hpp), the
// terrain from fixed ground cells (sigma0 of the clutter models at the cell's incidence times its
// speckle sample, shadowed cells left out); then range compression and backprojection
// (radar/products/sar.hpp). Outputs in the output directory: raw.tif (complex raw data, GCPs),
// image.tif (focused complex image, georeferenced), image.png (detected, dB, scale bar),
// sar.json (parameters, timings, point-target measurements) and, when a static trihedral is in
// the image, irf.png (its range and azimuth impulse-response cuts).

#include <string>

#include "common/work_control.hpp"

namespace radar_emu::tools {

struct SarToolOptions {
  std::string config;               ///< the TOML case
  std::string out_dir = "sar_out";  ///< created if missing
  bool no_raw = false;              ///< skip raw.tif
  bool quiet = false;
  /// Progress in pulses, the estimate of memory and time before the raw data, and the stop flag
  /// polled between pulse blocks.
  common::WorkControl control;
};

/// Whether this build can write GeoTIFF (GDAL found at configure time).
[[nodiscard]] bool sar_geotiff_available() noexcept;

/// Runs the case; throws std::invalid_argument / std::runtime_error with a one-line reason.
/// Returns 0, or 128 + the signal when control.stop ended the raw data early: then the pulses
/// done are focused (the rest are zero) and every output is written, sar.json saying
/// "incomplete": true, "pulses_done" and "stop_signal" ("incomplete": false otherwise).
int run_sar_tool(const SarToolOptions& options);

}  // namespace radar_emu::tools
