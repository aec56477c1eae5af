#pragma once
// Two-dimensional CFAR over a range-velocity power image: cell-averaging (by a summed-area table,
// O(1) a cell) and order-statistic (Rohling 1983). The training window is a rectangle of
// (2 (G_r + T_r) + 1) x (2 (G_v + T_v) + 1) cells around the cell under test minus the guard
// rectangle; it wraps in velocity (the Doppler axis is periodic) and is cut at the swath's ends,
// where the threshold factor is recomputed for the smaller number of training cells.

#include <cstddef>
#include <cstdint>
#include <span>
#include <vector>

namespace radar_emu::radar {

enum class CfarKind { kCellAveraging, kOrderStatistic };

struct CfarConfig {
  CfarKind kind = CfarKind::kCellAveraging;
  int range_training = 8;  ///< per side
  int range_guard = 2;
  int velocity_training = 4;
  int velocity_guard = 1;
  double pfa = 1e-6;      ///< design false-alarm probability per cell
  double os_rank = 0.75;  ///< OS: k = round(os_rank N), Rohling's usual 3/4
};

struct CfarHit {
  std::uint32_t range_bin = 0;
  std::uint32_t velocity_bin = 0;
  double power = 0.0;  ///< cell under test
  double noise = 0.0;  ///< unbiased estimate of the mean noise power from the training cells
};

class Cfar2d {
 public:
  /// Setup: validates against the image size (throws std::invalid_argument naming the field).
  Cfar2d(const CfarConfig& config, std::size_t range_bins, std::size_t velocity_bins);

  /// power: [velocity][range]. Writes the cells whose power exceeds the threshold into `hits` in
  /// raster order and returns how many; crossings that do not fit are added to `overflow`.
  /// Real-time safe.
  std::size_t detect(std::span<const double> power, std::span<CfarHit> hits,
                     std::uint64_t& overflow) noexcept;

  [[nodiscard]] std::size_t training_cells() const noexcept { return n_full_; }
  /// Threshold factor on the noise estimate for the full window (CA: on the mean; OS: on x_(k)).
  [[nodiscard]] double alpha() const noexcept { return alpha_[n_full_]; }
  [[nodiscard]] const CfarConfig& config() const noexcept { return config_; }

 private:
  CfarConfig config_;
  std::size_t n_range_, n_vel_, n_full_ = 0;
  std::vector<double> alpha_;      ///< by number of training cells
  std::vector<double> os_scale_;   ///< OS: E[x_(k)] for unit exponentials, by N
  std::vector<std::size_t> os_k_;  ///< OS: rank by N
  std::vector<double> sat_;        ///< summed-area table over the velocity-padded image
  std::vector<double> scratch_;    ///< OS: training cells of one cell under test
};

}  // namespace radar_emu::radar
