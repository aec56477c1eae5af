#include "radar/antenna/antenna.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

#include "radar/constants.hpp"

namespace radar_emu::radar {

namespace {

void require(bool ok, const std::string& field, const std::string& rule) {
  if (!ok)
    throw std::invalid_argument("antenna: " + field + " " + rule);
}

double aperture_voltage(PatternKind kind, double u) {
  if (kind == PatternKind::kUniform)
    return std::abs(u) < 1e-12 ? 1.0 : std::sin(kPi * u) / (kPi * u);
  // cosine illumination: cos(pi u) / (1 - 4 u^2), removable singularity pi/4 at u = 1/2
  const double d = 1.0 - 4.0 * u * u;
  if (std::abs(d) < 1e-9)
    return kPi / 4.0;
  return std::cos(kPi * u) / d;
}

// The u at which the power pattern is half its peak, by bisection on the main lobe.
double half_power_u(PatternKind kind) {
  double lo = 0.0, hi = kind == PatternKind::kUniform ? 0.99 : 1.49;
  for (int i = 0; i < 200; ++i) {
    const double mid = 0.5 * (lo + hi);
    const double v = aperture_voltage(kind, mid);
    (v * v > 0.5 ? lo : hi) = mid;
  }
  return 0.5 * (lo + hi);
}

}  // namespace

double gain_from_beamwidths(double az_rad, double el_rad, double efficiency) noexcept {
  return efficiency * 4.0 * kPi / (az_rad * el_rad);
}
double gain_from_aperture(double area_m2, double efficiency, double wavelength_m) noexcept {
  return 4.0 * kPi * efficiency * area_m2 / (wavelength_m * wavelength_m);
}

bool parse_pattern_kind(std::string_view name, PatternKind& out) noexcept {
  if (name == "uniform")
    out = PatternKind::kUniform;
  else if (name == "cosine")
    out = PatternKind::kCosine;
  else if (name == "gaussian")
    out = PatternKind::kGaussian;
  else if (name == "table")
    out = PatternKind::kTable;
  else
    return false;
  return true;
}
const char* pattern_name(PatternKind kind) noexcept {
  switch (kind) {
    case PatternKind::kUniform:
      return "uniform";
    case PatternKind::kCosine:
      return "cosine";
    case PatternKind::kGaussian:
      return "gaussian";
    case PatternKind::kTable:
      return "table";
  }
  return "?";
}

double Antenna::Cut::component(double off) const noexcept {
  switch (pattern.kind) {
    case PatternKind::kUniform:
    case PatternKind::kCosine:
      return aperture_voltage(pattern.kind, aperture_wavelengths * std::sin(off));
    case PatternKind::kGaussian: {
      const double x = off / pattern.beamwidth_rad;
      return std::exp(-2.0 * std::log(2.0) * x * x);
    }
    case PatternKind::kTable: {
      const auto& a = pattern.table_angle_rad;
      const auto& g = pattern.table_gain_db;
      double db;
      if (off <= a.front()) {
        db = g.front();
      } else if (off >= a.back()) {
        db = g.back();
      } else {
        const auto it = std::upper_bound(a.begin(), a.end(), off);
        const auto i = static_cast<std::size_t>(it - a.begin());
        const double t = (off - a[i - 1]) / (a[i] - a[i - 1]);
        db = g[i - 1] + t * (g[i] - g[i - 1]);
      }
      return std::pow(10.0, db / 20.0);
    }
  }
  return 0.0;
}
double Antenna::Cut::sum(double off) const noexcept {
  if (!monopulse)
    return component(off);
  return (component(off - squint_rad) + component(off + squint_rad)) * norm;
}
double Antenna::Cut::delta(double off) const noexcept {
  if (!monopulse)
    return 0.0;
  return (component(off - squint_rad) - component(off + squint_rad)) * norm;
}
void Antenna::Cut::channels(double off, double& s, double& d) const noexcept {
  if (!monopulse) {
    s = component(off);
    d = 0.0;
    return;
  }
  const double a = component(off - squint_rad), b = component(off + squint_rad);
  s = (a + b) * norm;
  d = (a - b) * norm;
}

double Antenna::Cut::invert(double r) const noexcept {
  if (ratio.size() < 2)
    return 0.0;
  if (r <= ratio.front())
    return angle.front();
  if (r >= ratio.back())
    return angle.back();
  const auto it = std::upper_bound(ratio.begin(), ratio.end(), r);
  const auto i = static_cast<std::size_t>(it - ratio.begin());
  const double t = (r - ratio[i - 1]) / (ratio[i] - ratio[i - 1]);
  return angle[i - 1] + t * (angle[i] - angle[i - 1]);
}

void Antenna::build(Cut& cut, const PatternCut& p, bool monopulse, double squint_fraction,
                    const char* plane) {
  const std::string field = std::string(plane);
  cut.pattern = p;
  if (p.kind == PatternKind::kTable) {
    require(p.table_angle_rad.size() >= 2 && p.table_angle_rad.size() == p.table_gain_db.size(),
            field + " table", "needs at least two (angle, gain) rows of equal length");
    for (std::size_t i = 0; i < p.table_angle_rad.size(); ++i) {
      require(std::isfinite(p.table_angle_rad[i]) && std::isfinite(p.table_gain_db[i]),
              field + " table row " + std::to_string(i + 1), "is not a finite number");
      require(i == 0 || p.table_angle_rad[i] > p.table_angle_rad[i - 1],
              field + " table row " + std::to_string(i + 1), "angles must increase");
    }
    // The table's own 3-dB width, for squint and reporting.
    double lo = 0.0, hi = 0.0;
    for (double a = 0.0; a < p.table_angle_rad.back(); a += 1e-5) {
      if (20.0 * std::log10(std::max(1e-300, cut.component(a))) < -3.0103) {
        hi = a;
        break;
      }
    }
    for (double a = 0.0; a > p.table_angle_rad.front(); a -= 1e-5) {
      if (20.0 * std::log10(std::max(1e-300, cut.component(a))) < -3.0103) {
        lo = a;
        break;
      }
    }
    require(hi > 0.0 && lo < 0.0, field + " table", "has no -3 dB point on both sides of 0");
    cut.pattern.beamwidth_rad = hi - lo;
  } else {
    require(std::isfinite(p.beamwidth_rad) && p.beamwidth_rad > 0.0 && p.beamwidth_rad < kPi / 2,
            field + " beamwidth", "must be in (0, 90) deg");
    if (p.kind != PatternKind::kGaussian)
      cut.aperture_wavelengths = half_power_u(p.kind) / std::sin(0.5 * p.beamwidth_rad);
  }
  cut.monopulse = monopulse;
  const double bw = cut.pattern.beamwidth_rad;
  if (monopulse) {
    require(squint_fraction > 0.0 && squint_fraction < 1.0, "squint_fraction",
            "must be in (0, 1) of the beamwidth");
    cut.squint_rad = squint_fraction * bw;
    cut.norm = 1.0 / (2.0 * cut.component(cut.squint_rad));
    // Delta/Sigma on a fine grid; keep the monotone segment through 0.
    const int n = 4001;
    const double t_max = 1.5 * bw;
    std::vector<double> t(n), r(n);
    for (int i = 0; i < n; ++i) {
      t[static_cast<std::size_t>(i)] = -t_max + 2.0 * t_max * i / (n - 1);
      const double s = cut.sum(t[static_cast<std::size_t>(i)]);
      r[static_cast<std::size_t>(i)] =
          std::abs(s) > 1e-12 ? cut.delta(t[static_cast<std::size_t>(i)]) / s : 0.0;
    }
    const std::size_t mid = n / 2;
    std::size_t hi = mid, lo = mid;
    while (hi + 1 < static_cast<std::size_t>(n) && r[hi + 1] > r[hi] && cut.sum(t[hi + 1]) > 0.0)
      ++hi;
    while (lo > 0 && r[lo - 1] < r[lo] && cut.sum(t[lo - 1]) > 0.0)
      --lo;
    cut.ratio.assign(r.begin() + static_cast<long>(lo), r.begin() + static_cast<long>(hi) + 1);
    cut.angle.assign(t.begin() + static_cast<long>(lo), t.begin() + static_cast<long>(hi) + 1);
  }
}

Antenna::Antenna(const AntennaConfig& config) : config_(config) {
  require(std::isfinite(config.peak_gain) && config.peak_gain >= 1.0, "peak_gain",
          "must be >= 1 (0 dBi)");
  require(!config.beam_azimuth_rad.empty(), "beam positions", "must list at least one beam");
  for (double a : config.beam_azimuth_rad)
    require(std::isfinite(a) && std::abs(a) < kPi / 2, "beam azimuth", "must be within +-90 deg");
  require(std::isfinite(config.beam_elevation_rad) && std::abs(config.beam_elevation_rad) < kPi / 2,
          "beam elevation", "must be within +-90 deg");
  build(az_, config.azimuth, config.monopulse, config.squint_fraction, "azimuth pattern");
  build(el_, config.elevation, config.monopulse, config.squint_fraction, "elevation pattern");
  auto slope = [](const Cut& c) {
    if (!c.monopulse)
      return 0.0;
    const double e = 1e-4 * c.pattern.beamwidth_rad;
    const double r1 = c.delta(e) / c.sum(e), r0 = c.delta(-e) / c.sum(-e);
    return (r1 - r0) / (2.0 * e) * c.pattern.beamwidth_rad;
  };
  slope_az_ = slope(az_);
  slope_el_ = slope(el_);
  auto width = [](const Cut& c) {
    double lo = 0.0, hi = 3.0 * c.pattern.beamwidth_rad;
    for (int i = 0; i < 200; ++i) {
      const double mid = 0.5 * (lo + hi);
      const double s = c.sum(mid);
      (s * s > 0.5 ? lo : hi) = mid;
    }
    return lo + hi;  // twice the half-power offset (symmetric patterns)
  };
  sum_bw_az_ = width(az_);
  sum_bw_el_ = width(el_);
}

double Antenna::component_az(double off) const noexcept {
  return az_.component(off);
}
double Antenna::component_el(double off) const noexcept {
  return el_.component(off);
}
double Antenna::sum_az(double off) const noexcept {
  return az_.sum(off);
}
double Antenna::delta_az(double off) const noexcept {
  return az_.delta(off);
}
double Antenna::sum_el(double off) const noexcept {
  return el_.sum(off);
}
double Antenna::delta_el(double off) const noexcept {
  return el_.delta(off);
}
void Antenna::channels_az(double off, double& sum, double& delta) const noexcept {
  az_.channels(off, sum, delta);
}
void Antenna::channels_el(double off, double& sum, double& delta) const noexcept {
  el_.channels(off, sum, delta);
}
double Antenna::offset_from_ratio_az(double ratio) const noexcept {
  return az_.invert(ratio);
}
double Antenna::offset_from_ratio_el(double ratio) const noexcept {
  return el_.invert(ratio);
}
double Antenna::extent_az_rad(double floor_db) const noexcept {
  const double floor = std::pow(10.0, floor_db / 20.0);
  const double step = az_.pattern.beamwidth_rad / 50.0;
  double last = 0.0;
  for (double a = 0.0; a < 0.5; a += step) {
    if (std::abs(az_.sum(a)) >= floor || std::abs(az_.sum(-a)) >= floor)
      last = a;
  }
  return last + step;
}

}  // namespace radar_emu::radar
