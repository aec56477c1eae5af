#include "radar/sensor/sensor.hpp"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <array>
#include <atomic>
#include <cmath>
#include <cstring>
#include <limits>
#include <stdexcept>
#include <string>

#include "radar/constants.hpp"
#include "radar/sensor/noise.hpp"

namespace radar_emu::radar {

namespace {

void require(bool ok, const char* field, const std::string& rule) {
  if (!ok)
    throw std::invalid_argument(std::string("sensor: ") + field + " " + rule);
}

// Log-parabolic (Gaussian) interpolation of a peak from three powers: offset of the vertex in
// bins, clamped to +-0.5.
double vertex(double pm, double p0, double pp) noexcept {
  if (!(pm > 0.0 && p0 > 0.0 && pp > 0.0))
    return 0.0;
  const double a = std::log(pm), b = std::log(p0), c = std::log(pp);
  const double den = a - 2.0 * b + c;
  if (!(den < 0.0))
    return 0.0;
  return std::clamp(0.5 * (a - c) / den, -0.5, 0.5);
}

constexpr std::uint64_t kChannelSum = 0, kChannelDeltaAz = 1, kChannelDeltaEl = 2,
                        kChannelSpeckle = 3, kChannelFalseAlarm = 4;
// Drawn for a captured frame's files only (Sensor::complete_image, Sensor::synthesise_raw): the
// image's cells the sensor did not synthesise, the speckle of diffuse returns in the raw samples,
// and the raw samples' receiver noise (one stream per channel from kChannelRawNoise on).
constexpr std::uint64_t kChannelFileNoise = 5, kChannelRawSpeckle = 6, kChannelRawNoise = 7;
// The raw samples of a diffuse return: points across its range extent, one a half bin, at most.
constexpr int kRawPointsPerDiffuse = 4;

// Spans of `in` widened by mr range bins and mv velocity rows (wrapping), one bounding span a
// row, clipped to nr bins.
void dilate(std::span<const RowSpan> in, std::span<RowSpan> out, long mr, long mv,
            long nr) noexcept {
  const auto nv = static_cast<long>(in.size());
  for (auto& o : out)
    o = RowSpan{};
  if (2 * mv + 1 >= nv) {  // every row reaches every other: one span for all
    RowSpan all{};
    for (const RowSpan& r : in)
      if (!r.empty())
        all = all.empty() ? r : RowSpan{std::min(all.begin, r.begin), std::max(all.end, r.end)};
    if (!all.empty()) {
      all = {static_cast<std::uint32_t>(std::max<long>(0, all.begin - mr)),
             static_cast<std::uint32_t>(std::min<long>(nr, all.end + mr))};
    }
    for (auto& o : out)
      o = all;
    return;
  }
  for (long j = 0; j < nv; ++j) {
    const RowSpan r = in[static_cast<std::size_t>(j)];
    if (r.empty())
      continue;
    const auto lo = static_cast<std::uint32_t>(std::max<long>(0, r.begin - mr));
    const auto hi = static_cast<std::uint32_t>(std::min<long>(nr, r.end + mr));
    for (long dj = -mv; dj <= mv; ++dj) {
      RowSpan& o = out[static_cast<std::size_t>(((j + dj) % nv + nv) % nv)];
      o = o.empty() ? RowSpan{lo, hi} : RowSpan{std::min(o.begin, lo), std::max(o.end, hi)};
    }
  }
}

// Widens row span `r` to cover bins [lo, hi).
void cover(RowSpan& r, long lo, long hi) noexcept {
  const auto a = static_cast<std::uint32_t>(lo), b = static_cast<std::uint32_t>(hi);
  r = r.empty() ? RowSpan{a, b} : RowSpan{std::min(r.begin, a), std::max(r.end, b)};
}

bool finite(const Contribution& c) noexcept {
  return std::isfinite(c.amplitude.real()) && std::isfinite(c.amplitude.imag()) &&
         std::isfinite(c.range_m) && std::isfinite(c.range_spread_m) &&
         std::isfinite(c.radial_velocity_mps) && std::isfinite(c.azimuth_rad) &&
         std::isfinite(c.elevation_rad);
}

}  // namespace

struct Sensor::Workspace {
  Workspace(const CfarConfig& cfar_config, const RangeDopplerProcessor& p, std::size_t max_hits)
      : image(p.image_cells()),
        clutter((p.range_bins() + 1) * p.velocity_bins()),
        direct(p.range_bins() * p.velocity_bins()),
        power(p.image_cells()),
        cfar(cfar_config, p.range_bins(), p.velocity_bins()),
        hits(max_hits),
        alarms(max_hits),
        dirty(p.velocity_bins()),
        cuts(p.velocity_bins()),
        synth(p.velocity_bins()) {}
  // image and clutter are zero outside `dirty` between frames: a beam clears what it wrote.
  std::vector<std::complex<double>> image;  ///< coherent signal, then the Sigma channel
  /// Mean clutter power as a difference array along range, transposed: [range bin][velocity
  /// row], N_r + 1 bins (a diffuse return's taps are neighbouring rows: contiguous here).
  std::vector<double> clutter;
  /// Mean clutter power of the pieces one bin long (most diffuse returns: a terrain cell's
  /// return covers two bins partly), added to their bin directly (one row an end instead of
  /// two); same layout, N_r bins. The cell's clutter power is the sum of both.
  std::vector<double> direct;
  std::vector<double> power;  ///< valid on `synth` only
  Cfar2d cfar;
  std::vector<CfarHit> hits;
  std::vector<FalseAlarm> alarms;
  std::vector<RowSpan> dirty;  ///< per velocity row: bins this frame's returns reach
  std::vector<RowSpan> cuts;   ///< cells under test evaluated on the image
  std::vector<RowSpan> synth;  ///< cells synthesised (the cuts' windows)
  /// The range bins [begin, end) of `clutter` this frame's returns wrote (its entries are zero
  /// elsewhere): the running sum reads those only. None: begin >= end.
  std::uint32_t clutter_begin = std::numeric_limits<std::uint32_t>::max(), clutter_end = 0;
  std::uint64_t crossings = 0, overflowed = 0, synthesised = 0;
  std::uint64_t below_floor = 0;  ///< (return, this beam) pairs under return_floor_db
};

Sensor::Sensor(const SensorConfig& config) : config_(config), antenna_(config.antenna) {
  const SensorConfig& c = config_;
  require(std::isfinite(c.tx_power_w) && c.tx_power_w > 0, "tx_power_w", "must be > 0");
  require(std::isfinite(c.noise_figure) && c.noise_figure >= 1, "noise_figure",
          "must be >= 1 (linear)");
  require(std::isfinite(c.system_losses) && c.system_losses >= 1, "system_losses",
          "must be >= 1 (linear)");
  require(std::isfinite(c.min_snr_db), "min_snr_db", "must be finite");
  require(c.beam_floor_db < 0 && c.beam_floor_db > -200, "beam_floor_db", "must be in (-200, 0)");
  require(!std::isnan(c.return_floor_db) && c.return_floor_db <= -30.0, "return_floor_db",
          "must be <= -30 dB (below the noise, where it changes no detection); -400 or below: off");
  require(c.max_hits_per_beam >= 1 && c.max_hits_per_beam <= (1u << 22), "max_hits_per_beam",
          "must be in [1, 2^22]");
  require(std::isfinite(c.max_range_m) && c.max_range_m > 0, "max_range_m", "must be > 0");
  require(c.max_contributions >= 1 && c.max_contributions <= (1u << 26), "max_contributions",
          "must be in [1, 2^26]");
  require(std::isfinite(c.merge_step_bins) && c.merge_step_bins >= 0.0 && c.merge_step_bins <= 0.5,
          "merge_step_bins", "must be in [0, 0.5] (0: off)");
  require(std::isfinite(c.merge_step_beamwidths) && c.merge_step_beamwidths > 0.0 &&
              c.merge_step_beamwidths <= 0.5,
          "merge_step_beamwidths", "must be in (0, 0.5]");
  require(c.processing.kernel_half_width_bins >= 0 &&
              c.processing.kernel_half_width_bins <= (Footprint::kMaxBins - 1) / 2,
          "kernel_half_width_bins", "must be in [0, 32] for the sensor");
  processor_ = std::make_unique<RangeDopplerProcessor>(c.processing);
  // One workspace per beam (the beams of a scan are accumulated together); worker w takes the
  // w-th of W contiguous blocks of beams.
  // As many workers as threads TBB may run (the result does not depend on it: every beam adds
  // the items in the same order and draws from its own random streams).
  n_workers_ = std::clamp<std::size_t>(
      static_cast<std::size_t>(tbb::this_task_arena::max_concurrency()), 1, antenna_.beams());
  worker_beams_.resize(n_workers_ + 1);
  footprint_cells_.resize(n_workers_ * kFootprintCells);
  beam_work_.resize(antenna_.beams() + 1);
  gain_floor_ = std::pow(10.0, c.beam_floor_db / 10.0);
  return_floor_ = c.thermal_noise && c.return_floor_db > kReturnFloorOff_db
                      ? std::pow(10.0, c.return_floor_db / 10.0)
                      : 0.0;
  for (std::size_t i = 0; i < antenna_.beams(); ++i)
    workspaces_.push_back(std::make_unique<Workspace>(c.cfar, *processor_, c.max_hits_per_beam));
  items_.resize(c.max_contributions);
  item_state_.resize(c.max_contributions);
  item_beams_.resize(c.max_contributions);
  item_bound_.resize(c.max_contributions);
  // A sum pattern's largest value, sampled over [-extent, extent] at `step` and on boresight,
  // and raised by 1e-4 for what the sampling and the gains' recurrence can miss.
  auto largest = [](auto pattern, double extent, double step) {
    double m = std::abs(pattern(0.0));
    for (double a = -extent; a <= extent; a += step)
      m = std::max(m, std::abs(pattern(a)));
    return (1.0 + 1e-4) * m;
  };
  // Azimuth (1 on boresight for the patterns here; a squinted pair's sum can peak off it): every
  // 1/2000 beamwidth over its extent. Elevation: over the whole half space (every elevation a
  // return can arrive from) at the same step, at most 2^18 samples. Both bound the gains of a
  // return before its angles are looked at; a coherent return under the floor at them is under
  // it in every beam (floor_norm_).
  max_sum_az_ =
      largest([&](double a) { return antenna_.sum_az(a); }, antenna_.extent_az_rad(c.beam_floor_db),
              c.antenna.azimuth.beamwidth_rad / 2000.0);
  const double max_sum_el =
      largest([&](double e) { return antenna_.sum_el(e); }, 0.5 * kPi,
              std::max(c.antenna.elevation.beamwidth_rad / 2000.0, kPi / (1 << 18)));
  const double peak = max_sum_az_ * max_sum_el;  // the one-way sum gain at most
  floor_norm_ = return_floor_ / (processor_->processing_gain() * (peak * peak) * (peak * peak));
  item_bucket_.resize(c.max_contributions);
  if (c.merge_step_bins > 0.0) {
    // Each part's region: twice its returns plus 2 (merge_returns()).
    merge_table_.assign(2 * c.max_contributions + 2 * kMergeParts, 0);
    merge_used_.resize(c.max_contributions);
    merge_order_.resize(c.max_contributions);
    merge_part_.resize(c.max_contributions);
    merge_keys_.resize(c.max_contributions);
    merge_hash_.resize(c.max_contributions);
    merge_hashed_.resize(c.max_contributions);
    merge_sums_.resize(c.max_contributions);
    merge_amplitude_.resize(c.max_contributions);
    // merge_key()'s cells a unit: per bin, and per radian of azimuth and elevation.
    merge_per_bin_ = 1.0 / c.merge_step_bins;
    merge_per_rad_az_ = 1.0 / (c.merge_step_beamwidths * antenna_.sum_beamwidth_az_rad());
    merge_per_rad_el_ = 1.0 / (c.merge_step_beamwidths * antenna_.sum_beamwidth_el_rad());
  }
  by_range_.resize(c.max_contributions);
  live_items_.resize(c.max_contributions);
  range_start_.resize(processor_->range_bins() + 2);
  range_energy_ = processor_->range_energy();
  per_beam_capacity_ = c.max_hits_per_beam;
  candidates_.resize(antenna_.beams() * per_beam_capacity_);
  beam_first_.resize(antenna_.beams());
  beam_count_.resize(antenna_.beams());
  for (std::size_t b = 0; b < antenna_.beams(); ++b)
    beam_first_[b] = b * per_beam_capacity_;
  order_.reserve(candidates_.size());
  kept_power_.resize(c.max_detections);
  capture_dropped_.resize(antenna_.beams());
  // Radar equation per fast-time sample (Richards 2014, eq. 2.84):
  // SNR = Pt G^2 lambda^2 sigma / ((4 pi)^3 R^4 L k T0 F fs); amplitude_scale_^2 is its value
  // for sigma = 1 m^2 at R = 1 m on boresight.
  const double lambda = wavelength_m(c.processing.waveform);
  const double g = c.antenna.peak_gain;
  amplitude_scale_ = std::sqrt(c.tx_power_w * g * g * lambda * lambda /
                               (std::pow(4.0 * kPi, 3) * c.system_losses) / noise_power_w());
  // A beam considers returns where its two-way gain is above the floor.
  az_extent_rad_ = antenna_.extent_az_rad(0.5 * c.beam_floor_db);
  beams_ascending_ =
      std::is_sorted(c.antenna.beam_azimuth_rad.begin(), c.antenna.beam_azimuth_rad.end());
  // Gaussian azimuth pattern, beams evenly spaced to within rounding (16 ulp of the largest
  // azimuth): the sum channel's gains across a return's beams by a recurrence (process_worker).
  const std::vector<double>& az = c.antenna.beam_azimuth_rad;
  if (c.antenna.azimuth.kind == PatternKind::kGaussian && beams_ascending_ && az.size() >= 2 &&
      az.back() > az.front()) {
    const double step = (az.back() - az.front()) / static_cast<double>(az.size() - 1);
    const double tol = 16.0 * std::numeric_limits<double>::epsilon() *
                       std::max(std::abs(az.front()), std::abs(az.back()));
    bool even = true;
    for (std::size_t b = 0; b < az.size(); ++b)
      even = even && std::abs(az[b] - (az.front() + static_cast<double>(b) * step)) <= tol;
    if (even) {
      const double bw = c.antenna.azimuth.beamwidth_rad;
      az_rec_.on = true;
      az_rec_.c = 2.0 * std::log(2.0) / (bw * bw);
      az_rec_.squint = c.antenna.monopulse ? c.antenna.squint_fraction * bw : 0.0;
      az_rec_.step = step;
      az_rec_.norm =
          c.antenna.monopulse ? 1.0 / (2.0 * antenna_.component_az(az_rec_.squint)) : 1.0;
      az_rec_.q = std::exp(-2.0 * az_rec_.c * step * step);
      az_rec_.k = std::exp(4.0 * az_rec_.c * step * az_rec_.squint);
    }
  }
}

Sensor::~Sensor() = default;

std::size_t Sensor::cfar_training_cells() const noexcept {
  return workspaces_.empty() ? 0 : workspaces_.front()->cfar.training_cells();
}

double Sensor::range_cell_m() const noexcept {
  return range_bin_m(config_.processing.waveform);
}
double Sensor::doppler_cell_mps() const noexcept {
  return velocity_bin_mps(config_.processing.waveform);
}
double Sensor::unambiguous_velocity_mps() const noexcept {
  return radar::unambiguous_velocity_mps(config_.processing.waveform);
}
double Sensor::unambiguous_range_m() const noexcept {
  return radar::unambiguous_range_m(config_.processing.waveform);
}
double Sensor::noise_power_w() const noexcept {
  return kBoltzmann_jpk * kReferenceTemperature_k * config_.noise_figure *
         fast_sample_rate_hz(config_.processing.waveform);
}
double Sensor::received_power_w(double rcs_m2, double range_m) const noexcept {
  return amplitude_scale_ * amplitude_scale_ * noise_power_w() * rcs_m2 / std::pow(range_m, 4);
}
double Sensor::expected_snr(double rcs_m2, double range_m) const noexcept {
  return received_power_w(rcs_m2, range_m) / noise_power_w() * processor_->processing_gain();
}
double Sensor::two_way_gain(double az_off_rad, double el_off_rad) const noexcept {
  const double v = antenna_.sum_az(az_off_rad) * antenna_.sum_el(el_off_rad);
  return v * v * v * v;
}

bool Sensor::gains_of(const Item& item, std::size_t beam, Gains& g) const noexcept {
  return gains_at(item.azimuth_rad, item.sum_el, item.delta_el, beam, g);
}

bool Sensor::gains_at(double azimuth_rad, double sum_el, double delta_el, std::size_t beam,
                      Gains& g) const noexcept {
  const double off_az = azimuth_rad - config_.antenna.beam_azimuth_rad[beam];
  if (std::abs(off_az) > az_extent_rad_)
    return false;
  double s_az = 0.0, d_az = 0.0;
  antenna_.channels_az(off_az, s_az, d_az);
  const double tx = s_az * sum_el;  // transmit on the sum beam, receive on each channel
  const double two_way = tx * tx;
  if (!(two_way * two_way >= gain_floor_))
    return false;
  g.sum = two_way;
  g.daz = tx * d_az * sum_el;
  g.del = tx * s_az * delta_el;
  return true;
}

double Sensor::range_share(const Item& item, long l) const noexcept {
  if (item.half_bins <= 0.0)
    return std::lround(item.pos.range_bin) == l ? 1.0 : 0.0;
  const double lo = item.pos.range_bin - item.half_bins, hi = item.pos.range_bin + item.half_bins;
  const auto ld = static_cast<double>(l);
  return std::max(0.0, std::min(hi, ld + 0.5) - std::max(lo, ld - 0.5)) / (hi - lo);
}

double Sensor::velocity_weight(const Item& item, long j) const noexcept {
  const std::optional<long> d =
      processor_->velocity_offset(static_cast<std::size_t>(j), item.pos.velocity_bin);
  if (!d)
    return 0.0;
  return processor_->velocity_power(static_cast<double>(std::lround(item.pos.velocity_bin) + *d) -
                                    item.pos.velocity_bin);
}

namespace {

// A diffuse return's range footprint for the difference array of clutter power: at most three
// pieces (the partly covered bins at each end, then the bins between, in that order), each
// [a, c] clipped to the swath; a piece's value is density * share (ends) or density (between),
// density = power / extent. One piece (`single`) when the footprint lies in one bin: the whole
// power on it.
struct DiffusePieces {
  long a[3] = {0, 0, 0}, c[3] = {-1, -1, -1};
  double share[2] = {0.0, 0.0};
  double extent = 1.0;
  bool single = false;
  long span_begin = 0, span_end = 0;  ///< bins the pieces cover, [begin, end)
};

DiffusePieces make_pieces(double range_bin, double half_bins, long nrl) noexcept {
  DiffusePieces d;
  const double lo = range_bin - half_bins, hi = range_bin + half_bins;
  const long l0 = std::lround(lo), l1 = std::lround(hi);
  auto clip = [&](int k, long a, long c) {
    d.a[k] = std::max<long>(a, 0);
    d.c[k] = std::min<long>(c, nrl - 1);
    if (d.a[k] > d.c[k])
      return;
    d.span_begin = d.span_begin < d.span_end ? std::min(d.span_begin, d.a[k]) : d.a[k];
    d.span_end = std::max(d.span_end, d.c[k] + 1);
  };
  if (half_bins <= 0.0 || l0 == l1) {
    d.single = true;
    clip(0, l0, l0);
    return d;
  }
  d.extent = hi - lo;
  d.share[0] = static_cast<double>(l0) + 0.5 - lo;
  d.share[1] = hi - (static_cast<double>(l1) - 0.5);
  clip(0, l0, l0);
  clip(1, l1, l1);
  clip(2, l0 + 1, l1 - 1);
  return d;
}

}  // namespace

void Sensor::split_beams() noexcept {
  // beam_work_ holds the frame's returns' work as a difference array over the beams: its running
  // sum is each beam's, plus each beam's own detection work. The workers' blocks cut the
  // cumulative work at equal shares (contiguous, so a return's beams stay together). Any split
  // gives the same result: each beam adds its returns in input order and draws its own streams.
  const std::size_t n_beams = antenna_.beams();
  double run = 0.0, total = 0.0;
  for (std::size_t b = 0; b < n_beams; ++b) {
    run += beam_work_[b];
    beam_work_[b] = std::max(run, 0.0) + kBeamWork;
    total += beam_work_[b];
  }
  worker_beams_[0] = 0;
  double done = 0.0;
  std::size_t b = 0;
  for (std::size_t w = 1; w < n_workers_; ++w) {
    const double share = total * static_cast<double>(w) / static_cast<double>(n_workers_);
    // Take beams while the block's end is nearer the share with the next beam than without it.
    while (b < n_beams && done + 0.5 * beam_work_[b] <= share)
      done += beam_work_[b++];
    worker_beams_[w] = b;
  }
  worker_beams_[n_workers_] = n_beams;
}

Sensor::BeamSpan Sensor::beam_span(const Item& item) const noexcept {
  const std::size_t n_beams = antenna_.beams();
  if (!beams_ascending_)
    return {0, static_cast<std::uint32_t>(n_beams)};
  const std::vector<double>& az = config_.antenna.beam_azimuth_rad;
  return {
      static_cast<std::uint32_t>(
          std::lower_bound(az.begin(), az.end(), item.azimuth_rad - az_extent_rad_) - az.begin()),
      static_cast<std::uint32_t>(
          std::upper_bound(az.begin(), az.end(), item.azimuth_rad + az_extent_rad_) - az.begin())};
}

void Sensor::process_worker(std::size_t w) noexcept {
  constexpr long kPrefetchBins = 4;
  const RangeDopplerProcessor& proc = *processor_;
  const std::size_t nr = proc.range_bins();
  const auto nrl = static_cast<long>(nr), nvl = static_cast<long>(proc.velocity_bins());
  const auto [dj0, dj1] = proc.velocity_support(proc.config().kernel_half_width_bins);
  const auto nv = static_cast<std::size_t>(nvl);
  const double processing_gain = proc.processing_gain();
  // This worker's beams: a contiguous block (a return reaches a few neighbouring beams, so most
  // returns are prepared by one worker only), of about equal work (split_beams()).
  const std::size_t beam_begin = worker_beams_[w], beam_end = worker_beams_[w + 1];
  // Each return's response is prepared once and added to every beam of this worker that sees it
  // with that beam's two-way gain. Targets: exact response (coherent). Clutter: mean power a
  // cell, its range footprint by a difference array along range, its Doppler leakage through the
  // taper; the speckle is drawn per cell afterwards.
  Footprint fp;
  // The azimuth recurrence's start a return azimuth (below), memoised: NaN marks an empty entry.
  struct AzMemo {
    double azimuth_rad = std::numeric_limits<double>::quiet_NaN();
    double a = 0.0, b = 0.0, ra = 0.0, rb = 0.0;
  };
  constexpr int kAzMemoBits = 7;
  std::array<AzMemo, std::size_t{1} << kAzMemoBits> az_memo{};
  std::complex<double>* cells = footprint_cells_.data() + w * kFootprintCells;
  double taps[Footprint::kMaxBins];
  std::uint32_t tap_rows[Footprint::kMaxBins];
  // A diffuse return's pieces, tap by tap, at unit two-way gain (scaled by each beam's).
  double values[3][Footprint::kMaxBins];
  // The live items (usable, their span holding a beam: live_items_, in input order); those this
  // worker will read are fetched kItemAhead ahead (the others, skipped by their span and bound
  // alone, are not).
  constexpr std::size_t kItemAhead = 8;
  const std::uint32_t* live = live_items_.data();
  for (std::size_t q = 0; q < live_count_; ++q) {
    const std::size_t i = live[q];
    if (q + kItemAhead < live_count_) {
      const std::size_t a = live[q + kItemAhead];
      const BeamSpan ahead = item_beams_[a];
      if (ahead.first < beam_end && ahead.end > beam_begin && !(item_bound_[a] < return_floor_)) {
        __builtin_prefetch(&items_[a]);
        __builtin_prefetch(reinterpret_cast<const char*>(&items_[a]) + sizeof(Item) - 1);
      }
    }
    // The beams within the azimuth extent of the return (gains_of() tests it again), from the
    // return's span of the whole scan; items outside this worker's beams are not read.
    const BeamSpan span = item_beams_[i];
    const std::size_t b_lowest = span.first;  // the return's first beam in the whole scan
    const std::size_t b_first = std::max<std::size_t>(beam_begin, span.first),
                      b_end = std::min<std::size_t>(beam_end, span.end);
    if (b_first >= b_end)
      continue;
    if (item_bound_[i] < return_floor_) {  // under the floor in every beam: its item not read
      for (std::size_t b = b_first; b < b_end; ++b)
        ++workspaces_[b]->below_floor;
      continue;
    }
    const Item& item = items_[i];
    bool prepared = false;
    // The most power any one cell of the image gets from the return at unit two-way gain: for a
    // coherent return its on-grid peak |a|^2 G_p, which bounds its whole response (with
    // non-negative tapers on a constant-envelope pulse, |sum w_i s_i conj(s_i+k) e^(j phi_i)| <=
    // sum w_i |s_i|^2 by the triangle inequality, in range and likewise in Doppler); for a
    // diffuse one, its densest tap (set when prepared). Compared with return_floor_ per beam.
    const double coherent_peak = item.coherent ? std::norm(item.amplitude) * processing_gain : 0.0;
    double diffuse_peak = 0.0;
    long n_bins = 0;  // coherent: the footprint's range bins
    int n_taps = 0;
    // Diffuse: its range footprint as up to three pieces of the difference array (the bins it
    // partly covers at each end, and the bins between), clipped to the swath once for all beams
    // and taps; `span` is the bins they cover.
    DiffusePieces pieces;
    // Gaussian pattern on evenly spaced beams (az_rec_): with E(t) = exp(-c t^2) and t the
    // offset from beam b's boresight, t_{b+1} = t_b - Delta, so E(t - Delta) = E(t) r(t) with
    // r(t) = exp(2 c Delta t - c Delta^2) and r(t - Delta) = r(t) exp(-2 c Delta^2): the two
    // component beams E(t -+ d) of every beam from the first one's by products (three `exp` a
    // return instead of two a beam; exact in real arithmetic, rounding-level otherwise). Only
    // the sum channel is needed here. The recurrence starts at the return's first beam of the
    // whole scan whatever this worker's block, so the result does not depend on the number of
    // workers.
    // The recurrence's start depends on the return's azimuth alone (and this worker's block):
    // returns at an azimuth met before (the terrain engine's cells: one azimuth a column) take
    // the values computed then, from a small direct-mapped memo (the same values: exact).
    double rec_a = 0.0, rec_ra = 0.0, rec_b = 0.0, rec_rb = 0.0;
    AzMemo* memo = nullptr;
    if (az_rec_.on) {
      std::uint64_t bits = 0;
      std::memcpy(&bits, &item.azimuth_rad, sizeof bits);
      memo = &az_memo[(bits * 0x9e3779b97f4a7c15ull) >> (64 - kAzMemoBits)];
      if (memo->azimuth_rad == item.azimuth_rad) {
        rec_a = memo->a;
        rec_b = memo->b;
        rec_ra = memo->ra;
        rec_rb = memo->rb;
        memo = nullptr;
      }
    }
    if (memo != nullptr) {
      const double t0 = item.azimuth_rad - config_.antenna.beam_azimuth_rad[b_lowest];
      const double ta = t0 - az_rec_.squint, tb = t0 + az_rec_.squint;
      const double cs = az_rec_.c * az_rec_.step;
      rec_a = std::exp(-az_rec_.c * ta * ta);
      rec_b = std::exp(-az_rec_.c * tb * tb);
      rec_ra = std::exp(cs * (2.0 * ta - az_rec_.step));
      rec_rb = rec_ra * az_rec_.k;
      for (std::size_t b = b_lowest; b < b_first; ++b) {
        rec_a *= rec_ra;
        rec_b *= rec_rb;
        rec_ra *= az_rec_.q;
        rec_rb *= az_rec_.q;
      }
      *memo = {item.azimuth_rad, rec_a, rec_b, rec_ra, rec_rb};
    }
    for (std::size_t b = b_first; b < b_end; ++b) {
      Gains g;
      if (az_rec_.on) {
        const double s_az = (rec_a + (az_rec_.squint > 0.0 ? rec_b : 0.0)) * az_rec_.norm;
        rec_a *= rec_ra;
        rec_b *= rec_rb;
        rec_ra *= az_rec_.q;
        rec_rb *= az_rec_.q;
        if (std::abs(item.azimuth_rad - config_.antenna.beam_azimuth_rad[b]) > az_extent_rad_)
          continue;
        const double tx = s_az * item.sum_el;
        const double two_way = tx * tx;
        if (!(two_way * two_way >= gain_floor_))
          continue;
        g.sum = two_way;
      } else if (!gains_of(item, b, g)) {
        continue;
      }
      Workspace& ws = *workspaces_[b];
      if (item.coherent) {
        // Below the floor in this beam (SensorConfig::return_floor_db): left out before its
        // response is prepared, which is most of a return's cost.
        if (g.sum * g.sum * coherent_peak < return_floor_) {
          ++ws.below_floor;
          continue;
        }
        if (!prepared) {
          if (!proc.footprint(item.amplitude, item.pos, item.radial_velocity_mps, fp))
            break;
          // The response's cells at unit gain, once a return (velocity value times range value,
          // the complex product written out as in add_footprint), so that each beam adds them
          // times its real gain: a scaled sum, which the compiler vectorises.
          n_bins = fp.l1 - fp.l0 + 1;
          for (int r = 0; r < fp.n_rows; ++r) {
            const double vr = fp.velocity[r].real(), vi = fp.velocity[r].imag();
            std::complex<double>* out = cells + r * n_bins;
            for (long l = 0; l < n_bins; ++l) {
              const double rr = fp.range[l].real(), ri = fp.range[l].imag();
              out[l] = {vr * rr - vi * ri, vr * ri + vi * rr};
            }
          }
          prepared = true;
        }
        for (int r = 0; r < fp.n_rows; ++r) {
          std::complex<double>* row = ws.image.data() + static_cast<std::size_t>(fp.rows[r]) * nr +
                                      static_cast<std::size_t>(fp.l0);
          const std::complex<double>* x = cells + r * n_bins;
          for (long l = 0; l < n_bins; ++l)
            row[l] = {row[l].real() + g.sum * x[l].real(), row[l].imag() + g.sum * x[l].imag()};
          cover(ws.dirty[fp.rows[r]], fp.l0, fp.l1 + 1);
        }
        continue;
      }
      if (!prepared) {
        proc.velocity_power_taps(item.pos.velocity_bin, dj0, dj1, taps);
        // The taps' rows, wrapping (one modulo an item).
        long row = ((std::lround(item.pos.velocity_bin) + dj0) % nvl + nvl) % nvl;
        for (long dj = dj0; dj <= dj1; ++dj) {
          tap_rows[n_taps++] = static_cast<std::uint32_t>(row);
          row = row + 1 == nvl ? 0 : row + 1;
        }
        pieces = make_pieces(item.pos.range_bin, item.half_bins, nrl);
        // The values of the pieces, tap by tap, at unit two-way gain: once a return, so that a
        // beam only scales them (no division a tap and a beam).
        const double p = std::norm(item.amplitude) * range_energy_;
        const double density = pieces.single ? p : p / pieces.extent;
        for (int t = 0; t < n_taps; ++t) {
          const double v = density * taps[t];
          values[0][t] = pieces.single ? v : v * pieces.share[0];
          values[1][t] = v * pieces.share[1];
          values[2][t] = v;
          diffuse_peak = std::max(diffuse_peak, v);  // no cell of it gets more (shares <= 1)
        }
        prepared = true;
      }
      if (pieces.span_begin >= pieces.span_end)
        continue;
      // Each piece's two ends added to the taps' rows times the beam's two-way power gain
      // (contiguous in the transposed array; two runs where the rows wrap).
      const double s = g.sum * g.sum;
      if (s * diffuse_peak < return_floor_) {  // below the floor in this beam
        ++ws.below_floor;
        continue;
      }
      for (int t = 0; t < n_taps; ++t)
        cover(ws.dirty[tap_rows[t]], pieces.span_begin, pieces.span_end);
      // The terrain engine's cells come in range order: the one-bin sums a few bins beyond this
      // return's are fetched ahead (a hint only; every order gives the same sums).
      if (pieces.span_end + kPrefetchBins + 2 < nrl) {
        const double* ahead = ws.direct.data() +
                              static_cast<std::size_t>(pieces.span_end + kPrefetchBins) * nv +
                              tap_rows[0];
        __builtin_prefetch(ahead, 1);
        __builtin_prefetch(ahead + 8, 1);
        __builtin_prefetch(ahead + nv, 1);
        __builtin_prefetch(ahead + nv + 8, 1);
      }
      const int n_first = std::min(n_taps, static_cast<int>(nvl - tap_rows[0]));
      for (int k = 0; k < (pieces.single ? 1 : 3); ++k) {
        if (pieces.a[k] > pieces.c[k])
          continue;
        const double* x = values[k];
        if (pieces.a[k] == pieces.c[k]) {  // one bin: added to it directly
          double* at = ws.direct.data() + static_cast<std::size_t>(pieces.a[k]) * nv;
          for (int t = 0, c = static_cast<int>(tap_rows[0]); t < n_first; ++t, ++c)
            at[c] += x[t] * s;
          for (int t = n_first, c = 0; t < n_taps; ++t, ++c)
            at[c] += x[t] * s;
          continue;
        }
        ws.clutter_begin = std::min(ws.clutter_begin, static_cast<std::uint32_t>(pieces.a[k]));
        ws.clutter_end = std::max(ws.clutter_end, static_cast<std::uint32_t>(pieces.c[k] + 2));
        double* on = ws.clutter.data() + static_cast<std::size_t>(pieces.a[k]) * nv;
        double* off = ws.clutter.data() + static_cast<std::size_t>(pieces.c[k] + 1) * nv;
        for (int t = 0, c = static_cast<int>(tap_rows[0]); t < n_first; ++t, ++c) {
          on[c] += x[t] * s;
          off[c] -= x[t] * s;
        }
        for (int t = n_first, c = 0; t < n_taps; ++t, ++c) {
          on[c] += x[t] * s;
          off[c] -= x[t] * s;
        }
      }
    }
  }
  for (std::size_t b = beam_begin; b < beam_end; ++b)
    detect_beam(b, *workspaces_[b]);
}

void Sensor::detect_beam(std::size_t beam, Workspace& ws) noexcept {
  const RangeDopplerProcessor& proc = *processor_;
  const std::size_t nr = proc.range_bins(), nv = proc.velocity_bins();
  const auto nrl = static_cast<long>(nr), nvl = static_cast<long>(nv);
  // 1. Where to synthesise: the returns' cells widened by the CFAR margins once (cells under
  // test whose window or neighbours hold a return) and twice (the cells those windows read).
  if (config_.synthesise_every_cell) {
    std::fill(ws.cuts.begin(), ws.cuts.end(), RowSpan{0, static_cast<std::uint32_t>(nr)});
    std::fill(ws.synth.begin(), ws.synth.end(), RowSpan{0, static_cast<std::uint32_t>(nr)});
  } else {
    const long mr = ws.cfar.range_margin(), mv = ws.cfar.velocity_margin();
    dilate(ws.dirty, ws.cuts, mr, mv, nrl);
    dilate(ws.cuts, ws.synth, mr, mv, nrl);
  }

  // 2. Receiver noise and clutter speckle (a complex Gaussian of variance 1 + clutter a cell).
  // Where no target adds a coherent signal only the power is needed: it is exponential (drawn by
  // the ziggurat, NoiseRng::exponential: the same law as -log(U) without the log).
  const double floor_var = config_.thermal_noise ? 1.0 : 0.0;
  for (std::size_t j = 0; j < nv; ++j) {
    const RowSpan sp = ws.synth[j], d = ws.dirty[j];
    if (sp.empty())
      continue;
    NoiseRng rng(stream_key(config_.noise_seed, frame_, kChannelSum, beam, j));
    std::complex<double>* image = ws.image.data() + j * nr;
    double* power = ws.power.data() + j * nr;
    auto synthesise = [&](std::uint32_t l, double var) {
      if (image[l] == std::complex<double>{0.0, 0.0}) {
        power[l] = var > 0.0 ? var * rng.exponential(exp_ziggurat_) : 0.0;
      } else {
        if (var > 0.0)
          image[l] += std::sqrt(var) * rng.complex_normal();
        power[l] = std::norm(image[l]);
      }
    };
    // Clutter power: the running sum of its difference array over the bins it reaches, plus
    // the one-bin pieces' power (both read once, and cleared for the next frame as read). The
    // difference array is read only on the bins the returns wrote (clutter_begin/end): before
    // them the sum is 0, after them it keeps its value (the same sums as reading the zeros).
    const std::uint32_t d0 = d.empty() ? sp.end : d.begin, d1 = d.empty() ? sp.end : d.end;
    const std::uint32_t c0 = std::clamp(ws.clutter_begin, d0, d1),
                        c1 = std::clamp(ws.clutter_end, c0, d1);
    for (std::uint32_t l = sp.begin; l < d0; ++l)
      synthesise(l, floor_var);
    double run = 0.0;
    double* diff = ws.clutter.data() + j;
    double* direct = ws.direct.data() + j;
    // rounding of the running sum must not go negative
    for (std::uint32_t l = d0; l < c0; ++l) {
      const double one_bin = direct[l * nv];
      direct[l * nv] = 0.0;
      synthesise(l, floor_var + (std::max(run, 0.0) + one_bin));
    }
    for (std::uint32_t l = c0; l < c1; ++l) {
      run += diff[l * nv];
      diff[l * nv] = 0.0;
      const double one_bin = direct[l * nv];
      direct[l * nv] = 0.0;
      synthesise(l, floor_var + (std::max(run, 0.0) + one_bin));
    }
    for (std::uint32_t l = c1; l < d1; ++l) {
      const double one_bin = direct[l * nv];
      direct[l * nv] = 0.0;
      synthesise(l, floor_var + (std::max(run, 0.0) + one_bin));
    }
    if (!d.empty())
      diff[static_cast<std::size_t>(d.end) * nv] = 0.0;
    for (std::uint32_t l = d1; l < sp.end; ++l)
      synthesise(l, floor_var);
    ws.synthesised += sp.end - sp.begin;
  }

  // 3. CFAR, then keep local maxima over the 8 neighbours (velocity wraps; ties by index).
  std::uint64_t overflow = 0;
  const std::size_t n_hits = ws.cfar.detect(ws.power, ws.cuts, ws.hits, overflow);
  ws.crossings += n_hits + overflow;
  ws.overflowed += overflow;
  std::size_t n_cand = 0;
  Candidate* out = candidates_.data() + beam_first_[beam];
  for (std::size_t h = 0; h < n_hits; ++h) {
    const CfarHit& hit = ws.hits[h];
    const auto l = static_cast<long>(hit.range_bin), j = static_cast<long>(hit.velocity_bin);
    const std::size_t idx = static_cast<std::size_t>(j) * nr + static_cast<std::size_t>(l);
    bool peak = true;
    for (long dj = -1; dj <= 1 && peak; ++dj) {
      const long jj = ((j + dj) % nvl + nvl) % nvl;
      for (long dl = -1; dl <= 1; ++dl) {
        const long ll = l + dl;
        if (ll < 0 || ll >= nrl || (dj == 0 && dl == 0))
          continue;
        const std::size_t o = static_cast<std::size_t>(jj) * nr + static_cast<std::size_t>(ll);
        if (ws.power[o] > hit.power || (ws.power[o] == hit.power && o < idx)) {
          peak = false;
          break;
        }
      }
    }
    if (!peak || n_cand >= per_beam_capacity_)
      continue;
    Candidate& cand = out[n_cand++];
    cand.power = hit.power;
    cand.noise = hit.noise;
    cand.beam = static_cast<std::uint32_t>(beam);
    cand.range_bin = hit.range_bin;
    cand.velocity_bin = hit.velocity_bin;
    // The Sigma value: drawn above where a target adds signal; elsewhere only its power was
    // needed, and its phase is uniform and independent of it.
    if (ws.image[idx] != std::complex<double>{0.0, 0.0}) {
      cand.sum = ws.image[idx];
    } else {
      NoiseRng phase(stream_key(config_.noise_seed, frame_, kChannelSpeckle, beam, idx));
      cand.sum = std::polar(std::sqrt(hit.power), 2.0 * kPi * phase.uniform());
    }
    const double pm = l > 0 ? ws.power[idx - 1] : 0.0;
    const double pp = l + 1 < nrl ? ws.power[idx + 1] : 0.0;
    const std::size_t jm = static_cast<std::size_t>((j + nvl - 1) % nvl);
    const std::size_t jp = static_cast<std::size_t>((j + 1) % nvl);
    cand.delta_r = vertex(pm, hit.power, pp);
    cand.delta_v = vertex(ws.power[jm * nr + static_cast<std::size_t>(l)], hit.power,
                          ws.power[jp * nr + static_cast<std::size_t>(l)]);
  }

  // 4. The noise-only cells: their false alarms, drawn (Cfar2d::draw_false_alarms).
  std::size_t n_fa = 0;
  if (config_.thermal_noise) {
    NoiseRng rng(stream_key(config_.noise_seed, frame_, kChannelFalseAlarm, beam));
    std::uint64_t crossings = 0, fa_overflow = 0;
    n_fa = ws.cfar.draw_false_alarms(rng, ws.cuts, ws.alarms, crossings, fa_overflow);
    ws.crossings += crossings;
    ws.overflowed += fa_overflow;
    for (std::size_t i = 0; i < n_fa && n_cand < per_beam_capacity_; ++i) {
      const FalseAlarm& fa = ws.alarms[i];
      Candidate& cand = out[n_cand++];
      cand.power = fa.hit.power;
      cand.noise = fa.hit.noise;
      cand.beam = static_cast<std::uint32_t>(beam);
      cand.range_bin = fa.hit.range_bin;
      cand.velocity_bin = fa.hit.velocity_bin;
      NoiseRng phase(stream_key(config_.noise_seed, frame_, kChannelSpeckle, beam,
                                std::uint64_t{fa.hit.velocity_bin} * nr + fa.hit.range_bin));
      cand.sum = std::polar(std::sqrt(fa.hit.power), 2.0 * kPi * phase.uniform());
      cand.delta_r = vertex(fa.range_minus, fa.hit.power, fa.range_plus);
      cand.delta_v = vertex(fa.velocity_minus, fa.hit.power, fa.velocity_plus);
    }
  }
  beam_count_[beam] = n_cand;
  if (capturing_)
    capture_beam(beam, ws, n_fa);

  // 5. Leave the image zero for the next frame: clear what was written (the clutter was cleared
  // as step 2 read it).
  ws.clutter_begin = std::numeric_limits<std::uint32_t>::max();
  ws.clutter_end = 0;
  for (std::size_t j = 0; j < nv; ++j) {
    RowSpan& d = ws.dirty[j];
    if (d.empty())
      continue;
    std::fill(ws.image.begin() + static_cast<long>(j * nr + d.begin),
              ws.image.begin() + static_cast<long>(j * nr + d.end), std::complex<double>{});
    d = RowSpan{};
  }
}

void Sensor::cell_channels(const Candidate& c, double& az_ratio, double& el_ratio,
                           std::uint32_t& object_id) const noexcept {
  az_ratio = el_ratio = 0.0;
  object_id = kNoObject;
  const RangeDopplerProcessor& proc = *processor_;
  // The coherent Sigma response at the cell per object (a target is many returns: its rays add
  // coherently); up to kObjects distinct objects, the rest are too many to matter here.
  constexpr std::size_t kObjects = 32;
  std::array<std::uint32_t, kObjects> ids{};
  std::array<std::complex<double>, kObjects> per_object{};
  std::size_t n_objects = 0;
  const auto l = static_cast<long>(c.range_bin), j = static_cast<long>(c.velocity_bin);
  // Coherent parts of the three channels, and the covariances of their Gaussian parts (clutter
  // from the same patches in all three; receiver noise independent in each).
  std::complex<double> s_coh{0.0, 0.0}, d_az{0.0, 0.0}, d_el{0.0, 0.0};
  const double n0 = config_.thermal_noise ? 1.0 : 0.0;
  double c_ss = n0, c_as = 0.0, c_aa = n0, c_es = 0.0, c_ee = n0;
  const double reach = proc.config().kernel_half_width_bins + max_half_bins_ + 1.0;
  const auto nr = static_cast<long>(proc.range_bins());
  const long b0 = std::max<long>(0, static_cast<long>(std::floor(static_cast<double>(l) - reach)));
  const long b1 =
      std::min<long>(nr - 1, static_cast<long>(std::ceil(static_cast<double>(l) + reach)));
  // The returns in reach, by range bucket: scattered over the items (fetched kAhead ahead).
  constexpr std::uint32_t kAhead = 8;
  const std::uint32_t q_end = range_start_[static_cast<std::size_t>(b1) + 1];
  for (std::uint32_t q = range_start_[static_cast<std::size_t>(b0)]; q < q_end; ++q) {
    if (q + kAhead < q_end) {
      const char* ahead = reinterpret_cast<const char*>(&items_[by_range_[q + kAhead]]);
      __builtin_prefetch(ahead);
      __builtin_prefetch(ahead + sizeof(Item) - 1);
    }
    const Item& item = items_[by_range_[q]];
    // A return whose response at the cell is zero adds nothing (its products are zeros): its
    // beam gains (two exp) are needed only to register a coherent return's object when it is new
    // (the order objects are met in stays the same). Most returns in reach are such.
    Gains g;
    if (item.coherent) {
      const std::complex<double> r = proc.response_at(
          {item.amplitude, item.range_m, item.radial_velocity_mps}, c.range_bin, c.velocity_bin);
      if (r == std::complex<double>{0.0, 0.0}) {
        std::size_t o = 0;
        while (o < n_objects && ids[o] != item.object_id)
          ++o;
        if (o == n_objects && n_objects < kObjects && gains_of(item, c.beam, g))
          ids[n_objects++] = item.object_id;
        continue;
      }
      if (!gains_of(item, c.beam, g))
        continue;
      s_coh += r * g.sum;
      d_az += r * g.daz;
      d_el += r * g.del;
      std::size_t o = 0;
      while (o < n_objects && ids[o] != item.object_id)
        ++o;
      if (o == n_objects && n_objects < kObjects)
        ids[n_objects++] = item.object_id;
      if (o < n_objects)
        per_object[o] += r * g.sum;
    } else {
      const double p = std::norm(item.amplitude) * range_energy_ * range_share(item, l) *
                       velocity_weight(item, j);
      if (p == 0.0 || !gains_of(item, c.beam, g))
        continue;
      c_ss += p * g.sum * g.sum;
      c_as += p * g.sum * g.daz;
      c_aa += p * g.daz * g.daz;
      c_es += p * g.sum * g.del;
      c_ee += p * g.del * g.del;
    }
  }
  // Ground truth: the object whose coherent power at the cell exceeds the clutter's mean power
  // and the noise's (and every other object's).
  double best = std::max(c_ss - n0, n0);
  for (std::size_t o = 0; o < n_objects; ++o) {
    if (std::norm(per_object[o]) > best) {
      best = std::norm(per_object[o]);
      object_id = ids[o];
    }
  }
  if (!config_.antenna.monopulse)
    return;
  // Difference channel given the sum: jointly Gaussian, so Delta | Sigma is Gaussian with mean
  // (C_ds / C_ss) (Sigma - Sigma_coh) and variance C_dd - C_ds^2 / C_ss.
  const std::complex<double> x = c.sum - s_coh;
  const std::uint64_t cell = static_cast<std::uint64_t>(j) * proc.range_bins() + c.range_bin;
  auto draw = [&](std::complex<double> coh, double c_ds, double c_dd, std::uint64_t channel) {
    std::complex<double> d = coh;
    if (c_ss > 0.0) {
      d += (c_ds / c_ss) * x;
      const double var = std::max(0.0, c_dd - c_ds * c_ds / c_ss);
      NoiseRng rng(stream_key(config_.noise_seed, frame_, channel, c.beam, cell));
      d += std::sqrt(var) * rng.complex_normal();
    }
    return d;
  };
  const std::complex<double> daz = draw(d_az, c_as, c_aa, kChannelDeltaAz);
  const std::complex<double> del = draw(d_el, c_es, c_ee, kChannelDeltaEl);
  const double s2 = std::norm(c.sum);
  if (s2 > 0.0) {
    az_ratio = (daz * std::conj(c.sum)).real() / s2;
    el_ratio = (del * std::conj(c.sum)).real() / s2;
  }
}

void Sensor::merge_returns(std::span<const Contribution> contributions,
                           SensorStats& stats) noexcept {
  // Coherent returns of one object within one merge cell of each other (merge_step_bins in range
  // and velocity, merge_step_beamwidths of the sum beam in azimuth and elevation) reach the image
  // through responses that differ by less than the direct path's own table step: they are one
  // return, with the sum of their amplitudes at their amplitude-weighted mean position. The
  // first return of a cell represents it, and the cell's sums accumulate in input order, so the
  // result depends on nothing but the input order (not on the table, the hash or the threads).
  // The keys, hashes and weighted positions are computed per item in parallel beforehand
  // (merge_key()). The returns are split into kMergeParts parts by their object (object_id mod
  // kMergeParts, merge_part_): a cell is one object's, so every return of a cell is in one part,
  // and the parts are merged independently (in parallel), each walking its own returns in input
  // order through its own region of the table (open addressing, at least twice its returns). An
  // object's returns come in runs (its kept paths, its rays' returns), so a part reads them in
  // sequence (a split by the key's hash read every kMergeParts-th return and was 2.5 times
  // slower, docs/performance.md). An entry holds the upper half of its key's hash beside the
  // item, so that a probe of another cell seldom reads its key. A cell's sums and amplitude
  // accumulate on its representative's entries; the representatives' items are written once, by
  // the part's finish.
  auto part_of = [&](std::size_t i) { return static_cast<std::size_t>(merge_part_[i]); };
  // Each part's returns in input order (a stable counting sort) and its region of the table.
  std::array<std::size_t, kMergeParts + 1> first{};
  for (std::size_t i = 0; i < item_count_; ++i)
    first[part_of(i) + 1] += merge_hashed_[i];
  for (std::size_t p = 0; p < kMergeParts; ++p)
    first[p + 1] += first[p];
  std::array<std::size_t, kMergeParts> next{};
  std::copy_n(first.begin(), kMergeParts, next.begin());
  for (std::size_t i = 0; i < item_count_; ++i)
    if (merge_hashed_[i])
      merge_order_[next[part_of(i)]++] = static_cast<std::uint32_t>(i);
  std::array<std::uint64_t, kMergeParts> merged{};
  // Part p's returns are merge_order_[first[p], first[p + 1]); its region of the table starts at
  // 2 first[p] + 2 p and holds 2 n + 2 entries (within merge_table_: set up for every return).
  auto merge_part = [&](std::size_t p) {
    const std::size_t begin = first[p], end = first[p + 1];
    if (begin == end)
      return;
    std::uint64_t* table = merge_table_.data() + 2 * begin + 2 * p;
    const std::uint64_t size = 2 * (end - begin) + 2;
    // A hash's slot in the region: its lower 32 bits scaled to [0, size) (Lemire, "Fast random
    // integer generation in an interval", ACM TOMACS 29(1), 2019).
    auto home = [&](std::size_t i) {
      return static_cast<std::size_t>(((merge_hash_[i] & 0xFFFFFFFFull) * size) >> 32);
    };
    // The table's lines are random: fetched kAhead returns ahead of the walk.
    constexpr std::size_t kAhead = 16;
    std::size_t n_used = begin;  // the part's representatives: merge_used_[begin, n_used)
    for (std::size_t q = begin; q < end; ++q) {
      if (q + kAhead < end)
        __builtin_prefetch(table + home(merge_order_[q + kAhead]));
      const std::size_t i = merge_order_[q];
      const MergeKey& key = merge_keys_[i];
      const std::uint64_t tag = merge_hash_[i] >> 32;
      std::size_t slot = home(i);
      std::size_t rep = 0;
      bool found = false;
      for (std::uint64_t e = table[slot]; e != 0;
           slot = slot + 1 == size ? 0 : slot + 1, e = table[slot]) {
        rep = static_cast<std::size_t>(e & 0xFFFFFFFFu) - 1;
        if ((e >> 32) == tag && merge_keys_[rep] == key) {
          found = true;
          break;
        }
      }
      if (!found) {  // the first return of its cell represents it
        table[slot] = (tag << 32) | static_cast<std::uint64_t>(i + 1);
        merge_used_[n_used++] = static_cast<std::uint32_t>(i);
        continue;
      }
      // The cell's sums and amplitude accumulate on its representative's entries.
      const MergeSums& m = merge_sums_[i];
      MergeSums& a = merge_sums_[rep];
      merge_amplitude_[rep] += merge_amplitude_[i];
      a.weight += m.weight;
      a.range_bin += m.range_bin;
      a.velocity_bin += m.velocity_bin;
      a.range_m += m.range_m;
      a.velocity_mps += m.velocity_mps;
      a.azimuth_rad += m.azimuth_rad;
      a.elevation_rad += m.elevation_rad;
      ++a.count;
      item_state_[i] = kMerged;  // its beam span stays empty (prepare)
      ++merged[p];
    }
    // The region emptied for the next frame at once (it is contiguous), and the representatives
    // finished in input order (they are, within a part): their sums, contributions and items are
    // then read and written in ascending order, not at the table's random slots.
    std::fill_n(table, size, std::uint64_t{0});
    for (std::size_t u = begin; u < n_used; ++u) {
      if (u + kAhead < n_used) {
        const std::size_t ahead = merge_used_[u + kAhead];
        __builtin_prefetch(&merge_sums_[ahead]);
        __builtin_prefetch(&contributions[ahead]);
        __builtin_prefetch(&items_[ahead], 1);
      }
      finish_merged(contributions, merge_used_[u]);
    }
  };
  tbb::parallel_for(std::size_t{0}, kMergeParts, merge_part);
  for (const std::uint64_t m : merged)
    stats.merged_returns += m;
}

void Sensor::finish_merged(std::span<const Contribution> contributions,
                           std::uint32_t representative) noexcept {
  // A merged cell's representative: its item (from its contribution, as the prepare step writes
  // the others' items), with the summed amplitude and the mean position, and its elevation
  // channels there.
  const std::size_t rep = representative;
  const MergeSums& a = merge_sums_[rep];
  const Contribution& c = contributions[rep];
  Item& r = items_[rep];
  r.amplitude = merge_amplitude_[rep];
  r.pos = processor_->position_of(c.range_m, c.radial_velocity_mps);
  r.coherent = true;
  r.object_id = c.object_id;
  r.half_bins = 0.0;
  r.range_m = c.range_m;
  r.radial_velocity_mps = c.radial_velocity_mps;
  r.azimuth_rad = c.azimuth_rad;
  r.elevation_rad = c.elevation_rad;
  if (a.count >= 2 && a.weight > 0.0) {
    r.pos.range_bin = a.range_bin / a.weight;
    r.pos.velocity_bin = a.velocity_bin / a.weight;
    r.range_m = a.range_m / a.weight;
    r.radial_velocity_mps = a.velocity_mps / a.weight;
    r.azimuth_rad = a.azimuth_rad / a.weight;
    r.elevation_rad = a.elevation_rad / a.weight;
  }
  antenna_.channels_el(r.elevation_rad - config_.antenna.beam_elevation_rad, r.sum_el, r.delta_el);
  item_beams_[rep] = beam_span(r);
  item_bucket_[rep] = bucket_of(r);
  item_bound_[rep] = bound_of(r);
}

double Sensor::bound_of(const Item& it) const noexcept {
  if (!it.coherent)
    return std::numeric_limits<double>::infinity();
  const double g = max_sum_az_ * it.sum_el;  // the two-way amplitude gain is g^2 at most
  return std::norm(it.amplitude) * processor_->processing_gain() * (g * g) * (g * g);
}

std::uint32_t Sensor::bucket_of(const Item& it) const noexcept {
  return static_cast<std::uint32_t>(std::clamp<long>(
      std::lround(it.pos.range_bin), 0, static_cast<long>(processor_->range_bins()) - 1));
}

void Sensor::merge_key(std::size_t i, const Contribution& c, const ImagePosition& pos,
                       std::complex<double> amplitude) noexcept {
  const double q = merge_per_bin_;
  // floor(x) for finite x within +-2^63: truncation, one less below zero off the integers
  // (std::floor is a library call without SSE4.1).
  auto cell = [](double x) {
    const auto t = static_cast<long long>(x);
    return t - (x < static_cast<double>(t) ? 1 : 0);
  };
  const MergeKey key{c.object_id, cell(pos.range_bin * q), cell(pos.velocity_bin * q),
                     cell(c.azimuth_rad * merge_per_rad_az_),
                     cell(c.elevation_rad * merge_per_rad_el_)};
  merge_keys_[i] = key;
  merge_part_[i] = static_cast<std::uint8_t>(c.object_id % kMergeParts);
  // The hash places the key in the table only (the result does not depend on it): one
  // multiply a field, then splitmix64's finaliser (Steele, Lea and Flood, "Fast splittable
  // pseudorandom number generators", OOPSLA 2014).
  std::uint64_t h = key.object_id * 0x9e3779b97f4a7c15ull;
  for (long long v : {key.range, key.velocity, key.azimuth, key.elevation})
    h = (h ^ static_cast<std::uint64_t>(v)) * 0xd1342543de82ef95ull;
  h = (h ^ (h >> 30)) * 0xbf58476d1ce4e5b9ull;
  h = (h ^ (h >> 27)) * 0x94d049bb133111ebull;
  h ^= h >> 31;
  merge_hash_[i] = h;
  merge_hashed_[i] = 1;
  // |amplitude| as sqrt(re^2 + im^2) (no hypot call: the amplitudes are in noise units, far
  // from overflow; rounding-level).
  const double w = std::sqrt(std::norm(amplitude));
  merge_amplitude_[i] = amplitude;
  merge_sums_[i] = {w,
                    w * pos.range_bin,
                    w * pos.velocity_bin,
                    w * c.range_m,
                    w * c.radial_velocity_mps,
                    w * c.azimuth_rad,
                    w * c.elevation_rad,
                    1};
}

std::size_t Sensor::process(std::span<const Contribution> contributions, std::span<Detection> out,
                            SensorStats& stats) noexcept {
  const RangeDopplerProcessor& proc = *processor_;
  const std::size_t n_beams = antenna_.beams();
  const std::size_t nr = proc.range_bins();
  // A capture armed by capture_next() covers this call only, and only storage of the right shape.
  capturing_ = false;
  if (capture_ != nullptr) {
    const CaptureShape shape = capture_shape();
    SensorCapture& c = *capture_;
    c.filled = false;
    capturing_ = c.image.size() >= shape.image_values() && c.power.size() >= shape.image_values() &&
                 c.synthesised.size() >= n_beams * shape.velocity_bins &&
                 c.false_alarm_count.size() >= n_beams;
    std::fill(capture_dropped_.begin(), capture_dropped_.end(), 0);
  }
  if (contributions.size() > items_.size()) {
    stats.dropped_input += contributions.size() - items_.size();
    contributions = contributions.first(items_.size());
  }
  // The frame's returns: position on the image and amplitude, once for all beams; then bucket
  // them by range bin (counting sort) for the monopulse look-ups.
  const double bin_m = range_cell_m();
  item_count_ = contributions.size();
  max_half_bins_ = 0.0;
  std::fill(range_start_.begin(), range_start_.end(), 0u);
  // Independent per item: prepared in parallel, counted after in order. Returns the half extent
  // of a usable item along range (0 for every other return).
  auto prepare = [&](std::size_t i) -> double {
    const Contribution& c = contributions[i];
    item_beams_[i] = {};
    if (!merge_hashed_.empty())
      merge_hashed_[i] = 0;
    if (!finite(c) || !(c.range_m > 0.0)) {
      item_state_[i] = kNotFinite;
      return 0.0;
    }
    const std::complex<double> amplitude =
        c.amplitude * (amplitude_scale_ / (c.range_m * c.range_m));
    // A coherent return under the floor in every cell of every beam whatever its angles (its
    // on-grid peak at the patterns' largest gains, SensorConfig::return_floor_db) is left out
    // before the merge: a cell then sums the returns over the floor only.
    if (c.coherent && std::norm(amplitude) < floor_norm_) {
      item_state_[i] = kUnderFloor;
      return 0.0;
    }
    const ImagePosition pos = proc.position_of(c.range_m, c.radial_velocity_mps);
    // A coherent return to be merged: its key, weighted position and amplitude only; its item
    // is written after the merge if it represents its cell (merge_returns()), so that the
    // returns summed into another are not written at all.
    if (c.coherent && !merge_table_.empty()) {
      if (!pos.in_swath) {
        item_state_[i] = kOffImage;
        return 0.0;
      }
      item_state_[i] = kUsable;
      merge_key(i, c, pos, amplitude);
      return 0.0;
    }
    Item& it = items_[i];
    it.amplitude = amplitude;
    it.pos = pos;
    it.coherent = c.coherent;
    it.object_id = c.object_id;
    it.half_bins = c.coherent ? 0.0 : 0.5 * std::max(c.range_spread_m, 0.0) / bin_m;
    it.range_m = c.range_m;
    it.radial_velocity_mps = c.radial_velocity_mps;
    it.azimuth_rad = c.azimuth_rad;
    it.elevation_rad = c.elevation_rad;
    const double lo = it.pos.range_bin - it.half_bins, hi = it.pos.range_bin + it.half_bins;
    const bool visible =
        it.coherent ? it.pos.in_swath : hi >= -0.5 && lo < static_cast<double>(nr) - 0.5;
    if (!visible) {
      item_state_[i] = kOffImage;
      return 0.0;
    }
    item_state_[i] = kUsable;
    antenna_.channels_el(it.elevation_rad - config_.antenna.beam_elevation_rad, it.sum_el,
                         it.delta_el);
    item_beams_[i] = beam_span(it);
    item_bound_[i] = bound_of(it);
    item_bucket_[i] = bucket_of(it) | (it.coherent ? 0u : kDiffuseBucket);
    return it.half_bins;
  };
  // The largest diffuse half extent, per block (a maximum: the same whatever the blocks).
  std::atomic<double> max_half_bins{0.0};
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, contributions.size(), 4096),
                    [&](const tbb::blocked_range<std::size_t>& r) {
                      double block_max = 0.0;
                      for (std::size_t i = r.begin(); i != r.end(); ++i)
                        block_max = std::max(block_max, prepare(i));
                      double m = max_half_bins.load(std::memory_order_relaxed);
                      while (block_max > m && !max_half_bins.compare_exchange_weak(m, block_max)) {
                      }
                    });
  max_half_bins_ = max_half_bins.load();
  if (config_.merge_step_bins > 0.0)
    merge_returns(contributions, stats);
  // One pass over the items' states, buckets (written where each item was, in parallel) and
  // beam spans: the counts, and each usable item's bucket kept for the second pass (4 bytes an
  // item); the items themselves are not read.
  constexpr std::uint32_t kNoBucket = 0xFFFFFFFFu;
  std::fill(beam_work_.begin(), beam_work_.end(), 0.0);
  live_count_ = 0;
  for (std::size_t i = 0; i < item_count_; ++i) {
    const std::uint8_t state = item_state_[i];
    stats.rejected_input += state == kNotFinite ? 1u : 0u;
    stats.out_of_grid += state == kOffImage ? 1u : 0u;
    stats.returns_under_floor += state == kUnderFloor ? 1u : 0u;
    if (state != kUsable) {
      item_bucket_[i] = kNoBucket;
      continue;
    }
    const std::uint32_t tagged = item_bucket_[i];
    const std::uint32_t bucket = tagged & ~kDiffuseBucket;
    item_bucket_[i] = bucket;
    ++range_start_[bucket + 1];
    // The work it brings to each beam of its span (a difference array over the beams).
    const BeamSpan span = item_beams_[i];
    live_items_[live_count_] = static_cast<std::uint32_t>(i);
    live_count_ += span.first < span.end ? 1u : 0u;
    // A coherent return under the floor in every beam is skipped by its bound alone.
    const double work = (tagged & kDiffuseBucket) != 0   ? kDiffuseWork
                        : item_bound_[i] < return_floor_ ? kSkippedWork
                                                         : kCoherentWork;
    beam_work_[span.first] += work;
    beam_work_[span.end] -= work;
  }
  split_beams();
  for (std::size_t b = 0; b + 1 < range_start_.size(); ++b)
    range_start_[b + 1] += range_start_[b];
  for (std::size_t i = 0; i < item_count_; ++i)
    if (item_bucket_[i] != kNoBucket)
      by_range_[range_start_[item_bucket_[i]]++] = static_cast<std::uint32_t>(i);
  for (std::size_t b = range_start_.size() - 1; b > 0; --b)  // restore the starts
    range_start_[b] = range_start_[b - 1];
  range_start_[0] = 0;
  if (capturing_) {  // the returns the raw samples are synthesised from (off the frame path)
    SensorCapture& c = *capture_;
    c.return_count = 0;
    c.dropped = 0;
    c.noise_frame = frame_;
    for (std::size_t i = 0; i < item_count_; ++i) {
      if (item_state_[i] != kUsable)
        continue;
      const Item& it = items_[i];
      if (c.return_count >= c.returns.size()) {
        ++c.dropped;
        continue;
      }
      c.returns[c.return_count++] = {it.amplitude,   it.range_m, it.radial_velocity_mps,
                                     it.azimuth_rad, it.sum_el,  it.delta_el,
                                     it.half_bins,   it.coherent};
    }
  }

  for (auto& ws : workspaces_)
    ws->crossings = ws->overflowed = ws->synthesised = ws->below_floor = 0;
  // Beams are independent; worker w handles the w-th block of beams. Every random stream is keyed
  // by (seed, frame, beam, ...), so the result does not depend on the schedule.
  tbb::parallel_for(std::size_t{0}, n_workers_, [&](std::size_t w) { process_worker(w); });
  for (auto& ws : workspaces_) {
    stats.cfar_crossings += ws->crossings;
    stats.hits_overflowed += ws->overflowed;
    stats.cells_synthesised += ws->synthesised;
    stats.returns_below_floor += ws->below_floor;
  }
  stats.cells_touched += n_beams * proc.image_cells();
  if (capturing_) {
    for (std::uint64_t d : capture_dropped_)
      capture_->dropped += d;
    capture_->filled = true;
    capturing_ = false;
  }
  capture_ = nullptr;

  // Group across adjacent beams: strongest first; a peak within one range and one velocity bin
  // of a stronger kept peak in the next beam is the same return seen by that beam's skirt.
  order_.clear();
  for (std::size_t b = 0; b < n_beams; ++b)
    for (std::size_t q = 0; q < beam_count_[b]; ++q)
      order_.push_back(static_cast<std::uint32_t>(beam_first_[b] + q));
  auto snr_of = [&](const Candidate& c) { return c.noise > 0.0 ? c.power / c.noise : c.power; };
  std::sort(order_.begin(), order_.end(), [&](std::uint32_t a, std::uint32_t b) {
    const double sa = snr_of(candidates_[a]), sb = snr_of(candidates_[b]);
    return sa != sb ? sa > sb : a < b;
  });
  const auto nv = static_cast<long>(proc.velocity_bins());
  std::size_t n_out = 0;
  const double min_snr = std::pow(10.0, config_.min_snr_db / 10.0);
  const Waveform& wf = config_.processing.waveform;
  const double lambda = wavelength_m(wf);
  const double k_chirp = chirp_rate_hz_per_s(wf);
  const double v_ua = unambiguous_velocity_mps();
  const double bw_az = antenna_.sum_beamwidth_az_rad(), bw_el = antenna_.sum_beamwidth_el_rad();
  for (std::size_t oi = 0; oi < order_.size(); ++oi) {
    const Candidate& c = candidates_[order_[oi]];
    // A weaker peak in the same range and velocity cell (+-1) of another beam is the same return
    // seen through that beam's skirt when its power is no more than the stronger detection's
    // power times the two-way pattern ratio of the two beams at the detection's angle (+10 dB
    // for noise and speckle).
    bool merged = false;
    const double beam_az = config_.antenna.beam_azimuth_rad[c.beam];
    for (std::size_t q = 0; q < n_out && !merged; ++q) {
      const Detection& k = out[q];
      if (k.azimuth_cell == c.beam)
        continue;
      const long dr = static_cast<long>(k.range_cell) - static_cast<long>(c.range_bin);
      long dv = (static_cast<long>(k.doppler_cell) - static_cast<long>(c.velocity_bin)) % nv;
      dv = std::min((dv + nv) % nv, (nv - dv) % nv);
      if (std::labs(dr) > 1 || dv > 1)
        continue;
      const double off_here = k.azimuth_rad - beam_az;
      if (std::abs(off_here) > az_extent_rad_)
        continue;
      const double off_there = k.azimuth_rad - config_.antenna.beam_azimuth_rad[k.azimuth_cell];
      const double el_off = k.elevation_rad - config_.antenna.beam_elevation_rad;
      const double ratio =
          two_way_gain(off_here, el_off) / std::max(two_way_gain(off_there, el_off), 1e-300);
      merged = c.power <= 10.0 * kept_power_[q] * ratio;
    }
    if (merged) {
      ++stats.merged;
      continue;
    }
    // Measured SNR: (signal + noise) / noise estimate - 1. Without receiver noise the image is
    // still in units of the noise power the radar would have, so its power is the SNR.
    const double snr_meas =
        config_.thermal_noise ? std::max(snr_of(c) - 1.0, 1e-3 * snr_of(c)) : c.power;
    if (snr_meas < min_snr)
      continue;
    if (n_out >= out.size() || n_out >= config_.max_detections) {
      ++stats.truncated;
      continue;
    }
    kept_power_[n_out] = c.power;
    Detection& d = out[n_out++];
    const double v_meas = proc.velocity_of_bin(c.velocity_bin + c.delta_v);
    // Range-Doppler coupling moved the peak by -c f_d / (2 k); undo it with the measured
    // (folded) Doppler (Richards 2014, eqs. 4.105-4.106).
    const double fd = -2.0 * v_meas / lambda;
    d.range_m =
        proc.range_of_bin(c.range_bin + c.delta_r) + kSpeedOfLight_mps * fd / (2.0 * k_chirp);
    d.radial_velocity_mps = v_meas;
    double az_ratio = 0.0, el_ratio = 0.0;
    cell_channels(c, az_ratio, el_ratio, d.object_id);
    const double off_az = config_.antenna.monopulse ? antenna_.offset_from_ratio_az(az_ratio) : 0.0;
    const double off_el = config_.antenna.monopulse ? antenna_.offset_from_ratio_el(el_ratio) : 0.0;
    d.azimuth_rad = config_.antenna.beam_azimuth_rad[c.beam] + off_az;
    d.elevation_rad = config_.antenna.beam_elevation_rad + off_el;
    d.snr = snr_meas;
    // RCS: the SNR the peak would have on the grid and on boresight, through the radar equation.
    const double straddle = proc.straddle_gain(c.delta_r, c.delta_v);
    const double gain = two_way_gain(off_az, off_el);
    const double per_m2 = expected_snr(1.0, std::max(d.range_m, 1e-3));
    d.rcs_m2 = snr_meas / (std::max(straddle, 1e-6) * std::max(gain, 1e-12) * per_m2);
    // Thermal-noise accuracy (Skolnik 2001, sec. 6.3): delay sigma = 1 / (beta sqrt(2 E/N0)),
    // Doppler sigma = 1 / (alpha sqrt(2 E/N0)), with the RMS bandwidth beta and RMS duration
    // alpha of the weighted signal (a Hann taper doubles them against pi B / sqrt(3)); angle
    // sigma = theta_3 / (k_m sqrt(2 SNR)), k_m the monopulse slope (Sherman and Barton 2011).
    // Without monopulse: the beam's width / sqrt(12).
    const double root = std::sqrt(2.0 * snr_meas);
    d.range_std_m = kSpeedOfLight_mps / (2.0 * proc.rms_bandwidth_rad_s() * root);
    d.velocity_std_mps = lambda / (2.0 * proc.rms_duration_rad() * root);
    const double km_az = antenna_.monopulse_slope_az(), km_el = antenna_.monopulse_slope_el();
    d.azimuth_std_rad = km_az > 0.0 ? bw_az / (km_az * root) : bw_az / std::sqrt(12.0);
    d.elevation_std_rad = km_el > 0.0 ? bw_el / (km_el * root) : bw_el / std::sqrt(12.0);
    d.range_ambiguous =
        wf.kind == WaveformKind::kPulsedLfm && unambiguous_range_m() < config_.max_range_m;
    d.velocity_ambiguous = v_ua < config_.processing.max_speed_mps;
    d.range_cell = c.range_bin;
    d.doppler_cell = c.velocity_bin;
    d.azimuth_cell = c.beam;
  }
  stats.detections += n_out;
  ++frame_;
  return n_out;
}

// ---- capture (SensorCapture): the frame path copies; the rest runs on the caller's thread ----

CaptureShape Sensor::capture_shape() const noexcept {
  const RangeDopplerProcessor& proc = *processor_;
  CaptureShape shape;
  shape.beams = antenna_.beams();
  shape.channels = config_.antenna.monopulse ? 3 : 1;
  shape.pulses = proc.velocity_bins();
  shape.fast_samples = proc.cube_fast_samples();
  shape.velocity_bins = proc.velocity_bins();
  shape.range_bins = proc.range_bins();
  return shape;
}

std::unique_ptr<Sensor::RawWorkspace> Sensor::make_raw_workspace(std::size_t max_threads) const {
  const CaptureShape shape = capture_shape();
  auto ws = std::make_unique<RawWorkspace>();
  const std::size_t n =
      std::clamp<std::size_t>(static_cast<std::size_t>(tbb::this_task_arena::max_concurrency()), 1,
                              std::min<std::size_t>({shape.beams, max_threads, std::size_t{4}}));
  for (std::size_t w = 0; w < n; ++w)
    ws->synthesisers.push_back(
        std::make_unique<RangeDopplerProcessor::RawSynthesiser>(*processor_, shape.channels));
  ws->scratch.resize(n * (shape.fast_samples + shape.pulses));
  return ws;
}

void Sensor::capture_beam(std::size_t beam, const Workspace& ws, std::size_t n_alarms) noexcept {
  SensorCapture& c = *capture_;
  const std::size_t nr = processor_->range_bins(), nv = processor_->velocity_bins();
  for (std::size_t j = 0; j < nv; ++j) {
    const RowSpan sp = ws.synth[j];
    c.synthesised[beam * nv + j] = sp;
    const std::size_t src = j * nr, dst = (beam * nv + j) * nr;
    for (std::uint32_t l = sp.begin; l < sp.end; ++l) {
      c.image[dst + l] = std::complex<float>(ws.image[src + l]);
      c.power[dst + l] = static_cast<float>(ws.power[src + l]);
    }
  }
  const std::size_t room = c.false_alarms.size() / antenna_.beams();
  const std::size_t kept = std::min(n_alarms, room);
  std::copy(ws.alarms.begin(), ws.alarms.begin() + static_cast<long>(kept),
            c.false_alarms.begin() + static_cast<long>(beam * room));
  c.false_alarm_count[beam] = static_cast<std::uint32_t>(kept);
  capture_dropped_[beam] = n_alarms - kept;
}

void Sensor::complete_image(SensorCapture& c) const noexcept {
  if (!c.filled)
    return;
  const std::size_t nr = processor_->range_bins(), nv = processor_->velocity_bins();
  const std::size_t n_beams = antenna_.beams();
  const std::uint64_t seed = config_.noise_seed;
  // The phase the sensor gives a cell whose power alone it drew (detect_beam, steps 3 and 4).
  auto speckle = [&](std::size_t beam, std::size_t j, std::size_t l, double power) {
    NoiseRng phase(stream_key(seed, c.noise_frame, kChannelSpeckle, beam, j * nr + l));
    return std::complex<float>(std::polar(std::sqrt(power), 2.0 * kPi * phase.uniform()));
  };
  for (std::size_t b = 0; b < n_beams; ++b) {
    for (std::size_t j = 0; j < nv; ++j) {
      const RowSpan sp = c.synthesised[b * nv + j];
      const std::size_t row = (b * nv + j) * nr;
      NoiseRng noise(stream_key(seed, c.noise_frame, kChannelFileNoise, b, j));
      for (std::size_t l = 0; l < nr; ++l) {
        std::complex<float>& v = c.image[row + l];
        if (l >= sp.begin && l < sp.end) {
          if (v == std::complex<float>{0.0f, 0.0f} && c.power[row + l] > 0.0f)
            v = speckle(b, j, l, static_cast<double>(c.power[row + l]));
        } else {
          v = config_.thermal_noise ? std::complex<float>(noise.complex_normal())
                                    : std::complex<float>{0.0f, 0.0f};
        }
      }
    }
    // The false alarms drawn in this beam's noise-only cells, with their neighbours' powers.
    const std::size_t room = c.false_alarms.size() / n_beams;
    for (std::size_t k = 0; k < c.false_alarm_count[b] && k < room; ++k) {
      const FalseAlarm& fa = c.false_alarms[b * room + k];
      const std::size_t l = fa.hit.range_bin, j = fa.hit.velocity_bin;
      auto put = [&](std::size_t jj, std::size_t ll, double power) {
        c.image[(b * nv + jj) * nr + ll] = speckle(b, jj, ll, power);
      };
      put(j, l, fa.hit.power);
      if (l > 0)
        put(j, l - 1, fa.range_minus);
      if (l + 1 < nr)
        put(j, l + 1, fa.range_plus);
      put((j + nv - 1) % nv, l, fa.velocity_minus);
      put((j + 1) % nv, l, fa.velocity_plus);
    }
  }
}

void Sensor::synthesise_raw(const SensorCapture& c, std::span<std::complex<float>> raw,
                            RawWorkspace& ws) const noexcept {
  const CaptureShape shape = capture_shape();
  const std::size_t n_workers = ws.synthesisers.size();
  if (!c.filled || raw.size() < shape.raw_values() || n_workers == 0 ||
      ws.scratch.size() < n_workers * (shape.fast_samples + shape.pulses))
    return;
  const RangeDopplerProcessor& proc = *processor_;
  const std::size_t nf = shape.fast_samples, np = shape.pulses, nc = shape.channels;
  const double bin_m = range_cell_m();
  const std::uint64_t seed = config_.noise_seed;
  // Worker w synthesises beams w, w + W, ... into their own slices of `raw`.
  tbb::parallel_for(std::size_t{0}, n_workers, [&](std::size_t w) {
    RangeDopplerProcessor::RawSynthesiser& synth = *ws.synthesisers[w];
    const std::span<std::complex<double>> fast = std::span(ws.scratch).subspan(w * (nf + np), nf);
    const std::span<std::complex<double>> slow =
        std::span(ws.scratch).subspan(w * (nf + np) + nf, np);
    for (std::size_t b = w; b < shape.beams; b += n_workers) {
      std::complex<float>* cube = raw.data() + b * nc * np * nf;
      std::fill(cube, cube + nc * np * nf, std::complex<float>{0.0f, 0.0f});
      synth.clear();
      for (std::size_t i = 0; i < c.return_count && i < c.returns.size(); ++i) {
        const CapturedReturn& r = c.returns[i];
        Gains g;
        if (!gains_at(r.azimuth_rad, r.sum_el, r.delta_el, b, g))
          continue;
        const double gains[3] = {g.sum, g.daz, g.del};
        // A diffuse return: points across its range extent, each an independent complex
        // Gaussian of an equal share of its mean power (the same draws in every beam: one
        // patch).
        const int n_sub = r.coherent ? 1
                                     : std::clamp(static_cast<int>(std::ceil(2.0 * r.half_bins)), 1,
                                                  kRawPointsPerDiffuse);
        for (int sub = 0; sub < n_sub; ++sub) {
          PointScatterer p{r.amplitude, r.range_m, r.radial_velocity_mps};
          if (!r.coherent) {
            NoiseRng rng(stream_key(seed, c.noise_frame, kChannelRawSpeckle, i,
                                    static_cast<std::uint64_t>(sub)));
            p.amplitude *= rng.complex_normal() / std::sqrt(static_cast<double>(n_sub));
            p.range_m +=
                ((sub + 0.5) / static_cast<double>(n_sub) - 0.5) * 2.0 * r.half_bins * bin_m;
          }
          if (synth.supported()) {
            synth.add(p, std::span<const double>(gains, nc));
            continue;
          }
          std::size_t first = 0;
          const std::size_t n = proc.echo(p, fast, first, slow);
          const std::size_t len = std::min(n, nf - std::min(first, nf));
          for (std::size_t ch = 0; ch < nc; ++ch) {
            for (std::size_t m = 0; m < np && len > 0; ++m) {
              // The outer product slow x fast, written out (no complex-multiply NaN branches).
              const double fr = slow[m].real() * gains[ch], fi = slow[m].imag() * gains[ch];
              std::complex<float>* row = cube + (ch * np + m) * nf + first;
              for (std::size_t k = 0; k < len; ++k) {
                const double xr = fast[k].real(), xi = fast[k].imag();
                row[k] = {row[k].real() + static_cast<float>(fr * xr - fi * xi),
                          row[k].imag() + static_cast<float>(fr * xi + fi * xr)};
              }
            }
          }
        }
      }
      if (synth.supported())
        synth.render(std::span(cube, nc * np * nf));
      if (!config_.thermal_noise)
        continue;
      for (std::size_t ch = 0; ch < nc; ++ch) {
        for (std::size_t m = 0; m < np; ++m) {
          NoiseRng rng(stream_key(seed, c.noise_frame, kChannelRawNoise + ch, b, m));
          std::complex<float>* row = cube + (ch * np + m) * nf;
          for (std::size_t n = 0; n < nf; ++n)
            row[n] += std::complex<float>(rng.complex_normal());
        }
      }
    }
  });
}

}  // namespace radar_emu::radar
