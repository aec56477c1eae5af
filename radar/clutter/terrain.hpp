#pragma once
// The terrain material catalogue and sigma0 per (material, frequency, polarisation, angle):
// physical parameters with their sources, the empirical curves where published coefficients
// exist, the model choice, and the table built once at setup that the frame path interpolates.
// Pure computation; every value's source is named beside it in terrain.cpp, and the values we
// had to assume are marked "assumed" there and in docs/validation.md.

#include <array>
#include <complex>
#include <cstdint>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "radar/clutter/surface.hpp"

namespace radar_emu::radar::clutter {

enum class PermittivityModel : std::uint8_t {
  kFixed,     ///< one measured value, used at every frequency (flagged outside its band)
  kWater,     ///< ITU-R P.840-9 double-Debye water at 15 C
  kSoil,      ///< Dobson et al. (1985) mixing model with P.840 free water
  kDrySnow,   ///< Matzler's dry-snow formula (Ulaby & Long 2014, sec. 4-6)
  kConductor  ///< perfect conductor: specular only (the SBR engine handles it)
};

/// Ulaby & Dobson (1989) handbook classes with published regression coefficients.
enum class EmpiricalClass : std::uint8_t {
  kNone,
  kSoil,
  kGrass,
  kShortVegetation,
  kShrubs,
  kDrySnow,
  kWetSnow
};

/// The measured-data curve of the catalogue (sigma0_catalogue.cpp): which published rows and
/// points a material's sigma0(incidence, frequency, polarisation) is founded on.
enum class CatalogueCurve : std::uint8_t {
  kNone,  ///< no diffuse sigma0 (the conductor)
  kAsphalt,
  kConcrete,
  kGrass,  ///< mown grass
  kTallGrass,
  kCrops,
  kForest,
  kSoilDry,
  kSoilWet,
  kGravel,
  kSnowDry,
  kSnowWet,
  kUrban,
  kWater  ///< NRL sea-clutter model at TerrainMaterial::sea_state
};

struct TerrainMaterial {
  std::string_view name;
  std::string_view description;
  PermittivityModel permittivity_model = PermittivityModel::kFixed;
  std::complex<double> fixed_permittivity{1.0, 0.0};  ///< kFixed (eps' - j eps'')
  double moisture = 0.0;                              ///< kSoil: volumetric moisture m_v [m^3/m^3]
  double snow_density_gcm3 = 0.0;                     ///< kDrySnow
  std::string_view permittivity_source;
  Roughness roughness;
  std::string_view roughness_source;
  bool has_volume = false;
  VolumeLayer volume;                        ///< extinction: see volume_extinction_np_per_m()
  bool canopy_extinction_from_p833 = false;  ///< extinction = P.833 woodland gamma
  std::string_view volume_source;
  EmpiricalClass empirical = EmpiricalClass::kNone;
  CatalogueCurve curve = CatalogueCurve::kNone;  ///< the measured-data sigma0 curve
  double sea_state = 0.0;                        ///< kWater: Douglas sea state 0-6 (NRL model)
};

[[nodiscard]] std::span<const TerrainMaterial> terrain_catalogue() noexcept;
/// nullptr when unknown.
[[nodiscard]] const TerrainMaterial* find_terrain_material(std::string_view name) noexcept;
/// "asphalt, concrete, ..." for error messages and --help.
[[nodiscard]] std::string terrain_material_names();
/// The material named `name`; throws std::invalid_argument "unknown terrain material 'x'
/// (known: asphalt, ...)" otherwise. Setup only.
[[nodiscard]] const TerrainMaterial& terrain_material(std::string_view name);

/// Relative permittivity of the material at `freq_hz` (eps' - j eps''). Throws
/// std::invalid_argument for a conductor.
[[nodiscard]] std::complex<double> permittivity(const TerrainMaterial& m, double freq_hz);
/// Extinction of the material's volume layer at `freq_hz` [Np/m].
[[nodiscard]] double volume_extinction_np_per_m(const TerrainMaterial& m, double freq_hz);

/// kTotal: the model the images use: the measured-data catalogue in backscatter (a material
/// with a CatalogueCurve), the physical models (kPhysical) bistatic or for a custom surface.
/// kPhysical: IEM surface + first-order RT volume (the physics of surface.hpp, no data).
/// kEmpirical: the raw Ulaby-Dobson L/S/C rows only.
enum class Sigma0Model : std::uint8_t {
  kEmpirical,
  kIem,
  kSpm,
  kKirchhoff,
  kRt,
  kTotal,
  kPhysical
};
[[nodiscard]] const char* to_string(Sigma0Model m) noexcept;
/// Parses empirical|iem|spm|ka|rt|total|physical; throws std::invalid_argument otherwise.
[[nodiscard]] Sigma0Model parse_sigma0_model(std::string_view text);

/// Ulaby & Dobson regression sigma0(dB) = P1 + P2 exp(-P3 t) + P4 cos(P5 t + P6), t the
/// incidence angle [rad]. nullopt when no published row covers (class, band, polarisation).
struct EmpiricalRow {
  double p[6];
};
[[nodiscard]] std::optional<EmpiricalRow> empirical_row(EmpiricalClass c, double freq_hz,
                                                        int pol /*0 hh 1 vv 2 hv*/) noexcept;
[[nodiscard]] double empirical_sigma0_db(const EmpiricalRow& row, double theta_rad) noexcept;

// ---- The measured-data catalogue (sigma0_catalogue.cpp; sources in docs/validation.md) ------
//
// sigma0 of each material against incidence 0-90 deg, HH, VV and cross-pol, continuous in
// frequency 1-100 GHz: per material a few anchor curves (published regression rows, published
// near-grazing points, and, where nothing was found, assumed rows marked as such), each a
// Ulaby-Dobson row up to 70 deg continued to grazing by a cos^p tail through a near-grazing
// point; anchors interpolated linearly in dB against log frequency, held flat outside the
// first and last anchor. Water: the NRL sea-clutter model. Validity bits (surface.hpp):
// kOutsideMeasuredRange where the value is extrapolated beyond its source's angles or
// frequencies, kAssumedValue where it rests on an assumed anchor.

enum class Sigma0Pol : std::uint8_t { kHH = 0, kVV = 1, kHV = 2, kVH = 3 };

struct Sigma0Value {
  double linear = 0.0;      ///< sigma0 [m^2/m^2]
  std::uint32_t flags = 0;  ///< kOutsideMeasuredRange | kAssumedValue (surface.hpp), 0: measured
};

/// sigma0 of catalogue material `m` (backscatter) at `freq_hz` (any > 0; values are held
/// flat outside 1-100 GHz and flagged), `pol`, incidence `theta_rad` in [0, pi/2] (clamped).
/// A conductor (CatalogueCurve::kNone) gives 0. Real-time safe (no allocation, no throw), but
/// meant for setup: the frame path reads Sigma0Table.
[[nodiscard]] Sigma0Value sigma0(const TerrainMaterial& m, double freq_hz, Sigma0Pol pol,
                                 double theta_rad) noexcept;
/// By name: throws std::invalid_argument naming the known materials for an unknown one.
[[nodiscard]] Sigma0Value sigma0(std::string_view material, double freq_hz, Sigma0Pol pol,
                                 double theta_rad);
/// The catalogue curve alone (what sigma0() evaluates for a material).
[[nodiscard]] Sigma0Value catalogue_sigma0(CatalogueCurve c, double sea_state, double freq_hz,
                                           Sigma0Pol pol, double theta_rad) noexcept;
/// NRL sea clutter (Gregers-Hansen & Mital 2012, NRL/MR/5310-12-9346, eq. (7), Table 1) in dB
/// at grazing angle 90 deg - theta, continued to nadir by a quasi-specular lobe (see .cpp);
/// HH or VV (cross-pol: assumed offset). `sea_state` 0-6.
[[nodiscard]] Sigma0Value sea_sigma0(double freq_hz, Sigma0Pol pol, double theta_rad,
                                     double sea_state) noexcept;

/// Everything the models need about a surface at one frequency, resolved at setup.
struct SurfaceSpec {
  SurfaceParams surface;
  bool has_volume = false;
  VolumeLayer volume;
  EmpiricalClass empirical = EmpiricalClass::kNone;
  CatalogueCurve curve = CatalogueCurve::kNone;  ///< kTotal backscatter reads this curve
  double sea_state = 0.0;
  bool conductor = false;
};
/// Resolve a catalogue material at `freq_hz` (throws for unknown ranges with a one-line reason).
[[nodiscard]] SurfaceSpec resolve_surface(const TerrainMaterial& m, double freq_hz);

/// sigma0 of `spec` under `model` (linear; `invalid` as in surface.hpp, plus kEmpiricalOutside
/// when the empirical curve has no row there, and for kTotal from the catalogue the OR of the
/// four polarisations' kOutsideMeasuredRange / kAssumedValue). Setup and offline use.
/// `cross_pol_backscatter` as in iem().
inline constexpr std::uint32_t kEmpiricalOutside = 1u << 9;
[[nodiscard]] SurfaceScatter evaluate_sigma0(const SurfaceSpec& spec, Sigma0Model model,
                                             double freq_hz, const Geometry& g,
                                             bool cross_pol_backscatter = true);

/// sigma0 per (material, polarisation) against incidence angle, sampled every 0.05 deg over
/// 0-90 deg at setup; lookup() interpolates linearly (real-time safe, no allocation).
class Sigma0Table {
 public:
  enum Pol : std::uint8_t { kHH = 0, kVV = 1, kHV = 2, kVH = 3 };
  static constexpr int kSamples = 1801;

  Sigma0Table() = default;
  /// One row per spec (conductors: zero diffuse clutter).
  Sigma0Table(std::span<const SurfaceSpec> specs, Sigma0Model model, double freq_hz);

  [[nodiscard]] std::size_t materials() const noexcept { return values_.size() / (4 * kSamples); }
  /// Linear sigma0 of material `index` for incidence cos(theta) in [0, 1]; out-of-range index
  /// or non-finite input gives 0.
  [[nodiscard]] float lookup(std::size_t index, Pol pol, double cos_incidence) const noexcept;
  /// lookup() and, in `flags`, lookup_flags() of the same samples (one acos). Real-time safe.
  [[nodiscard]] float lookup(std::size_t index, Pol pol, double cos_incidence,
                             std::uint32_t& flags) const noexcept;
  /// Validity bits of the two samples lookup() interpolates (OR); 0 for bad input. Real-time
  /// safe. For images: kOutsideMeasuredRange / kAssumedValue mark catalogue values that are
  /// extrapolated or assumed (surface.hpp).
  [[nodiscard]] std::uint32_t lookup_flags(std::size_t index, Pol pol,
                                           double cos_incidence) const noexcept;
  /// OR of the validity bits over all angles of material `index`, polarisation `pol`.
  [[nodiscard]] std::uint32_t row_flags(std::size_t index, Pol pol) const noexcept;

 private:
  std::vector<float> values_;
  std::vector<std::uint32_t> flags_;
};

/// Where a product's terrain read sigma0 values the catalogue flags (issue 28: outside a
/// physical model's validity, extrapolated or assumed; the bits of surface.hpp): per sigma0 row
/// (material) of a Sigma0Table, what the product's patches read. The core fills it, the tools
/// report it (sigma0_use_lines()). Plain counters: add() and merge() are real-time safe.
struct Sigma0Use {
  std::uint64_t patches = 0;          ///< patches (lit, added to the product) of this row
  std::uint64_t flagged_patches = 0;  ///< of those, the ones whose sample carried a flag
  std::uint32_t flags = 0;            ///< OR of the flags of the samples read
  double power_m2 = 0.0;              ///< mean power of the row's patches [m^2]
  double flagged_power_m2 = 0.0;      ///< of the flagged ones [m^2]
  /// Incidence span of the flagged patches [rad] (min > max: none).
  double flagged_incidence_min_rad = 10.0;
  double flagged_incidence_max_rad = -10.0;
  /// One patch of mean power `power_m2` at incidence cos theta = `cos_incidence` whose sample
  /// carried `flags` (Sigma0Table::lookup_flags).
  void add(std::uint32_t sample_flags, double cos_incidence, double patch_power_m2) noexcept;
  void merge(const Sigma0Use& other) noexcept;
};

/// The rows of `use` that read flagged values, one line each, e.g. "water at 35 GHz, 2-28 deg
/// incidence: catalogue: extrapolated beyond ... (12.5 % of the terrain's patches, 3.1 % of its
/// power)"; `names` per row (a missing name: "row N"). Empty when nothing was flagged. Setup and
/// reporting only (allocates).
[[nodiscard]] std::vector<std::string> sigma0_use_lines(std::span<const Sigma0Use> use,
                                                        std::span<const std::string> names,
                                                        double carrier_hz);
/// OR of the flags of every row that read a flagged value (0: none).
[[nodiscard]] std::uint32_t sigma0_use_flags(std::span<const Sigma0Use> use) noexcept;
/// Fractions over all rows: flagged patches / patches and flagged power / power (0 when none).
[[nodiscard]] double sigma0_use_patch_fraction(std::span<const Sigma0Use> use) noexcept;
[[nodiscard]] double sigma0_use_power_fraction(std::span<const Sigma0Use> use) noexcept;

}  // namespace radar_emu::radar::clutter
