#include "radar/sensor/cfar.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

#include "radar/sensor/detection_theory.hpp"

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
  const std::size_t pad = static_cast<std::size_t>(c.velocity_training + c.velocity_guard);
  if (c.kind == CfarKind::kCellAveraging)
    sat_.assign((n_vel_ + 2 * pad + 1) * (n_range_ + 1), 0.0);
  else
    scratch_.resize(n_full_);
}

std::size_t Cfar2d::detect(std::span<const double> power, std::span<CfarHit> hits,
                           std::uint64_t& overflow) noexcept {
  if (power.size() < n_range_ * n_vel_)
    return 0;
  const auto tr = static_cast<long>(config_.range_training);
  const auto grd = static_cast<long>(config_.range_guard);
  const auto tv = static_cast<long>(config_.velocity_training);
  const auto gv = static_cast<long>(config_.velocity_guard);
  const auto nr = static_cast<long>(n_range_);
  const auto nv = static_cast<long>(n_vel_);
  const long pad = tv + gv;
  std::size_t count = 0;
  auto emit = [&](long j, long l, double p, double noise) {
    if (count < hits.size())
      hits[count++] = {static_cast<std::uint32_t>(l), static_cast<std::uint32_t>(j), p, noise};
    else
      ++overflow;
  };

  if (config_.kind == CfarKind::kCellAveraging) {
    // S[i][l] = sum of padded rows < i and range bins < l; padded row i is image row
    // (i - pad) mod M.
    const std::size_t w = n_range_ + 1;
    const long rows = nv + 2 * pad;
    for (long i = 0; i < rows; ++i) {
      const long j = ((i - pad) % nv + nv) % nv;
      const double* src = power.data() + static_cast<std::size_t>(j) * n_range_;
      double* s_prev = sat_.data() + static_cast<std::size_t>(i) * w;
      double* s = s_prev + w;
      double run = 0.0;
      s[0] = 0.0;
      for (std::size_t l = 0; l < n_range_; ++l) {
        run += src[l];
        s[l + 1] = s_prev[l + 1] + run;
      }
    }
    auto box = [&](long i0, long i1, long l0, long l1) {  // inclusive padded rows, range bins
      const double* a = sat_.data() + static_cast<std::size_t>(i0) * w;
      const double* b = sat_.data() + static_cast<std::size_t>(i1 + 1) * w;
      return b[l1 + 1] - b[l0] - a[l1 + 1] + a[l0];
    };
    for (long j = 0; j < nv; ++j) {
      const long i = j + pad;  // padded row of the cell under test
      const double* row = power.data() + static_cast<std::size_t>(j) * n_range_;
      for (long l = 0; l < nr; ++l) {
        const long o0 = std::max<long>(0, l - tr - grd), o1 = std::min<long>(nr - 1, l + tr + grd);
        const long g0 = std::max<long>(0, l - grd), g1 = std::min<long>(nr - 1, l + grd);
        const double outer = box(i - pad, i + pad, o0, o1);
        const double inner = box(i - gv, i + gv, g0, g1);
        const auto n =
            static_cast<std::size_t>((o1 - o0 + 1) * (2 * pad + 1) - (g1 - g0 + 1) * (2 * gv + 1));
        if (n == 0)
          continue;
        const double mean = (outer - inner) / static_cast<double>(n);
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
    const double* row = power.data() + static_cast<std::size_t>(j) * n_range_;
    for (long l = 0; l < nr; ++l) {
      const long l0 = std::max<long>(0, l - tr - grd), l1 = std::min<long>(nr - 1, l + tr + grd);
      const long g0 = std::max<long>(0, l - grd), g1 = std::min<long>(nr - 1, l + grd);
      const auto n =
          static_cast<std::size_t>((l1 - l0 + 1) * (2 * pad + 1) - (g1 - g0 + 1) * (2 * gv + 1));
      if (n == 0)
        continue;
      const std::size_t k = os_k_[n];
      const double t = row[l] / alpha_[n];
      std::size_t below = 0, above = 0;
      bool decided = false, crosses = false;
      for (long dj = -pad; dj <= pad && !decided; ++dj) {
        const long jj = ((j + dj) % nv + nv) % nv;
        const double* src = power.data() + static_cast<std::size_t>(jj) * n_range_;
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
        const long jj = ((j + dj) % nv + nv) % nv;
        const double* src = power.data() + static_cast<std::size_t>(jj) * n_range_;
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

}  // namespace radar_emu::radar
