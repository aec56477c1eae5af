#include "radar/sensor/sensor.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

#include "radar/constants.hpp"

namespace radar_emu::radar {

namespace {

constexpr std::size_t kMaxTouchedCells = 1u << 18;

void require(bool ok, const char* field, const char* what) {
  if (!ok)
    throw std::invalid_argument(std::string("sensor config: ") + field + " " + what);
}

double wavelength(const SensorConfig& c) {
  return kSpeedOfLight_mps / c.carrier_hz;
}

}  // namespace

Sensor::Sensor(const SensorConfig& config) : config_(config) {
  const SensorConfig& c = config;
  require(c.carrier_hz > 0 && std::isfinite(c.carrier_hz), "carrier_hz", "must be > 0");
  require(c.bandwidth_hz > 0, "bandwidth_hz", "must be > 0");
  require(c.prf_hz > 0, "prf_hz", "must be > 0");
  require(c.pulses >= 1, "pulses", "must be >= 1");
  require(c.pulse_width_s > 0, "pulse_width_s", "must be > 0");
  require(c.tx_power_w > 0, "tx_power_w", "must be > 0");
  require(c.antenna_gain > 0, "antenna_gain", "must be > 0");
  require(c.noise_figure >= 1, "noise_figure", "must be >= 1 (linear)");
  require(c.system_losses >= 1, "system_losses", "must be >= 1 (linear)");
  require(c.azimuth_min_rad < c.azimuth_max_rad, "azimuth_min/max_rad", "must satisfy min < max");
  require(c.azimuth_cell_rad > 0, "azimuth_cell_rad", "must be > 0");
  require(c.max_range_m > 0, "max_range_m", "must be > 0");
  require(c.cfar_training_cells >= 1, "cfar_training_cells", "must be >= 1");
  require(c.cfar_guard_cells >= 0, "cfar_guard_cells", "must be >= 0");
  require(c.cfar_pfa > 0 && c.cfar_pfa < 1, "cfar_pfa", "must be in (0, 1)");
  n_range_ = static_cast<std::size_t>(std::ceil(c.max_range_m / range_cell_m()));
  n_doppler_ = static_cast<std::size_t>(c.pulses);
  n_az_ = static_cast<std::size_t>(
      std::ceil((c.azimuth_max_rad - c.azimuth_min_rad) / c.azimuth_cell_rad - 1e-9));
  const std::size_t cells = n_range_ * n_doppler_ * n_az_;
  require(cells <= (1u << 30), "grid", "has more than 2^30 cells");
  slot_of_cell_.assign(cells, 0);
  slots_.resize(std::min(cells, kMaxTouchedCells));
  candidates_.reserve(slots_.size());
  // CA-CFAR threshold factor alpha = N (Pfa^(-1/N) - 1) for N training cells (Richards,
  // Principles of Modern Radar, 2010, eq. 16.37), for every N that can occur at grid edges.
  cfar_alpha_.resize(2 * static_cast<std::size_t>(c.cfar_training_cells) + 1, 0.0);
  for (std::size_t n = 1; n < cfar_alpha_.size(); ++n) {
    const double nd = static_cast<double>(n);
    cfar_alpha_[n] = nd * (std::pow(c.cfar_pfa, -1.0 / nd) - 1.0);
  }
  // Radar equation, Skolnik, Introduction to Radar Systems, 3rd ed., eq. 2.1 form:
  // P_r = Pt G^2 lambda^2 sigma / ((4 pi)^3 R^4 L).
  const double lambda = wavelength(c);
  amplitude_scale_ = std::sqrt(c.tx_power_w * c.antenna_gain * c.antenna_gain * lambda * lambda /
                               (std::pow(4.0 * kPi, 3) * c.system_losses));
  snr_per_watt_ =
      static_cast<double>(c.pulses) * c.pulse_width_s * c.bandwidth_hz / noise_power_w();
}

double Sensor::range_cell_m() const noexcept {
  return kSpeedOfLight_mps / (2.0 * config_.bandwidth_hz);
}
double Sensor::unambiguous_velocity_mps() const noexcept {
  return wavelength(config_) * config_.prf_hz / 4.0;
}
double Sensor::doppler_cell_mps() const noexcept {
  return 2.0 * unambiguous_velocity_mps() / static_cast<double>(config_.pulses);
}
std::size_t Sensor::range_cells() const noexcept {
  return n_range_;
}
std::size_t Sensor::azimuth_cells() const noexcept {
  return n_az_;
}
std::size_t Sensor::doppler_cells() const noexcept {
  return n_doppler_;
}

std::uint32_t Sensor::range_cell_of(double range_m) const noexcept {
  const double cell = std::floor(range_m / range_cell_m());
  return cell <= 0.0 ? 0u : static_cast<std::uint32_t>(std::min(cell, 4.0e9));
}
std::uint32_t Sensor::doppler_cell_of(double v_mps) const noexcept {
  // A coherent interval of N pulses at the PRF resolves N Doppler cells of width dv centred on
  // multiples of dv (an FFT's bins), periodic in 2 v_ua: cell = round(v / dv) mod N, stored with
  // zero velocity at index N/2 so that indices increase with velocity from -v_ua.
  if (!std::isfinite(v_mps))
    return 0;
  const auto n = static_cast<std::int64_t>(n_doppler_);
  const double dv = doppler_cell_mps();
  const auto bin =
      static_cast<std::int64_t>(std::llround(std::fmod(v_mps / dv, static_cast<double>(n))));
  return static_cast<std::uint32_t>(((bin + n / 2) % n + n) % n);
}
std::uint32_t Sensor::azimuth_cell_of(double az_rad) const noexcept {
  const double cell = std::floor((az_rad - config_.azimuth_min_rad) / config_.azimuth_cell_rad);
  return cell <= 0.0 ? 0u : static_cast<std::uint32_t>(std::min(cell, 4.0e9));
}
double Sensor::noise_power_w() const noexcept {
  return kBoltzmann_jpk * kReferenceTemperature_k * config_.noise_figure * config_.bandwidth_hz;
}
double Sensor::received_power_w(double rcs_m2, double range_m) const noexcept {
  return amplitude_scale_ * amplitude_scale_ * rcs_m2 / std::pow(range_m, 4);
}

Sensor::Cell* Sensor::cell_for(std::uint32_t index, SensorStats& stats) noexcept {
  std::uint32_t& slot = slot_of_cell_[index];
  if (slot == 0) {
    if (used_slots_ == slots_.size()) {
      ++stats.cells_overflowed;
      return nullptr;
    }
    slots_[used_slots_] = Cell{};
    slots_[used_slots_].index = index;
    slot = static_cast<std::uint32_t>(++used_slots_);
  }
  return &slots_[slot - 1];
}

double Sensor::snr_of_index(std::uint32_t index) const noexcept {
  const std::uint32_t slot = slot_of_cell_[index];
  if (slot == 0)
    return 0.0;
  const Cell& c = slots_[slot - 1];
  return (std::norm(c.coherent) + c.incoherent_w) * snr_per_watt_;
}

std::size_t Sensor::process(std::span<const Contribution> contributions, std::span<Detection> out,
                            SensorStats& stats) noexcept {
  // Clear only what the previous frame touched.
  for (std::size_t i = 0; i < used_slots_; ++i)
    slot_of_cell_[slots_[i].index] = 0;
  used_slots_ = 0;
  const double dr = range_cell_m();
  const auto nr = static_cast<std::int64_t>(n_range_);
  for (const Contribution& c : contributions) {
    const double az_cells = (c.azimuth_rad - config_.azimuth_min_rad) / config_.azimuth_cell_rad;
    if (!(c.range_m >= 0.0 && c.range_m < config_.max_range_m) || !(az_cells >= 0.0) ||
        az_cells >= static_cast<double>(n_az_)) {
      ++stats.out_of_grid;
      continue;
    }
    const auto ia = static_cast<std::uint32_t>(az_cells);
    const std::uint32_t id = doppler_cell_of(c.radial_velocity_mps);
    const std::size_t line = (static_cast<std::size_t>(ia) * n_doppler_ + id) * n_range_;
    const double scale = amplitude_scale_ / (c.range_m * c.range_m);
    if (c.coherent) {
      const auto ir = static_cast<std::size_t>(c.range_m / dr);
      Cell* cell = cell_for(static_cast<std::uint32_t>(line + ir), stats);
      if (!cell)
        continue;
      const std::complex<double> a = c.amplitude * scale;
      const double p = std::norm(a);
      cell->coherent += a;
      cell->weight += p;
      cell->elevation_weight += p * c.elevation_rad;
    } else {
      // Diffuse power spread uniformly over the range cells its footprint covers.
      const double p = std::norm(c.amplitude) * scale * scale;
      const double r0 = c.range_m - 0.5 * c.range_spread_m, r1 = c.range_m + 0.5 * c.range_spread_m;
      const std::int64_t i0 =
          std::max<std::int64_t>(0, static_cast<std::int64_t>(std::floor(r0 / dr)));
      const std::int64_t i1 =
          std::min<std::int64_t>(nr - 1, static_cast<std::int64_t>(std::floor(r1 / dr)));
      for (std::int64_t i = i0; i <= i1; ++i) {
        const double lo = std::max(r0, static_cast<double>(i) * dr);
        const double hi = std::min(r1, static_cast<double>(i + 1) * dr);
        const double share =
            c.range_spread_m > 0.0 ? std::max(0.0, hi - lo) / c.range_spread_m : 1.0;
        if (share <= 0.0)
          continue;
        Cell* cell =
            cell_for(static_cast<std::uint32_t>(line + static_cast<std::size_t>(i)), stats);
        if (!cell)
          continue;
        cell->incoherent_w += p * share;
        cell->weight += p * share;
        cell->elevation_weight += p * share * c.elevation_rad;
      }
    }
  }
  stats.cells_touched += used_slots_;

  // CA-CFAR along range, then keep local maxima over the 3x3x3 neighbourhood.
  const double min_snr = std::pow(10.0, config_.min_snr_db / 10.0);
  const auto guard = static_cast<std::int64_t>(config_.cfar_guard_cells);
  const auto train = static_cast<std::int64_t>(config_.cfar_training_cells);
  candidates_.clear();
  for (std::size_t s = 0; s < used_slots_; ++s) {
    const Cell& cell = slots_[s];
    const double snr = (std::norm(cell.coherent) + cell.incoherent_w) * snr_per_watt_;
    if (snr < min_snr)
      continue;
    const std::uint32_t index = cell.index;
    const auto ir = static_cast<std::int64_t>(index % n_range_);
    const std::uint32_t line_start = index - static_cast<std::uint32_t>(ir);
    double sum = 0.0;
    std::size_t n = 0;
    for (std::int64_t k = guard + 1; k <= guard + train; ++k) {
      if (ir - k >= 0) {
        sum += snr_of_index(line_start + static_cast<std::uint32_t>(ir - k));
        ++n;
      }
      if (ir + k < nr) {
        sum += snr_of_index(line_start + static_cast<std::uint32_t>(ir + k));
        ++n;
      }
    }
    const double mean = n > 0 ? sum / static_cast<double>(n) : 0.0;
    const double alpha = n > 0 ? cfar_alpha_[n] : cfar_alpha_.back();
    if (!(snr + 1.0 > alpha * (mean + 1.0)))
      continue;
    ++stats.cfar_crossings;
    // Peak grouping: strictly greatest in its neighbourhood (ties broken by cell index).
    const auto ia = static_cast<std::int64_t>(index / (n_range_ * n_doppler_));
    const auto id = static_cast<std::int64_t>((index / n_range_) % n_doppler_);
    bool peak = true;
    for (std::int64_t da = -1; da <= 1 && peak; ++da) {
      const std::int64_t a = ia + da;
      if (a < 0 || a >= static_cast<std::int64_t>(n_az_))
        continue;
      for (std::int64_t dd = -1; dd <= 1 && peak; ++dd) {
        const auto nd = static_cast<std::int64_t>(n_doppler_);
        const std::int64_t d = ((id + dd) % nd + nd) % nd;  // Doppler is circular
        for (std::int64_t drr = -1; drr <= 1; ++drr) {
          const std::int64_t r = ir + drr;
          if (r < 0 || r >= nr || (da == 0 && dd == 0 && drr == 0))
            continue;
          const auto other = static_cast<std::uint32_t>(
              (static_cast<std::size_t>(a) * n_doppler_ + static_cast<std::size_t>(d)) * n_range_ +
              static_cast<std::size_t>(r));
          const double o = snr_of_index(other);
          if (o > snr || (o == snr && other < index)) {
            peak = false;
            break;
          }
        }
      }
    }
    if (peak)
      candidates_.push_back({snr, static_cast<std::uint32_t>(s)});
  }
  std::sort(candidates_.begin(), candidates_.end(), [&](const Candidate& a, const Candidate& b) {
    return a.snr != b.snr ? a.snr > b.snr : slots_[a.slot].index < slots_[b.slot].index;
  });
  const std::size_t n_out = std::min({candidates_.size(), out.size(), config_.max_detections});
  stats.truncated += candidates_.size() - n_out;
  for (std::size_t i = 0; i < n_out; ++i) {
    const Cell& cell = slots_[candidates_[i].slot];
    Detection& d = out[i];
    d.range_cell = cell.index % static_cast<std::uint32_t>(n_range_);
    d.doppler_cell = (cell.index / static_cast<std::uint32_t>(n_range_)) %
                     static_cast<std::uint32_t>(n_doppler_);
    d.azimuth_cell = cell.index / static_cast<std::uint32_t>(n_range_ * n_doppler_);
    d.range_m = (d.range_cell + 0.5) * dr;
    d.azimuth_rad = config_.azimuth_min_rad + (d.azimuth_cell + 0.5) * config_.azimuth_cell_rad;
    d.radial_velocity_mps =
        (static_cast<double>(d.doppler_cell) - static_cast<double>(n_doppler_ / 2)) *
        doppler_cell_mps();
    d.elevation_rad = cell.weight > 0.0 ? cell.elevation_weight / cell.weight : 0.0;
    d.snr = candidates_[i].snr;
    d.rcs_m2 = d.snr / snr_per_watt_ / received_power_w(1.0, d.range_m);
  }
  stats.detections += n_out;
  return n_out;
}

}  // namespace radar_emu::radar
