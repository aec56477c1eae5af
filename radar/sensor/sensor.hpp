#pragma once
// The radar sensor: turns one frame's scattering contributions into a detection list, as a
// scanning pulse-Doppler (or FMCW) radar with amplitude-comparison monopulse would.
//
// For each beam position of the scan: every contribution inside the beam's pattern is weighted by
// the two-way gain of the sum channel (and of the azimuth and elevation difference channels) and
// the radar equation, added to the range-velocity image with the waveform's exact response
// (RangeDopplerProcessor's direct path; diffuse clutter as speckle, a complex Gaussian of the
// footprint's mean power), receiver noise is added, and a 2-D CFAR finds the crossings. Peaks are
// grouped within the beam and across adjacent beams; each detection gets interpolated range and
// velocity, a monopulse angle, measured SNR, an RCS estimate from the radar equation, one-sigma
// uncertainties, ambiguity flags and the scene object that dominates its cell.
//
// Cost follows the signal, not the image: only the cells a return reaches are synthesised, with
// the CFAR windows around them (Cfar2d::range_margin/velocity_margin, twice: the cells under
// test next to a return, and the cells their windows read). Every other cell holds receiver
// noise alone, and its false alarms are drawn from their exact distribution, CFAR and
// local-maximum test included (Cfar2d::draw_false_alarms), so an empty frame costs a few
// microseconds a beam. `synthesise_every_cell` turns this off (the reference the tests compare
// the statistical cells with).

#include <complex>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <span>
#include <vector>

#include "radar/antenna/antenna.hpp"
#include "radar/em/sbr.hpp"
#include "radar/sensor/cfar.hpp"
#include "radar/sensor/noise.hpp"
#include "radar/sensor/range_doppler.hpp"

namespace radar_emu::radar {

/// SensorConfig::return_floor_db at or below which no return is left out (every return kept).
inline constexpr double kReturnFloorOff_db = -400.0;

struct SensorConfig {
  ProcessingConfig processing;  ///< waveform, windows, direct-path support
  AntennaConfig antenna;
  double tx_power_w = 20.0;    ///< peak
  double noise_figure = 3.16;  ///< linear
  double system_losses = 2.0;  ///< linear, >= 1
  CfarConfig cfar;
  double min_snr_db = 0.0;  ///< detections must also measure at least this SNR
  std::size_t max_detections = 64;
  bool thermal_noise = true;
  std::uint64_t noise_seed = 20261123;
  double beam_floor_db = -40.0;  ///< two-way sum gain below which a beam ignores a return
  /// A return whose largest cell in a beam's image would hold less than this power, relative to
  /// the receiver noise power of a cell (the image's unit), is left out of that beam's image,
  /// and counted (SensorStats::returns_below_floor). The bound used is the on-grid peak,
  /// |a|^2 G_p (RangeDopplerProcessor::processing_gain(), which no off-grid or Doppler-shifted
  /// response exceeds) times the beam's two-way power gain: a return left out had at most this
  /// fraction of a cell's noise power in any cell, so its amplitude was at most sqrt(floor) of
  /// the noise's (-60 dB: 1e-3, moving a cell at the noise level by 0.009 dB at most). Applied
  /// with thermal noise only (without it there is no noise to measure against);
  /// kReturnFloorOff_db or below: off. A coherent return under the floor at the patterns'
  /// largest gains (in every beam, whatever its angles) is left out before the merge
  /// (merge_step_bins), counted once (SensorStats::returns_under_floor): a merged cell sums the
  /// returns over the floor only. The ones a cell left out summed to at most -35 dB of a cell's
  /// noise (at those gains) over the default and the terrain approaches, 200 frames each
  /// (docs/performance.md), which moves a cell at the noise level by 0.15 dB at most.
  double return_floor_db = -60.0;
  double max_range_m = 6000.0;  ///< farthest return of interest: sets the range-ambiguity flag
  std::size_t max_hits_per_beam = 4096;
  std::size_t max_contributions = 1u << 18;  ///< per frame; beyond it returns are counted, dropped
  /// Synthesise receiver noise in every cell of every beam instead of drawing the noise-only
  /// cells' false alarms (reference mode: slower, same distributions).
  bool synthesise_every_cell = false;
  /// Coherent returns of one object closer than this in range and in velocity [bins] (and
  /// merge_step_beamwidths in angle) are summed into one before synthesis; 0: off. The default is
  /// the direct path's own table step (1/64 bin: its interpolation error is below 1e-3).
  double merge_step_bins = 1.0 / 64.0;
  double merge_step_beamwidths = 1.0 / 64.0;  ///< of the sum beam's 3 dB widths
};

/// Detection::object_id when no scene object's return dominates the cell (clutter or noise).
inline constexpr std::uint32_t kNoObject = 0xFFFFFFFFu;

/// One detection in SI units, antenna frame.
struct Detection {
  double range_m = 0.0;
  double azimuth_rad = 0.0;
  double elevation_rad = 0.0;
  double radial_velocity_mps = 0.0;  ///< positive receding, folded into [-v_ua, v_ua)
  double snr = 0.0;                  ///< measured, linear
  double rcs_m2 = 0.0;               ///< from the radar equation at the measured range and angle
  double range_std_m = 0.0;          ///< one-sigma thermal-noise accuracy
  double velocity_std_mps = 0.0;
  double azimuth_std_rad = 0.0;
  double elevation_std_rad = 0.0;
  bool range_ambiguous = false;     ///< the waveform folds ranges shorter than max_range_m
  bool velocity_ambiguous = false;  ///< |v| may exceed v_ua: the velocity may be folded
  std::uint32_t range_cell = 0;
  std::uint32_t doppler_cell = 0;
  std::uint32_t azimuth_cell = 0;  ///< beam position
  /// Ground truth: the scene object (Contribution::object_id) whose coherent return dominates
  /// the detection's cell, or kNoObject when clutter or receiver noise dominates.
  std::uint32_t object_id = kNoObject;
};

struct SensorStats {
  std::uint64_t cells_touched = 0;      ///< image cells covered (beams x range x velocity)
  std::uint64_t cells_synthesised = 0;  ///< of those, synthesised (returns and CFAR margins)
  std::uint64_t cfar_crossings = 0;
  std::uint64_t detections = 0;
  std::uint64_t truncated = 0;        ///< detections beyond max_detections or the output span
  std::uint64_t out_of_grid = 0;      ///< contributions outside every beam or outside the swath
  std::uint64_t hits_overflowed = 0;  ///< CFAR crossings beyond max_hits_per_beam
  std::uint64_t merged = 0;           ///< peaks merged into a stronger one in an adjacent beam
  std::uint64_t rejected_input = 0;   ///< contributions with non-finite fields
  std::uint64_t dropped_input = 0;    ///< contributions beyond max_contributions
  std::uint64_t merged_returns = 0;   ///< coherent returns summed into another (merge_step_bins)
  /// (return, beam) pairs, over the beams of the return's span, left out of the beam's image: the
  /// return's bound there (or in every beam) was below
  /// SensorConfig::return_floor_db
  std::uint64_t returns_below_floor = 0;
  /// Coherent returns left out before the merge: under SensorConfig::return_floor_db in every
  /// cell of every beam at the patterns' largest gains, whatever their angles
  std::uint64_t returns_under_floor = 0;
};

/// One return of a captured frame as the sensor saw it (after merging): what the frame's raw
/// samples are synthesised from (Sensor::synthesise_raw).
struct CapturedReturn {
  std::complex<double> amplitude{0.0, 0.0};  ///< at the receiver, noise units, before patterns
  double range_m = 0.0;
  double radial_velocity_mps = 0.0;
  double azimuth_rad = 0.0;
  double sum_el = 0.0, delta_el = 0.0;  ///< elevation pattern factors (sum, difference)
  double half_bins = 0.0;               ///< diffuse: half its extent along range [bins]
  bool coherent = true;
};

/// The shape of a captured frame's cubes.
struct CaptureShape {
  std::size_t beams = 0;
  std::size_t channels = 0;  ///< raw: Sigma, Delta-az, Delta-el (Sigma alone without monopulse)
  std::size_t pulses = 0;
  std::size_t fast_samples = 0;  ///< raw samples a pulse
  std::size_t velocity_bins = 0;
  std::size_t range_bins = 0;
  [[nodiscard]] std::size_t raw_values() const noexcept {
    return beams * channels * pulses * fast_samples;
  }
  [[nodiscard]] std::size_t image_values() const noexcept {
    return beams * velocity_bins * range_bins;
  }
};

/// Caller-provided storage for one captured frame (Sensor::capture_next), sized at setup from
/// Sensor::capture_shape(). process() fills it without allocating: the image cells it
/// synthesised, the false alarms it drew for the others, and the frame's returns. The rest
/// (every other cell of the image, the raw samples) is completed off the frame path by
/// Sensor::complete_image and Sensor::synthesise_raw.
struct SensorCapture {
  std::span<std::complex<float>> image;  ///< [beam][velocity bin][range bin], image_values()
  std::span<float> power;                ///< same shape: |cell|^2 of the synthesised cells
  std::span<RowSpan> synthesised;        ///< [beam][velocity bin]: the cells synthesised
  /// [beam][k]: room for the false alarms drawn in each beam, k = false_alarms.size() / beams
  std::span<FalseAlarm> false_alarms;
  std::span<std::uint32_t> false_alarm_count;  ///< [beam]: how many (filled by process())
  std::span<CapturedReturn> returns;           ///< room for the frame's returns
  // Filled by process():
  std::size_t return_count = 0;
  std::uint64_t dropped = 0;      ///< returns and false alarms that found no room (counted)
  std::uint64_t noise_frame = 0;  ///< the sensor's frame counter: the key of its noise streams
  bool filled = false;
};

class Sensor {
 public:
  /// Setup: validates (throws std::invalid_argument naming the field), plans and allocates.
  explicit Sensor(const SensorConfig& config);
  ~Sensor();

  /// Processes one frame. Writes detections sorted by SNR (descending) into `out`; returns how
  /// many. `stats` is added to, not reset. Real-time safe: no allocation, no exceptions.
  [[nodiscard]] std::size_t process(std::span<const Contribution> contributions,
                                    std::span<Detection> out, SensorStats& stats) noexcept;

  /// Capture: the next process() call (one frame) also fills `capture` (nullptr: none). The
  /// storage must match capture_shape() (process() skips a capture that does not) and stay
  /// valid until that call returns. Real-time safe.
  void capture_next(SensorCapture* capture) noexcept { capture_ = capture; }
  /// The frame counter that keys the noise streams (one more each process()). Setup: set back
  /// after a frame processed only to learn its cost, so the run draws what it would have drawn.
  [[nodiscard]] std::uint64_t noise_frame() const noexcept { return frame_; }
  void set_noise_frame(std::uint64_t frame) noexcept { frame_ = frame; }
  [[nodiscard]] CaptureShape capture_shape() const noexcept;
  /// After process() filled `capture`: every image cell as the CFAR saw it. The synthesised
  /// cells keep their value (where no return added signal, the phase is the one the sensor
  /// gives a detection there); every other cell gets receiver noise drawn for the file, and the
  /// false alarms the sensor drew there (with their neighbours) get the powers it drew.
  /// Thread-safe against process() (reads setup state only); no allocation.
  void complete_image(SensorCapture& capture) const noexcept;
  /// What synthesise_raw() works in: one synthesiser and scratch per thread it uses.
  struct RawWorkspace {
    std::vector<std::unique_ptr<RangeDopplerProcessor::RawSynthesiser>> synthesisers;
    std::vector<std::complex<double>> scratch;  ///< FMCW: fast + slow values per thread
  };
  /// Setup for synthesise_raw(): allocates and plans (throws on failure) for at most
  /// `max_threads` threads (and no more than TBB may run, 4, or the beams).
  [[nodiscard]] std::unique_ptr<RawWorkspace> make_raw_workspace(std::size_t max_threads = 4) const;
  /// The raw samples of the frame `capture` holds: [beam][channel][pulse][fast sample]
  /// (capture_shape().raw_values()), in units of the receiver noise's standard deviation of one
  /// fast-time sample. Every return with its beam's channel gains (pulsed LFM: through
  /// RangeDopplerProcessor::RawSynthesiser, delays to 1/8 sample; FMCW: sample by sample,
  /// RangeDopplerProcessor::echo); a diffuse return as up to 4 points across its range extent
  /// with complex Gaussian amplitudes; plus receiver noise of unit variance, drawn for the file.
  /// Thread-safe against process(); no allocation.
  void synthesise_raw(const SensorCapture& capture, std::span<std::complex<float>> raw,
                      RawWorkspace& workspace) const noexcept;
  [[nodiscard]] const SensorConfig& config() const noexcept { return config_; }
  [[nodiscard]] const Antenna& antenna() const noexcept { return antenna_; }
  [[nodiscard]] const RangeDopplerProcessor& processor() const noexcept { return *processor_; }
  [[nodiscard]] std::size_t cfar_training_cells() const noexcept;
  [[nodiscard]] double range_cell_m() const noexcept;
  [[nodiscard]] double doppler_cell_mps() const noexcept;
  [[nodiscard]] double unambiguous_velocity_mps() const noexcept;
  [[nodiscard]] double unambiguous_range_m() const noexcept;
  /// Thermal noise power k T0 F fs of one fast-time sample [W].
  [[nodiscard]] double noise_power_w() const noexcept;
  /// Received power of a point target on the sum beam's boresight (radar equation) [W].
  [[nodiscard]] double received_power_w(double rcs_m2, double range_m) const noexcept;
  /// SNR in the range-velocity image of an on-grid point target on boresight.
  [[nodiscard]] double expected_snr(double rcs_m2, double range_m) const noexcept;
  /// Two-way sum gain relative to boresight of a return at (az, el) off a beam's boresight.
  [[nodiscard]] double two_way_gain(double az_off_rad, double el_off_rad) const noexcept;

 private:
  struct Workspace;
  /// A contribution as this frame sees it: computed once, shared by the beams.
  struct Item {
    std::complex<double> amplitude;  ///< at the receiver, noise units, before the patterns
    ImagePosition pos;
    double half_bins = 0.0;  ///< diffuse: half the footprint's extent along range [bins]
    double range_m = 0.0;
    double radial_velocity_mps = 0.0;
    double azimuth_rad = 0.0, elevation_rad = 0.0;
    double sum_el = 0.0, delta_el = 0.0;  ///< elevation channels (one beam elevation per scan)
    std::uint32_t object_id = 0;
    bool coherent = true;
  };
  /// Per item, this frame: whether it is usable (its Item written) or why not.
  enum ItemState : std::uint8_t {
    kUsable = 0,
    kNotFinite = 1,   ///< a field not finite, or no range
    kOffImage = 2,    ///< outside the swath
    kMerged = 3,      ///< summed into an earlier coherent return (merge_returns())
    kUnderFloor = 4,  ///< coherent, under the floor in every beam at any angle (prepare)
  };
  std::vector<std::uint8_t> item_state_;
  struct Candidate {
    std::complex<double> sum{0.0, 0.0};  ///< Sigma channel at the cell (signal + clutter + noise)
    double power = 0, noise = 0;
    std::uint32_t beam = 0, range_bin = 0, velocity_bin = 0;
    double delta_r = 0, delta_v = 0;  ///< interpolated offsets [bins]
  };
  struct Gains {
    double sum = 0, daz = 0, del = 0;  ///< two-way amplitude factors of the three channels
  };
  bool gains_of(const Item& item, std::size_t beam, Gains& g) const noexcept;
  bool gains_at(double azimuth_rad, double sum_el, double delta_el, std::size_t beam,
                Gains& g) const noexcept;
  /// Capture: copies beam `beam`'s synthesised cells and false alarms (detect_beam).
  void capture_beam(std::size_t beam, const Workspace& ws, std::size_t n_alarms) noexcept;

  /// Sums coherent returns that share a merge cell (SensorConfig::merge_step_bins), and writes
  /// the Item of each cell's representative.
  void merge_returns(std::span<const Contribution> contributions, SensorStats& stats) noexcept;
  /// merge_returns()'s last step for the cell whose representative is item `representative`:
  /// writes its item.
  void finish_merged(std::span<const Contribution> contributions,
                     std::uint32_t representative) noexcept;
  struct MergeKey {
    std::uint32_t object_id = 0;
    long long range = 0, velocity = 0, azimuth = 0, elevation = 0;
    bool operator==(const MergeKey&) const = default;
  };
  struct MergeSums {  ///< amplitude-weighted sums of a merge cell's positions
    double weight = 0, range_bin = 0, velocity_bin = 0, range_m = 0, velocity_mps = 0;
    double azimuth_rad = 0, elevation_rad = 0;
    std::uint32_t count = 0;
  };
  /// The merge's parts (merge_returns(): merged independently, in parallel).
  static constexpr std::size_t kMergeParts = 8;
  /// Open addressing, a region of 2 n + 2 entries for each part of n coherent returns: 0 empty,
  /// else (the key hash's upper 32 bits << 32) | (item index + 1).
  std::vector<std::uint64_t> merge_table_;
  std::vector<std::uint32_t> merge_used_;   ///< each part's representatives this frame, in order
  std::vector<std::uint32_t> merge_order_;  ///< the coherent returns by part, in input order
  std::vector<std::uint8_t> merge_part_;    ///< per coherent return: its part (its object's)
  std::vector<MergeKey> merge_keys_;        ///< per usable coherent item
  std::vector<std::uint64_t> merge_hash_;   ///< ... its key's hash
  std::vector<std::uint8_t> merge_hashed_;  ///< per item: 1 when it has a key (usable, coherent)
  std::vector<MergeSums> merge_sums_;       ///< ... its own weighted position, then its cell's
  /// ... its amplitude, then its cell's (the coherent items' Items are written after the merge,
  /// for the representatives only)
  std::vector<std::complex<double>> merge_amplitude_;
  /// The merge cells a unit (setup): 1 / merge_step_bins, and per radian of azimuth and of
  /// elevation, 1 / (merge_step_beamwidths x the sum beam's width).
  double merge_per_bin_ = 0.0, merge_per_rad_az_ = 0.0, merge_per_rad_el_ = 0.0;
  /// Item i's merge key, hash, weighted position and amplitude (prepare step, in parallel), from
  /// its contribution, its image position and its amplitude at the receiver.
  void merge_key(std::size_t i, const Contribution& c, const ImagePosition& pos,
                 std::complex<double> amplitude) noexcept;
  /// Worker w: accumulates every item into its beams (the w-th of the contiguous blocks of
  /// worker_beams_), then detects in them.
  void process_worker(std::size_t w) noexcept;
  void detect_beam(std::size_t beam, Workspace& ws) noexcept;
  /// Share of a diffuse item's power in range bin l, and its velocity-leakage weight in bin j.
  [[nodiscard]] double range_share(const Item& item, long l) const noexcept;
  [[nodiscard]] double velocity_weight(const Item& item, long j) const noexcept;
  /// At a detection's cell: the monopulse ratios (the difference channels drawn jointly with the
  /// sum; 0 without monopulse) and the object whose coherent return dominates (kNoObject when
  /// clutter or noise is stronger).
  void cell_channels(const Candidate& c, double& az_ratio, double& el_ratio,
                     std::uint32_t& object_id) const noexcept;

  SensorConfig config_;
  Antenna antenna_;
  std::unique_ptr<RangeDopplerProcessor> processor_;  ///< const after setup: shared by workers
  std::vector<std::unique_ptr<Workspace>> workspaces_;
  std::vector<Item> items_;  ///< this frame's contributions
  /// Per item: the beams [first, end) of the whole scan whose azimuth extent holds it (every
  /// beam when the beams do not ascend; none when the item is not usable), so that a worker
  /// skips the items outside its beams without reading them.
  struct BeamSpan {
    std::uint32_t first = 0, end = 0;
  };
  std::vector<BeamSpan> item_beams_;
  /// Per usable item: the most power any cell of any beam's image can get from it (a coherent
  /// return: |a|^2 G_p (max_sum_az_ sum_el)^4, the two-way sum gain at most; a diffuse one:
  /// infinity, judged per beam), so that a worker leaves out a return under the floor in every
  /// beam without reading its item.
  std::vector<double> item_bound_;
  double max_sum_az_ = 1.0;  ///< the azimuth sum pattern's largest value (setup, sampled)
  /// return_floor_ / (G_p (max_sum_az_ max_sum_el)^4), max_sum_el the elevation sum pattern's
  /// largest value (setup, sampled): a coherent return with |a|^2 below it
  /// (a at the receiver, noise units) is under the floor in every cell of every beam, whatever
  /// its angles (0: the floor off).
  double floor_norm_ = 0.0;
  /// item_bound_ for item `it` (its amplitude and elevation channel set).
  [[nodiscard]] double bound_of(const Item& it) const noexcept;
  /// Item i's beam span from its azimuth (usable items).
  [[nodiscard]] BeamSpan beam_span(const Item& item) const noexcept;
  std::vector<std::uint32_t> item_bucket_;  ///< per item: its nearest range bin, or ~0 (unusable)
  /// item_bucket_ as written with the item (prepare, finish_merged): the bin, this bit set for
  /// a diffuse return; process() clears it.
  static constexpr std::uint32_t kDiffuseBucket = 0x80000000u;
  /// Item `it`'s bucket: its nearest range bin, clamped to the image.
  [[nodiscard]] std::uint32_t bucket_of(const Item& it) const noexcept;
  std::vector<std::uint32_t> by_range_;  ///< item indices sorted by nearest range bin
  /// The usable items whose span holds a beam, in input order (the workers' list: most returns
  /// are merged or under the floor, and are not walked), and their number this frame.
  std::vector<std::uint32_t> live_items_;
  std::size_t live_count_ = 0;
  std::vector<std::uint32_t> range_start_;  ///< by_range_ offset of each range bin (+1 entry)
  std::size_t item_count_ = 0;
  double max_half_bins_ = 0.0;
  std::vector<Candidate> candidates_;    ///< all beams, after in-beam grouping
  std::vector<std::size_t> beam_first_;  ///< per beam: first slot in candidates_
  std::vector<std::size_t> beam_count_;  ///< per beam: candidates found
  std::vector<std::uint32_t> order_;     ///< candidate indices by SNR
  std::vector<double> kept_power_;       ///< per output detection: its peak power
  std::size_t per_beam_capacity_ = 0;
  double amplitude_scale_ = 0.0;  ///< sqrt(Pt G^2 lambda^2 / ((4 pi)^3 L) / (k T0 F fs))
  double az_extent_rad_ = 0.0;
  double gain_floor_ = 0.0;  ///< beam_floor_db as a linear two-way power ratio
  /// return_floor_db as a power in noise units; 0 when off (or without thermal noise)
  double return_floor_ = 0.0;
  std::size_t n_workers_ = 1;
  /// Per worker: a coherent return's response cells at unit gain, [velocity row][range bin].
  static constexpr std::size_t kFootprintCells =
      static_cast<std::size_t>(Footprint::kMaxBins) * Footprint::kMaxBins;
  std::vector<std::complex<double>> footprint_cells_;
  /// Worker w takes beams [worker_beams_[w], worker_beams_[w + 1]) (split_beams(), per frame).
  std::vector<std::size_t> worker_beams_;
  /// Per beam, this frame's work estimate (a difference array while the items are counted).
  std::vector<double> beam_work_;
  /// The work model of split_beams(), in units of a coherent return's work in one beam: a
  /// diffuse return's (its map rows, and the cells it makes the beam synthesise and test), a
  /// beam's own (its noise-only cells' false alarms, its CFAR bookkeeping), and a coherent
  /// return's under the floor in every beam (its span and bound read, its item not). From the
  /// profile of BM_SensorLoopFrame (coherent only and diffuse only); the last from the two
  /// workers' balance on its default and terrain frames (0.05 made the default's sensor 8 %
  /// slower, 0.25 neither). Only the split depends on them.
  static constexpr double kCoherentWork = 1.0, kDiffuseWork = 2.5, kBeamWork = 200.0,
                          kSkippedWork = 0.25;
  /// Splits the beams into the workers' contiguous blocks of about equal work (beam_work_).
  void split_beams() noexcept;
  /// The scan's beam azimuths ascend: a return's beams are found by bisection, not by testing
  /// every beam.
  bool beams_ascending_ = false;
  /// Gaussian azimuth pattern on evenly spaced beams: a return's sum-channel gains across beams
  /// by a recurrence (AzRecurrence in sensor.cpp) instead of two `exp` a beam.
  struct AzRecurrence {
    bool on = false;
    double c = 0.0;       ///< 2 ln 2 / theta3^2 [1/rad^2]: E(t) = exp(-c t^2)
    double squint = 0.0;  ///< d [rad] (0 without monopulse: one component beam)
    double step = 0.0;    ///< beam spacing Delta [rad]
    double norm = 1.0;    ///< the sum channel's 1 / (2 E(d)), or 1 without monopulse
    double q = 1.0;       ///< exp(-2 c Delta^2): the step ratio's own ratio
    double k = 1.0;       ///< exp(4 c Delta d): the step ratio of E(t + d) over that of E(t - d)
  } az_rec_;
  double range_energy_ = 1.0;
  ExponentialZiggurat exp_ziggurat_;  ///< the noise-only cells' exponential variates
  std::uint64_t frame_ = 0;
  SensorCapture* capture_ = nullptr;            ///< armed by capture_next() for one process() call
  bool capturing_ = false;                      ///< this frame fills capture_
  std::vector<std::uint64_t> capture_dropped_;  ///< per beam: false alarms without room
};

}  // namespace radar_emu::radar
