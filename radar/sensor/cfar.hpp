#pragma once
// Two-dimensional CFAR over a range-velocity power image: cell-averaging (by a summed-area table,
// O(1) a cell) and order-statistic (Rohling 1983). The training window is a rectangle of
// (2 (G_r + T_r) + 1) x (2 (G_v + T_v) + 1) cells around the cell under test minus the guard
// rectangle; it wraps in velocity (the Doppler axis is periodic) and is cut at the swath's ends,
// where the threshold factor is recomputed for the smaller number of training cells.
//
// A radar image is mostly receiver noise. The CFAR therefore works on two kinds of cells:
//  * cells under test given as spans per velocity row are evaluated on the power image, which
//    needs to hold values only where their windows reach (detect());
//  * every other cell is known to hold noise alone, in itself and in its whole window: its
//    crossings are drawn from their exact distribution without synthesising a cell
//    (draw_false_alarms()). A noise-only cell crosses with probability Pfa(N) (the design Pfa for
//    CA-CFAR's exact threshold, Richards 2014, eq. 6.135; os_cfar_pfa() for OS), so the crossings
//    among M such cells are Bernoulli trials, placed by geometric skips (Devroye, Non-Uniform
//    Random Variate Generation, 1986, sec. X.2). Given a crossing, the cell and its training cells
//    are drawn from their joint law conditioned on the crossing: with unit exponentials,
//    P(x > T) = exp(-T), so the conditioning tilts the training cells by exp(-alpha * estimate):
//      CA: estimate = mean of N cells, each cell becomes exponential of rate 1 + alpha / N;
//      OS: estimate = x_(k); by Renyi's representation x_(m) = sum_{i<=m} E_i / (N - i + 1) with
//          E_i unit exponentials, the tilt makes E_i (i <= k) exponential of rate
//          1 + alpha / (N - i + 1) and leaves the others (Renyi, Acta Math. Hung. 4, 1953);
//    and the cell under test is the threshold plus a unit exponential (memorylessness). The
//    8 neighbours (training cells where they are, fresh noise otherwise) decide whether the
//    crossing is a local maximum, as in the synthesised image. Each cell's law is exact; what the
//    draw leaves out is the dependence between two crossings that share training cells, a
//    correction of relative order Pfa to the number of pairs of crossings.

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

/// Range bins [begin, end) of one velocity row (empty when begin >= end).
struct RowSpan {
  std::uint32_t begin = 0;
  std::uint32_t end = 0;
  [[nodiscard]] bool empty() const noexcept { return begin >= end; }
};

/// A false alarm drawn for a noise-only cell that is a local maximum, with the powers of its
/// range and velocity neighbours (0 beyond the swath) for peak interpolation.
struct FalseAlarm {
  CfarHit hit;
  double range_minus = 0.0, range_plus = 0.0;
  double velocity_minus = 0.0, velocity_plus = 0.0;
};

class NoiseRng;

class Cfar2d {
 public:
  /// Setup: validates against the image size (throws std::invalid_argument naming the field).
  Cfar2d(const CfarConfig& config, std::size_t range_bins, std::size_t velocity_bins);

  /// power: [velocity][range]. Writes the cells whose power exceeds the threshold into `hits` in
  /// raster order and returns how many; crossings that do not fit are added to `overflow`.
  /// Real-time safe.
  std::size_t detect(std::span<const double> power, std::span<CfarHit> hits,
                     std::uint64_t& overflow) noexcept;
  /// The same for the cells under test in `cuts` (one span per velocity row) only. `power` must
  /// hold values wherever those cells' windows reach (window_margins() around them, velocity
  /// wrapping); it is not read elsewhere. Real-time safe.
  std::size_t detect(std::span<const double> power, std::span<const RowSpan> cuts,
                     std::span<CfarHit> hits, std::uint64_t& overflow) noexcept;

  /// Crossings of the noise-only cells: every cell outside `cuts` (one span per velocity row),
  /// whose own value, window and 8 neighbours hold unit-mean receiver noise alone. Draws them
  /// from `rng` (see the header) and writes those that are local maxima into `out` (raster
  /// order); returns how many. `crossings` is added every crossing, `overflow` the local maxima
  /// that did not fit. Cost: O(rows + crossings x window). Real-time safe.
  std::size_t draw_false_alarms(NoiseRng& rng, std::span<const RowSpan> cuts,
                                std::span<FalseAlarm> out, std::uint64_t& crossings,
                                std::uint64_t& overflow) noexcept;

  /// Reach of the window around a cell under test: range bins and velocity bins on each side,
  /// at least 1 (the neighbours of the local-maximum test).
  [[nodiscard]] long range_margin() const noexcept;
  [[nodiscard]] long velocity_margin() const noexcept;
  /// Probability that a noise-only cell with n training cells crosses (n <= training_cells()).
  [[nodiscard]] double pfa_of(std::size_t n) const noexcept { return pfa_[n]; }

  [[nodiscard]] std::size_t training_cells() const noexcept { return n_full_; }
  /// Threshold factor on the noise estimate for the full window (CA: on the mean; OS: on x_(k)).
  [[nodiscard]] double alpha() const noexcept { return alpha_[n_full_]; }
  [[nodiscard]] const CfarConfig& config() const noexcept { return config_; }

 private:
  CfarConfig config_;
  std::size_t n_range_, n_vel_, n_full_ = 0;
  std::vector<double> alpha_;               ///< by number of training cells
  std::vector<double> inv_n_;               ///< 1 / N, by number of training cells
  std::vector<const double*> window_rows_;  ///< CA detect(): running sums of the window's rows
  std::vector<std::uint8_t> window_guard_;  ///< ... and whether the row crosses the guard
  std::vector<double> os_scale_;            ///< OS: E[x_(k)] for unit exponentials, by N
  std::vector<std::size_t> os_k_;           ///< OS: rank by N
  std::vector<double> pfa_;                 ///< exact Pfa of the threshold used, by N
  double pfa_max_ = 0.0;                    ///< largest of pfa_ (geometric skips, then thinning)
  std::vector<double> prefix_;              ///< CA: per-row running sums, n_range_ + 1 a row
  std::vector<double> scratch_;             ///< training cells of one cell under test
  std::vector<RowSpan> full_;               ///< every cell of every row
  std::vector<RowSpan> need_;               ///< per row: where detect() reads power
  /// Number of training cells of a cell under test at range bin l (velocity wraps).
  [[nodiscard]] std::size_t training_at(long l) const noexcept;
};

}  // namespace radar_emu::radar
