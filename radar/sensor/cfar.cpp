#include "radar/sensor/cfar.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

#include "radar/sensor/detection_theory.hpp"
#include "radar/sensor/noise.hpp"

namespace radar_emu::radar {

namespace {
void require(bool ok, const char* field, const std::string& rule) {
  if (!ok)
    throw std::invalid_argument(std::string("cfar: ") + field + " " + rule);
}
}  // namespace

Cfar2d::Cfar2d(const CfarConfig& c, std::size_t range_bins, std::size_t velocity_bins)
    : config_(c), n_range_(range_bins), n_vel_(velocity_bins) {
  require(c.range_training >= 0 && c.range_guard >= 0 && c.velocity_training >= 0 &&
              c.velocity_guard >= 0,
          "training/guard cells", "must be >= 0");
  require(c.pfa > 0.0 && c.pfa < 1.0, "pfa", "must be in (0, 1)");
  require(c.os_rank > 0.0 && c.os_rank <= 1.0, "os_rank", "must be in (0, 1]");
  const auto wr = static_cast<std::size_t>(2 * (c.range_training + c.range_guard) + 1);
  const auto wv = static_cast<std::size_t>(2 * (c.velocity_training + c.velocity_guard) + 1);
  require(wr <= n_range_, "range_training + range_guard",
          "window (" + std::to_string(wr) + " cells) is longer than the " +
              std::to_string(n_range_) + " range bins");
  require(wv <= n_vel_, "velocity_training + velocity_guard",
          "window (" + std::to_string(wv) + " cells) is longer than the " + std::to_string(n_vel_) +
              " velocity bins");
  const auto gr = static_cast<std::size_t>(2 * c.range_guard + 1);
  const auto gv = static_cast<std::size_t>(2 * c.velocity_guard + 1);
  n_full_ = wr * wv - gr * gv;
  require(n_full_ >= 1, "training cells", "must leave at least one cell");
  alpha_.assign(n_full_ + 1, 0.0);
  os_scale_.assign(n_full_ + 1, 1.0);
  os_k_.assign(n_full_ + 1, 1);
  for (std::size_t n = 1; n <= n_full_; ++n) {
    if (c.kind == CfarKind::kCellAveraging) {
      alpha_[n] = ca_cfar_alpha(n, c.pfa);
    } else {
      const auto k = std::clamp<std::size_t>(
          static_cast<std::size_t>(std::lround(c.os_rank * static_cast<double>(n))), 1, n);
      os_k_[n] = k;
      alpha_[n] = os_cfar_alpha(n, k, c.pfa);
      // E[x_(k)] of N unit exponentials = sum_{i=0}^{k-1} 1 / (N - i) (Renyi representation).
      double e = 0.0;
      for (std::size_t i = 0; i < k; ++i)
        e += 1.0 / static_cast<double>(n - i);
      os_scale_[n] = e;
    }
  }
  inv_n_.assign(n_full_ + 1, 0.0);
  for (std::size_t n = 1; n <= n_full_; ++n)
    inv_n_[n] = 1.0 / static_cast<double>(n);
  window_rows_.resize(wv);
  window_guard_.resize(wv);
  pfa_.assign(n_full_ + 1, 0.0);
  for (std::size_t n = 1; n <= n_full_; ++n) {
    pfa_[n] = c.kind == CfarKind::kCellAveraging ? c.pfa : os_cfar_pfa(n, os_k_[n], alpha_[n]);
    pfa_max_ = std::max(pfa_max_, pfa_[n]);
  }
  if (c.kind == CfarKind::kCellAveraging)
    prefix_.assign(n_vel_ * (n_range_ + 1), 0.0);
  scratch_.resize(n_full_);
  full_.assign(n_vel_, RowSpan{0, static_cast<std::uint32_t>(n_range_)});
  need_.resize(n_vel_);
}

long Cfar2d::range_margin() const noexcept {
  return std::max<long>(1, config_.range_training + config_.range_guard);
}
long Cfar2d::velocity_margin() const noexcept {
  return std::max<long>(1, config_.velocity_training + config_.velocity_guard);
}

std::size_t Cfar2d::training_at(long l) const noexcept {
  const long w = config_.range_training + config_.range_guard, grd = config_.range_guard;
  const long pad = config_.velocity_training + config_.velocity_guard, gv = config_.velocity_guard;
  const auto nr = static_cast<long>(n_range_);
  const long o0 = std::max<long>(0, l - w), o1 = std::min<long>(nr - 1, l + w);
  const long g0 = std::max<long>(0, l - grd), g1 = std::min<long>(nr - 1, l + grd);
  return static_cast<std::size_t>((o1 - o0 + 1) * (2 * pad + 1) - (g1 - g0 + 1) * (2 * gv + 1));
}

std::size_t Cfar2d::detect(std::span<const double> power, std::span<CfarHit> hits,
                           std::uint64_t& overflow) noexcept {
  return detect(power, full_, hits, overflow);
}

std::size_t Cfar2d::detect(std::span<const double> power, std::span<const RowSpan> cuts,
                           std::span<CfarHit> hits, std::uint64_t& overflow) noexcept {
  if (power.size() < n_range_ * n_vel_ || cuts.size() < n_vel_)
    return 0;
  const auto tr = static_cast<long>(config_.range_training);
  const auto grd = static_cast<long>(config_.range_guard);
  const auto tv = static_cast<long>(config_.velocity_training);
  const auto gv = static_cast<long>(config_.velocity_guard);
  const auto nr = static_cast<long>(n_range_);
  const auto nv = static_cast<long>(n_vel_);
  const long pad = tv + gv;
  auto wrap = [nv](long j) { return static_cast<std::size_t>(((j % nv) + nv) % nv); };
  std::size_t count = 0;
  auto emit = [&](long j, long l, double p, double noise) {
    if (count < hits.size())
      hits[count++] = {static_cast<std::uint32_t>(l), static_cast<std::uint32_t>(j), p, noise};
    else
      ++overflow;
  };

  if (config_.kind == CfarKind::kCellAveraging) {
    // Running sums of each row over the bins the windows of that row's and its velocity
    // neighbours' cells under test reach; a window's sum is then two look-ups a row.
    for (auto& n : need_)
      n = RowSpan{};
    for (long j = 0; j < nv; ++j) {
      const RowSpan c = cuts[static_cast<std::size_t>(j)];
      if (c.empty())
        continue;
      const auto lo = static_cast<std::uint32_t>(std::max<long>(0, c.begin - tr - grd));
      const auto hi = static_cast<std::uint32_t>(std::min<long>(nr, c.end + tr + grd));
      for (long dj = -pad; dj <= pad; ++dj) {
        RowSpan& n = need_[wrap(j + dj)];
        n = n.empty() ? RowSpan{lo, hi} : RowSpan{std::min(n.begin, lo), std::max(n.end, hi)};
      }
    }
    const std::size_t w = n_range_ + 1;
    for (std::size_t j = 0; j < n_vel_; ++j) {
      const RowSpan n = need_[j];
      if (n.empty())
        continue;
      const double* src = power.data() + j * n_range_;
      double* p = prefix_.data() + j * w;
      p[n.begin] = 0.0;
      for (std::uint32_t l = n.begin; l < n.end; ++l)
        p[l + 1] = p[l] + src[l];
    }
    // The window's rows of a cell-under-test row: their running sums, guard rows flagged (set
    // once a row: no modulo or division per cell).
    const auto n_rows = static_cast<std::size_t>(2 * pad + 1);
    for (long j = 0; j < nv; ++j) {
      const RowSpan c = cuts[static_cast<std::size_t>(j)];
      if (c.empty())
        continue;
      const double* row = power.data() + static_cast<std::size_t>(j) * n_range_;
      for (long dj = -pad; dj <= pad; ++dj) {
        const auto k = static_cast<std::size_t>(dj + pad);
        window_rows_[k] = prefix_.data() + wrap(j + dj) * w;
        window_guard_[k] = dj >= -gv && dj <= gv ? 1 : 0;
      }
      // Cells whose window lies inside the swath: the full window, no clipping (the same sums
      // as below, in the same order).
      const long in0 = std::max<long>(c.begin, tr + grd);
      const long in1 = std::min<long>(c.end, nr - tr - grd);
      const double alpha_full = alpha_[n_full_], inv_full = inv_n_[n_full_];
      auto full_window = [&](long l) {
        const long o0 = l - tr - grd, o1 = l + tr + grd, g0 = l - grd, g1 = l + grd;
        double sum = 0.0;
        for (std::size_t k = 0; k < n_rows; ++k) {
          const double* p = window_rows_[k];
          sum += p[o1 + 1] - p[o0];
          if (window_guard_[k] != 0)
            sum -= p[g1 + 1] - p[g0];
        }
        const double mean = sum * inv_full;
        if (row[l] > alpha_full * mean)
          emit(j, l, row[l], mean);
      };
      for (long l = c.begin; l < static_cast<long>(c.end); ++l) {
        if (l == in0 && in0 < in1) {
          for (; l < in1; ++l)
            full_window(l);
          if (l >= static_cast<long>(c.end))
            break;
        }
        const long o0 = std::max<long>(0, l - tr - grd), o1 = std::min<long>(nr - 1, l + tr + grd);
        const long g0 = std::max<long>(0, l - grd), g1 = std::min<long>(nr - 1, l + grd);
        // training_at(l), from the bounds at hand
        const auto n =
            static_cast<std::size_t>((o1 - o0 + 1) * (2 * pad + 1) - (g1 - g0 + 1) * (2 * gv + 1));
        if (n == 0)
          continue;
        double sum = 0.0;  // each row's sum over bins o0..o1 less its guard bins g0..g1
        for (std::size_t k = 0; k < n_rows; ++k) {
          const double* p = window_rows_[k];
          sum += p[o1 + 1] - p[o0];
          if (window_guard_[k] != 0)
            sum -= p[g1 + 1] - p[g0];
        }
        const double mean = sum * inv_n_[n];
        if (row[l] > alpha_[n] * mean)
          emit(j, l, row[l], mean);
      }
    }
    return count;
  }

  // Order statistic. The cell crosses when x_(k) < P / alpha, i.e. when at least k training
  // cells lie below P / alpha: count, and stop as soon as the answer is known (a noise cell is
  // settled after about N - k + 1 cells). The k-th smallest itself is selected only for
  // crossings (the noise estimate).
  for (long j = 0; j < nv; ++j) {
    const RowSpan c = cuts[static_cast<std::size_t>(j)];
    const double* row = power.data() + static_cast<std::size_t>(j) * n_range_;
    for (long l = c.begin; l < static_cast<long>(c.end); ++l) {
      const long l0 = std::max<long>(0, l - tr - grd), l1 = std::min<long>(nr - 1, l + tr + grd);
      const long g0 = std::max<long>(0, l - grd), g1 = std::min<long>(nr - 1, l + grd);
      const std::size_t n = training_at(l);
      if (n == 0)
        continue;
      const std::size_t k = os_k_[n];
      const double t = row[l] / alpha_[n];
      std::size_t below = 0, above = 0;
      bool decided = false, crosses = false;
      for (long dj = -pad; dj <= pad && !decided; ++dj) {
        const double* src = power.data() + wrap(j + dj) * n_range_;
        const bool guard_row = dj >= -gv && dj <= gv;
        for (long ll = l0; ll <= l1; ++ll) {
          if (guard_row && ll >= g0 && ll <= g1)
            continue;
          if (src[ll] < t) {
            if (++below >= k) {
              decided = crosses = true;
              break;
            }
          } else if (++above > n - k) {
            decided = true;
            break;
          }
        }
      }
      if (!crosses)
        continue;
      std::size_t m = 0;
      for (long dj = -pad; dj <= pad; ++dj) {
        const double* src = power.data() + wrap(j + dj) * n_range_;
        const bool guard_row = dj >= -gv && dj <= gv;
        for (long ll = l0; ll <= l1; ++ll)
          if (!(guard_row && ll >= g0 && ll <= g1))
            scratch_[m++] = src[ll];
      }
      std::nth_element(scratch_.begin(), scratch_.begin() + static_cast<long>(k - 1),
                       scratch_.begin() + static_cast<long>(m));
      emit(j, l, row[l], scratch_[k - 1] / os_scale_[n]);
    }
  }
  return count;
}

std::size_t Cfar2d::draw_false_alarms(NoiseRng& rng, std::span<const RowSpan> cuts,
                                      std::span<FalseAlarm> out, std::uint64_t& crossings,
                                      std::uint64_t& overflow) noexcept {
  if (cuts.size() < n_vel_ || !(pfa_max_ > 0.0))
    return 0;
  const auto tr = static_cast<long>(config_.range_training);
  const auto grd = static_cast<long>(config_.range_guard);
  const auto gv = static_cast<long>(config_.velocity_guard);
  const long pad = static_cast<long>(config_.velocity_training) + gv;
  const auto nr = static_cast<long>(n_range_);
  const auto nv = static_cast<long>(n_vel_);
  auto clean_in = [&](std::size_t j) -> std::uint64_t {
    const RowSpan c = cuts[j];
    return n_range_ - (c.empty() ? 0u : c.end - c.begin);  // spans lie inside the swath
  };
  auto unit_exp = [&rng] { return -std::log(rng.uniform()); };
  const double log_q = std::log1p(-pfa_max_);
  std::size_t written = 0;
  std::uint64_t pos = 0;       // index of the next candidate among the clean cells, raster order
  std::uint64_t row_base = 0;  // clean cells in the rows before `j`
  std::size_t j = 0;
  bool first = true;
  while (true) {
    // Geometric skip: the number of cells passed over before the next Bernoulli(pfa_max) success.
    const double skip = std::floor(std::log(rng.uniform()) / log_q);
    if (!(skip < 1e18))
      break;
    pos += static_cast<std::uint64_t>(skip) + (first ? 0u : 1u);
    first = false;
    while (j < n_vel_ && pos >= row_base + clean_in(j)) {
      row_base += clean_in(j);
      ++j;
    }
    if (j >= n_vel_)
      break;
    const RowSpan c = cuts[j];
    const std::uint64_t r = pos - row_base;
    const long l =
        c.empty() || r < c.begin ? static_cast<long>(r) : static_cast<long>(c.end + (r - c.begin));
    const std::size_t n = training_at(l);
    if (n == 0)
      continue;
    // Thinning: cells at the swath's ends have fewer training cells and their own Pfa.
    if (pfa_[n] < pfa_max_ && rng.uniform() * pfa_max_ >= pfa_[n])
      continue;
    ++crossings;
    // The training cells conditioned on the crossing (header), in window order, and the
    // neighbours that are among them.
    const double alpha = alpha_[n];
    double estimate = 0.0;
    if (config_.kind == CfarKind::kCellAveraging) {
      const double rate = 1.0 + alpha / static_cast<double>(n);
      for (std::size_t i = 0; i < n; ++i) {
        scratch_[i] = unit_exp() / rate;
        estimate += scratch_[i];
      }
      estimate /= static_cast<double>(n);
    } else {
      const std::size_t k = os_k_[n];
      double x = 0.0;
      for (std::size_t i = 0; i < n; ++i) {
        const auto left = static_cast<double>(n - i);  // N - i + 1 with i counted from 1
        x += unit_exp() / (i < k ? left + alpha : left);
        scratch_[i] = x;
      }
      estimate = scratch_[k - 1];
      for (std::size_t i = n - 1; i > 0; --i) {  // uniform order over the window (Fisher-Yates)
        const auto s = std::min<std::size_t>(
            i, static_cast<std::size_t>(rng.uniform() * static_cast<double>(i + 1)));
        std::swap(scratch_[i], scratch_[s]);
      }
    }
    const double threshold = alpha * estimate;
    const double power = threshold + unit_exp();
    // Neighbours [dj + 1][dl + 1]: -1 = not yet known.
    double nb[3][3] = {{-1, -1, -1}, {-1, -1, -1}, {-1, -1, -1}};
    {
      const long l0 = std::max<long>(0, l - tr - grd), l1 = std::min<long>(nr - 1, l + tr + grd);
      const long g0 = std::max<long>(0, l - grd), g1 = std::min<long>(nr - 1, l + grd);
      std::size_t i = 0;
      for (long dj = -pad; dj <= pad; ++dj) {
        const bool guard_row = dj >= -gv && dj <= gv;
        for (long ll = l0; ll <= l1; ++ll) {
          if (guard_row && ll >= g0 && ll <= g1)
            continue;
          if (dj >= -1 && dj <= 1 && ll >= l - 1 && ll <= l + 1)
            nb[dj + 1][ll - l + 1] = scratch_[i];
          ++i;
        }
      }
    }
    bool peak = true;
    for (long dj = -1; dj <= 1; ++dj) {
      // Rows that wrap onto the cell's own row (1 velocity bin) or onto each other (2) are the
      // same cells: compare each once.
      if (dj != 0 && (nv == 1 || (nv == 2 && dj == 1)))
        continue;
      for (long dl = -1; dl <= 1; ++dl) {
        if ((dj == 0 && dl == 0) || l + dl < 0 || l + dl >= nr)
          continue;
        double& v = nb[dj + 1][dl + 1];
        if (v < 0.0)
          v = unit_exp();  // a guard cell or a cell outside the window: fresh noise
        peak = peak && v < power;
      }
    }
    if (nv == 2)
      nb[2][1] = nb[0][1];
    if (!peak)
      continue;
    if (written >= out.size()) {
      ++overflow;
      continue;
    }
    FalseAlarm& fa = out[written++];
    fa.hit = {static_cast<std::uint32_t>(l), static_cast<std::uint32_t>(j), power,
              config_.kind == CfarKind::kCellAveraging ? estimate : estimate / os_scale_[n]};
    fa.range_minus = l > 0 ? nb[1][0] : 0.0;
    fa.range_plus = l + 1 < nr ? nb[1][2] : 0.0;
    fa.velocity_minus = nv > 1 ? nb[0][1] : 0.0;
    fa.velocity_plus = nv > 1 ? nb[2][1] : 0.0;
  }
  return written;
}

}  // namespace radar_emu::radar
