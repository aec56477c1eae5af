#pragma once
// First radar sensor: bins SBR contributions into range x Doppler x azimuth cells (coherent sum
// for targets, power sum for diffuse clutter), applies the radar equation and noise, and detects
// with a cell-averaging CFAR along range plus peak grouping. Issue 5 replaces it with waveform
// synthesis and matched filtering; this stage keeps the same inputs and outputs.

#include <complex>
#include <cstddef>
#include <cstdint>
#include <span>
#include <vector>

#include "radar/em/sbr.hpp"

namespace radar_emu::radar {

struct SensorConfig {
  double carrier_hz = 94e9;
  double bandwidth_hz = 50e6;  ///< range cell c / (2 B)
  double prf_hz = 100e3;       ///< pulse repetition frequency
  int pulses = 64;             ///< pulses per coherent interval (Doppler cells)
  double pulse_width_s = 2e-6;
  double tx_power_w = 10.0;
  double antenna_gain = 3162.0;      ///< two-way gain G (linear) used as G^2
  double noise_figure = 5.0;         ///< linear
  double system_losses = 2.0;        ///< linear, >= 1
  double azimuth_min_rad = -0.1745;  ///< azimuth cells span the field of view
  double azimuth_max_rad = 0.1745;
  double azimuth_cell_rad = 0.01745;
  double max_range_m = 6000.0;
  int cfar_training_cells = 16;  ///< per side, along range
  int cfar_guard_cells = 4;      ///< per side
  double cfar_pfa = 1e-6;        ///< design false-alarm probability
  double min_snr_db = 13.0;
  std::size_t max_detections = 64;
};

/// One detection in SI units.
struct Detection {
  double range_m = 0.0;
  double azimuth_rad = 0.0;
  double elevation_rad = 0.0;        ///< power-weighted mean elevation of the cell's returns
  double radial_velocity_mps = 0.0;  ///< Doppler cell centre, folded: (cell - N/2) * dv
  double snr = 0.0;                  ///< linear
  double rcs_m2 = 0.0;               ///< from the radar equation at the cell's range
  std::uint32_t range_cell = 0;
  std::uint32_t doppler_cell = 0;
  std::uint32_t azimuth_cell = 0;
};

struct SensorStats {
  std::uint64_t cells_touched = 0;
  std::uint64_t cfar_crossings = 0;
  std::uint64_t detections = 0;
  std::uint64_t truncated = 0;         ///< detections beyond max_detections or the output span
  std::uint64_t out_of_grid = 0;       ///< contributions beyond max range or azimuth
  std::uint64_t cells_overflowed = 0;  ///< power lost: more touched cells than reserved
};

class Sensor {
 public:
  /// Setup: validates (throws std::invalid_argument naming the field) and allocates the grid.
  explicit Sensor(const SensorConfig& config);

  /// Processes one frame's contributions. Writes detections sorted by SNR (descending) into
  /// `out`; returns how many. `stats` is added to, not reset. Real-time safe: no allocation, no
  /// exceptions.
  [[nodiscard]] std::size_t process(std::span<const Contribution> contributions,
                                    std::span<Detection> out, SensorStats& stats) noexcept;

  [[nodiscard]] const SensorConfig& config() const noexcept { return config_; }
  [[nodiscard]] double range_cell_m() const noexcept;
  [[nodiscard]] double doppler_cell_mps() const noexcept;
  [[nodiscard]] double unambiguous_velocity_mps() const noexcept;  ///< v_ua = lambda PRF / 4
  [[nodiscard]] std::size_t range_cells() const noexcept;
  [[nodiscard]] std::size_t azimuth_cells() const noexcept;
  [[nodiscard]] std::size_t doppler_cells() const noexcept;
  /// Cell indices of a point (tests and the emulator's ground truth use the same binning).
  [[nodiscard]] std::uint32_t range_cell_of(double range_m) const noexcept;
  [[nodiscard]] std::uint32_t doppler_cell_of(double radial_velocity_mps) const noexcept;
  [[nodiscard]] std::uint32_t azimuth_cell_of(double azimuth_rad) const noexcept;
  /// Thermal noise power k T0 F B [W].
  [[nodiscard]] double noise_power_w() const noexcept;
  /// Received power of a point target of RCS sigma at range R, radar equation [W].
  [[nodiscard]] double received_power_w(double rcs_m2, double range_m) const noexcept;

 private:
  SensorConfig config_;
  // Grid storage, allocated once (see sensor.cpp).
  struct Cell {
    std::complex<double> coherent{0.0, 0.0};  ///< sum of received complex amplitudes [sqrt(W)]
    double incoherent_w = 0.0;                ///< diffuse power [W]
    double elevation_weight = 0.0;            ///< sum of power x elevation
    double weight = 0.0;                      ///< sum of power
    std::uint32_t index = 0;                  ///< flat cell index
  };
  std::vector<std::uint32_t> slot_of_cell_;  ///< 0 = untouched, else slot + 1
  std::vector<Cell> slots_;
  std::size_t used_slots_ = 0;
  struct Candidate {
    double snr;
    std::uint32_t slot;
  };
  std::vector<Candidate> candidates_;
  std::vector<double> cfar_alpha_;  ///< threshold factor by number of training cells
  std::size_t n_range_ = 0, n_doppler_ = 0, n_az_ = 0;
  double amplitude_scale_ = 0.0;  ///< sqrt(Pt G^2 lambda^2 / ((4 pi)^3 L)) [sqrt(W) m]
  double snr_per_watt_ = 0.0;     ///< processing gain / noise power [1/W]
  Cell* cell_for(std::uint32_t index, SensorStats& stats) noexcept;
  [[nodiscard]] double snr_of_index(std::uint32_t index) const noexcept;
};

}  // namespace radar_emu::radar
