#include "radar/clutter/terrain.hpp"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <stdexcept>

#include "common/units.hpp"
#include "radar/constants.hpp"
#include "radar/propagation/itu.hpp"

namespace radar_emu::radar::clutter {

namespace {

using cplx = std::complex<double>;
constexpr double kDbPerNp = 4.342944819032518;  // 10 log10(e): power dB per neper

// The catalogue. Where no published value was found, the value is ours and says "assumed";
// docs/notes/clutter_data_sources.md records what was searched.
const std::array<TerrainMaterial, 15>& catalogue() {
  using P = PermittivityModel;
  using E = EmpiricalClass;
  using C = Correlation;
  using L = VolumeLayer::Placement;
  using K = CatalogueCurve;
  static const std::array<TerrainMaterial, 15> k{{
      {"asphalt",
       "asphalt road surface (aggregate in bitumen)",
       P::kFixed,
       {5.0, -0.09},
       0.0,
       0.0,
       "eps' 5.0: Olkkonen 2016, NDT&E Int. 83 (slab mean 5.01, 7-17 GHz); eps'' 0.09 from the "
       "4 cm penetration depth at 30 GHz of the NCHRP-IDEA asphalt density-sensor study",
       {0.0005, 0.005, C::kExponential, 1.5},
       "assumed: s 0.5 mm, l 5 mm (fine road texture; no measured correlation length found)",
       true,
       {L::kInsideGround, 0.04, 25.0, 0.1},
       false,
       "extinction 25 Np/m from the same 4 cm penetration depth; thickness 4 cm (one "
       "penetration depth); albedo 0.1 assumed",
       E::kNone,
       K::kAsphalt},
      {"concrete",
       "concrete pavement or apron",
       P::kFixed,
       {5.5, -0.5},
       0.0,
       0.0,
       "assumed: eps 5.5 - j0.5 (dry concrete, order of the X-band values reported for highway "
       "pavement; no mm-wave measurement found)",
       {0.0008, 0.008, C::kExponential, 1.5},
       "assumed: s 0.8 mm, l 8 mm (brushed finish)",
       true,
       {L::kInsideGround, 0.03, 30.0, 0.1},
       false,
       "assumed: aggregate inclusions, extinction 30 Np/m, 3 cm, albedo 0.1",
       E::kNone,
       K::kConcrete},
      {"grass",
       "grass 0.3 m over moist soil",
       P::kSoil,
       {1.0, 0.0},
       0.2,
       0.0,
       "ground: Dobson et al. 1985 (m_v 0.2, sand 0.4, clay 0.2) with P.840 free water",
       {0.01, 0.08, C::kExponential, 1.5},
       "ground: s 1 cm, l 8 cm, inside the range of the Oh, Sarabandi & Ulaby 1992 field "
       "surfaces (s 0.3-3 cm)",
       true,
       {L::kCanopyAboveGround, 0.3, 0.0, 0.15},
       true,
       "canopy 0.3 m; extinction = ITU-R P.833 woodland gamma (Figure 2, held at 30 GHz "
       "above); albedo 0.15 assumed",
       E::kGrass,
       K::kGrass},
      {"crops",
       "crops 1 m over moist soil",
       P::kSoil,
       {1.0, 0.0},
       0.2,
       0.0,
       "ground: Dobson et al. 1985 (m_v 0.2)",
       {0.015, 0.1, C::kExponential, 1.5},
       "ground: s 1.5 cm, l 10 cm (Oh et al. 1992 range)",
       true,
       {L::kCanopyAboveGround, 1.0, 0.0, 0.15},
       true,
       "canopy 1 m; extinction = P.833 gamma; albedo 0.15 assumed",
       E::kShortVegetation,
       K::kCrops},
      {"forest",
       "forest canopy 10 m over soil",
       P::kSoil,
       {1.0, 0.0},
       0.25,
       0.0,
       "ground: Dobson et al. 1985 (m_v 0.25)",
       {0.02, 0.15, C::kExponential, 1.5},
       "ground: s 2 cm, l 15 cm (assumed)",
       true,
       {L::kCanopyAboveGround, 10.0, 0.0, 0.2},
       true,
       "canopy 10 m; extinction = P.833 gamma; albedo 0.2 assumed",
       E::kNone,
       K::kForest},
      {"soil_dry",
       "bare dry soil",
       P::kSoil,
       {1.0, 0.0},
       0.05,
       0.0,
       "Dobson et al. 1985 (m_v 0.05, sand 0.4, clay 0.2; fitted 1.4-18 GHz)",
       {0.01, 0.1, C::kExponential, 1.5},
       "s 1 cm, l 10 cm (Oh et al. 1992 range)",
       false,
       {},
       false,
       "",
       E::kSoil,
       K::kSoilDry},
      {"soil_wet",
       "bare wet soil",
       P::kSoil,
       {1.0, 0.0},
       0.30,
       0.0,
       "Dobson et al. 1985 (m_v 0.30)",
       {0.01, 0.1, C::kExponential, 1.5},
       "s 1 cm, l 10 cm (Oh et al. 1992 range)",
       false,
       {},
       false,
       "",
       E::kSoil,
       K::kSoilWet},
      {"water",
       "calm inland water (sea state 1)",
       P::kWater,
       {1.0, 0.0},
       0.0,
       0.0,
       "ITU-R P.840-9 double-Debye water permittivity at 15 C",
       {0.001, 0.02, C::kGaussian, 1.5},
       "assumed: ripples s 1 mm, l 2 cm",
       false,
       {},
       false,
       "",
       E::kNone,
       K::kWater,
       1.0},
      {"gravel",
       "gravel or dry sand",
       P::kFixed,
       {2.53, -0.05},
       0.0,
       0.0,
       "eps' 2.53: Matzler 1998, IEEE TGRS 36(1) (dry sand); eps'' 0.05 assumed",
       {0.003, 0.015, C::kExponential, 1.5},
       "assumed: s 3 mm, l 1.5 cm",
       true,
       {L::kInsideGround, 0.05, 10.0, 0.1},
       false,
       "assumed: grain scattering, extinction 10 Np/m, 5 cm, albedo 0.1",
       E::kNone,
       K::kGravel},
      {"snow",
       "dry snow 0.3 g/cm3 (snow_dry)",
       P::kDrySnow,
       {1.0, 0.0},
       0.0,
       0.3,
       "eps' = 1 + 1.4667 v + 1.435 v^3, v = rho / 0.9167 (Matzler; Ulaby & Long 2014, "
       "sec. 4-6); eps'' 0.001 assumed",
       {0.003, 0.03, C::kExponential, 1.5},
       "assumed: s 3 mm, l 3 cm",
       true,
       {L::kInsideGround, 0.5, 5.0, 0.5},
       false,
       "assumed: grains, extinction 5 Np/m, 0.5 m, albedo 0.5 (snow scatters more than it "
       "absorbs at mm-wave; first order flagged)",
       E::kDrySnow,
       K::kSnowDry},
      {"urban",
       "built-up ground between modelled buildings",
       P::kFixed,
       {5.5, -0.5},
       0.0,
       0.0,
       "assumed: as concrete",
       {0.05, 0.5, C::kExponential, 1.5},
       "assumed: s 5 cm, l 50 cm (kerbs, debris; the buildings themselves are scene geometry)",
       false,
       {},
       false,
       "",
       E::kNone,
       K::kUrban},
      {"tall_grass",
       "tall grass 0.8 m over moist soil",
       P::kSoil,
       {1.0, 0.0},
       0.2,
       0.0,
       "ground: Dobson et al. 1985 (m_v 0.2)",
       {0.015, 0.1, C::kExponential, 1.5},
       "ground: s 1.5 cm, l 10 cm (Oh et al. 1992 range)",
       true,
       {L::kCanopyAboveGround, 0.8, 0.0, 0.15},
       true,
       "canopy 0.8 m; extinction = P.833 gamma; albedo 0.15 assumed",
       E::kShrubs,
       K::kTallGrass},
      {"snow_wet",
       "wet snow",
       P::kFixed,
       {2.0, -0.3},
       0.0,
       0.0,
       "assumed: eps 2.0 - j0.3 (a few per cent liquid water; no value adopted from a source)",
       {0.003, 0.03, C::kExponential, 1.5},
       "assumed: s 3 mm, l 3 cm",
       false,
       {},
       false,
       "",
       E::kWetSnow,
       K::kSnowWet},
      {"sea",
       "open sea, sea state 3",
       P::kWater,
       {1.0, 0.0},
       0.0,
       0.0,
       "ITU-R P.840-9 double-Debye water permittivity at 15 C (fresh water; salinity ignored)",
       {0.01, 0.1, C::kGaussian, 1.5},
       "assumed: s 1 cm, l 10 cm (physical models only; the catalogue uses the NRL model)",
       false,
       {},
       false,
       "",
       E::kNone,
       K::kWater,
       3.0},
      {"metal",
       "metal (perfect conductor)",
       P::kConductor,
       {1.0, 0.0},
       0.0,
       0.0,
       "perfect electric conductor (seed paper: R_perp = -1, R_par = +1)",
       {0.0, 1.0, C::kExponential, 1.5},
       "smooth",
       false,
       {},
       false,
       "",
       E::kNone,
       K::kNone},
  }};
  return k;
}

// Ulaby & Dobson (1989), Handbook of Radar Scattering Statistics for Terrain: regression
// coefficients P1..P6 per class and band, as transcribed in DartsTST.jl, modules/scattering.jl
// (github.com/darts-team/DartsTST.jl, commit 989d2191), the only public transcription found
// (docs/notes/clutter_data_sources.md sec. 2.1). Each row lists (HH, HV, VV). Left out: soil L
// HH (a refit by the transcriber, not the book's row) and shrubs S (mis-copied: +70 dB).
// Only L, S and C bands are available; X, Ku, Ka and W rows were not found.
struct EmpiricalTable {
  EmpiricalClass cls;
  char band;
  double p[6][3];  // p[k][pol], pol 0 HH, 1 HV, 2 VV
  bool hh_ok;
};
constexpr EmpiricalTable kEmpirical[] = {
    {EmpiricalClass::kSoil,
     'L',
     {{2442, -30.2, -94.36},
      {-3.771, 15.261, 99.0},
      {-2.193, 3.56, 0.365},
      {-2442, -0.424, -3.398},
      {0.1711, 0.0, 5.0},
      {-0.07967, 0.0, -1.739}},
     false},
    {EmpiricalClass::kSoil,
     'S',
     {{-91.2, -46.467, -97.016},
      {99.0, 31.788, 99.0},
      {0.433, 2.189, 0.270},
      {5.063, -17.99, -2.056},
      {2.941, 1.34, 5.0},
      {-3.142, 1.583, -1.754}},
     true},
    {EmpiricalClass::kSoil,
     'C',
     {{-24.855, -26.7, -24.951},
      {26.351, 15.055, 28.742},
      {1.146, 1.816, 1.043},
      {0.204, -0.499, -1.681},
      {0, 0, 0},
      {0, 0, 0}},
     true},
    {EmpiricalClass::kGrass,
     'L',
     {{-29.325, -40.166, -28.022},
      {37.55, 26.833, 36.59},
      {2.332, 2.029, 2.53},
      {-2.615, -1.473, -1.53},
      {5.0, 3.738, 5.0},
      {-1.616, -1.324, -1.513}},
     true},
    {EmpiricalClass::kGrass,
     'S',
     {{-20.361, -29.035, -21.198},
      {25.727, 18.055, 26.694},
      {2.979, 2.8, 2.828},
      {-1.13, -1.556, -0.612},
      {5.0, 4.554, 5.0},
      {-1.916, -0.464, -2.079}},
     true},
    {EmpiricalClass::kGrass,
     'C',
     {{-15.75, -23.109, -93.606},
      {17.931, 13.591, 99},
      {2.369, 1.508, 0.22},
      {-1.502, -0.757, -5.509},
      {4.592, 4.491, -2.964},
      {-3.142, -3.142, 1.287}},
     true},
    {EmpiricalClass::kShortVegetation,
     'L',
     {{-27.265, -41.6, -24.614},
      {32.39, 22.872, 27.398},
      {2.133, 0.689, 2.265},
      {1.438, -1.238, -1.080},
      {-3.847, 0.0, 5.0},
      {3.142, 0.0, -1.999}},
     true},
    {EmpiricalClass::kShortVegetation,
     'S',
     {{-20.779, -99.0, -20.367},
      {21.867, 85.852, 21.499},
      {2.434, 0.179, 2.151},
      {0.347, 3.687, -1.069},
      {-0.013, 2.121, 5.0},
      {-0.393, -3.142, -1.95}},
     true},
    {EmpiricalClass::kShortVegetation,
     'C',
     {{-87.727, -99.0, -88.593},
      {99.0, 93.293, 99.0},
      {0.322, 0.181, 0.326},
      {10.188, 5.359, 9.574},
      {-1.747, 1.948, 1.969},
      {3.143, -3.142, -3.142}},
     true},
    {EmpiricalClass::kShrubs,
     'L',
     {{-26.688, -99.0, -81.371},
      {29.454, 99.0, 99.0},
      {1.814, 0.086, 0.567},
      {0.873, -21.298, 16.2},
      {4.135, 0.0, -1.948},
      {-3.142, 0.0, 3.142}},
     true},
    {EmpiricalClass::kShrubs,
     'C',
     {{-91.95, -99.0, -91.133},
      {99.0, 91.003, 99.0},
      {0.270, 0.156, 0.294},
      {6.980, 3.948, 8.107},
      {1.922, 2.239, 2.112},
      {-3.142, -3.142, -3.142}},
     true},
    {EmpiricalClass::kDrySnow,
     'L',
     {{-74.019, -91.341, -77.032},
      {99, 99, 99},
      {1.592, 1.202, 1.415},
      {-30, 30, -30},
      {1.928, 1.790, 1.720},
      {0.905, -2.304, 0.997}},
     true},
    {EmpiricalClass::kDrySnow,
     'S',
     {{-47.055, -54.29, -40.652},
      {30.164, 13.292, 18.826},
      {5.788, 10.0, 9.211},
      {30, -30, 30},
      {1.188, -0.715, 0.690},
      {-0.629, 3.142, 0.214}},
     true},
    {EmpiricalClass::kDrySnow,
     'C',
     {{-42.864, -25.543, -19.765},
      {20.762, 16.64, 19.83},
      {10, 10, 10},
      {30, -2.959, 7.089},
      {0.763, 3.116, 1.54},
      {-0.147, 2.085, -0.012}},
     true},
    {EmpiricalClass::kWetSnow,
     'L',
     {{-73.069, -90.98, -75.156},
      {95.221, 99, 99},
      {1.548, 1.129, 1.446},
      {30, 30, 30},
      {1.795, 1.827, 1.793},
      {-2.126, -2.308, -2.179}},
     true},
    {EmpiricalClass::kWetSnow,
     'S',
     {{-45.772, -42.940, -39.328},
      {25.16, 9.935, 18.594},
      {5.942, 15.0, 8.046},
      {30, 30, 30},
      {0.929, 0.438, 0.666},
      {-0.284, 0.712, 0.269}},
     true},
    {EmpiricalClass::kWetSnow,
     'C',
     {{-31.91, -24.622, 4.288},
      {17.749, 15.102, 15.642},
      {11.854, 15.0, 15.0},
      {30, -3.401, 30},
      {0.421, 2.431, 0.535},
      {0.74, 3.142, 1.994}},
     true},
};

/// IEEE Std 521 letter bands as the handbook uses them: L 1-2, S 2-4, C 4-8 GHz.
char band_of(double freq_hz) {
  const double g = freq_hz * 1e-9;
  if (g >= 1.0 && g < 2.0)
    return 'L';
  if (g >= 2.0 && g < 4.0)
    return 'S';
  if (g >= 4.0 && g <= 8.0)
    return 'C';
  return '?';
}

/// Dobson, Ulaby, Hallikainen & El-Rayes (1985), IEEE TGRS GE-23(1), eqs. (28)-(30): the
/// semi-empirical mixing model eps_m^a = 1 + (rho_b/rho_s)(eps_s^a - 1) + m_v^b eps_fw^a - m_v,
/// a = 0.65, eps_s = (1.01 + 0.44 rho_s)^2 - 0.062, b' = 1.2748 - 0.519 S - 0.152 C,
/// b'' = 1.33797 - 0.603 S - 0.166 C; free water from P.840's double-Debye model at 15 C (the
/// ionic-conductivity term is negligible at mm-wave and left out). Fitted on 1.4-18 GHz.
cplx dobson_soil(double freq_hz, double m_v) {
  constexpr double kSand = 0.4, kClay = 0.2, kRhoB = 1.5, kRhoS = 2.66, kAlpha = 0.65;
  const cplx fw = water_permittivity(freq_hz, 288.15);
  const double eps_s = std::pow(1.01 + 0.44 * kRhoS, 2) - 0.062;
  const double b1 = 1.2748 - 0.519 * kSand - 0.152 * kClay;
  const double b2 = 1.33797 - 0.603 * kSand - 0.166 * kClay;
  const double re = std::pow(1.0 + (kRhoB / kRhoS) * (std::pow(eps_s, kAlpha) - 1.0) +
                                 std::pow(m_v, b1) * std::pow(fw.real(), kAlpha) - m_v,
                             1.0 / kAlpha);
  const double im = std::pow(std::pow(m_v, b2) * std::pow(-fw.imag(), kAlpha), 1.0 / kAlpha);
  return {re, -im};
}

}  // namespace

std::span<const TerrainMaterial> terrain_catalogue() noexcept {
  return catalogue();
}

const TerrainMaterial* find_terrain_material(std::string_view name) noexcept {
  for (const TerrainMaterial& m : catalogue())
    if (m.name == name)
      return &m;
  return nullptr;
}

std::string terrain_material_names() {
  std::string out;
  for (const TerrainMaterial& m : catalogue()) {
    out += out.empty() ? "" : ", ";
    out += m.name;
  }
  return out;
}

cplx permittivity(const TerrainMaterial& m, double freq_hz) {
  switch (m.permittivity_model) {
    case PermittivityModel::kFixed:
      return m.fixed_permittivity;
    case PermittivityModel::kWater:
      return water_permittivity(freq_hz, 288.15);
    case PermittivityModel::kSoil:
      return dobson_soil(freq_hz, m.moisture);
    case PermittivityModel::kDrySnow: {
      const double v = m.snow_density_gcm3 / 0.9167;
      return {1.0 + 1.4667 * v + 1.435 * v * v * v, -0.001};
    }
    case PermittivityModel::kConductor:
      break;
  }
  throw std::invalid_argument("material '" + std::string(m.name) +
                              "' is a conductor: it has no permittivity (specular only)");
}

double volume_extinction_np_per_m(const TerrainMaterial& m, double freq_hz) {
  if (!m.has_volume)
    return 0.0;
  if (m.canopy_extinction_from_p833) {
    const double f = std::clamp(freq_hz, 1e9, 30e9);
    return woodland_specific_attenuation_db_per_m(f, true) / kDbPerNp;
  }
  return m.volume.extinction_np_per_m;
}

const char* to_string(Sigma0Model m) noexcept {
  switch (m) {
    case Sigma0Model::kEmpirical:
      return "empirical";
    case Sigma0Model::kIem:
      return "iem";
    case Sigma0Model::kSpm:
      return "spm";
    case Sigma0Model::kKirchhoff:
      return "ka";
    case Sigma0Model::kRt:
      return "rt";
    case Sigma0Model::kTotal:
      return "total";
    case Sigma0Model::kPhysical:
      return "physical";
  }
  return "?";
}

Sigma0Model parse_sigma0_model(std::string_view text) {
  for (Sigma0Model m :
       {Sigma0Model::kEmpirical, Sigma0Model::kIem, Sigma0Model::kSpm, Sigma0Model::kKirchhoff,
        Sigma0Model::kRt, Sigma0Model::kTotal, Sigma0Model::kPhysical}) {
    if (text == to_string(m))
      return m;
  }
  throw std::invalid_argument("unknown model '" + std::string(text) +
                              "' (known: empirical, iem, spm, ka, rt, total, physical)");
}

std::optional<EmpiricalRow> empirical_row(EmpiricalClass c, double freq_hz, int pol) noexcept {
  const char band = band_of(freq_hz);
  for (const EmpiricalTable& t : kEmpirical) {
    if (t.cls != c || t.band != band)
      continue;
    const int column = pol == 0 ? 0 : (pol == 1 ? 2 : 1);
    if (column == 0 && !t.hh_ok)
      return std::nullopt;
    EmpiricalRow r{};
    for (int k = 0; k < 6; ++k)
      r.p[k] = t.p[k][column];
    return r;
  }
  return std::nullopt;
}

double empirical_sigma0_db(const EmpiricalRow& r, double theta_rad) noexcept {
  return r.p[0] + r.p[1] * std::exp(-r.p[2] * theta_rad) +
         r.p[3] * std::cos(r.p[4] * theta_rad + r.p[5]);
}

SurfaceSpec resolve_surface(const TerrainMaterial& m, double freq_hz) {
  SurfaceSpec s;
  s.empirical = m.empirical;
  s.curve = m.curve;
  s.sea_state = m.sea_state;
  if (m.permittivity_model == PermittivityModel::kConductor) {
    s.conductor = true;
    return s;
  }
  s.surface.relative_permittivity = permittivity(m, freq_hz);
  s.surface.roughness = m.roughness;
  s.has_volume = m.has_volume;
  s.volume = m.volume;
  s.volume.extinction_np_per_m = volume_extinction_np_per_m(m, freq_hz);
  validate(s.surface, freq_hz);
  return s;
}

SurfaceScatter evaluate_sigma0(const SurfaceSpec& spec, Sigma0Model model, double freq_hz,
                               const Geometry& g, bool cross_pol_backscatter) {
  if (spec.conductor)
    return {};
  switch (model) {
    case Sigma0Model::kEmpirical: {
      SurfaceScatter out;
      if (!g.is_backscatter()) {
        out.invalid |= kEmpiricalOutside;
        return out;
      }
      double* dst[4] = {&out.incoherent.hh, &out.incoherent.vv, &out.incoherent.hv,
                        &out.incoherent.vh};
      for (int pol = 0; pol < 4; ++pol) {
        const auto row = empirical_row(spec.empirical, freq_hz, pol == 3 ? 2 : pol);
        if (!row) {
          out.invalid |= kEmpiricalOutside;
          continue;
        }
        *dst[pol] = std::pow(10.0, empirical_sigma0_db(*row, g.theta_i_rad) / 10.0);
      }
      // The regressions were fitted to data out to about 70-80 deg.
      if (g.theta_i_rad > common::radians(70.0))
        out.invalid |= kGrazing;
      return out;
    }
    case Sigma0Model::kIem:
      return iem(spec.surface, freq_hz, g, IemConventions::kPublishedEquations,
                 cross_pol_backscatter);
    case Sigma0Model::kSpm:
      return spm(spec.surface, freq_hz, g);
    case Sigma0Model::kKirchhoff:
      return kirchhoff(spec.surface, freq_hz, g);
    case Sigma0Model::kRt: {
      SurfaceScatter out;
      if (spec.has_volume)
        out.incoherent = rt_volume(spec.volume, spec.surface, freq_hz, g, &out.invalid);
      return out;
    }
    case Sigma0Model::kTotal:
      if (spec.curve != CatalogueCurve::kNone && g.is_backscatter()) {
        // The measured-data catalogue (sigma0_catalogue.cpp).
        SurfaceScatter out;
        double* dst[4] = {&out.incoherent.hh, &out.incoherent.vv, &out.incoherent.hv,
                          &out.incoherent.vh};
        for (int pol = 0; pol < 4; ++pol) {
          const Sigma0Value v = catalogue_sigma0(spec.curve, spec.sea_state, freq_hz,
                                                 static_cast<Sigma0Pol>(pol), g.theta_i_rad);
          *dst[pol] = v.linear;
          out.invalid |= v.flags;
        }
        return out;
      }
      [[fallthrough]];
    case Sigma0Model::kPhysical:
      return spec.has_volume
                 ? rt_total(spec.volume, spec.surface, freq_hz, g, cross_pol_backscatter)
                 : iem(spec.surface, freq_hz, g, IemConventions::kPublishedEquations,
                       cross_pol_backscatter);
  }
  return {};
}

Sigma0Table::Sigma0Table(std::span<const SurfaceSpec> specs, Sigma0Model model, double freq_hz) {
  values_.assign(specs.size() * 4 * kSamples, 0.0f);
  flags_.assign(specs.size() * 4 * kSamples, 0u);
  // Co-polarised sigma0 at every sample. The physical models' cross-polarised backscatter (the
  // IEM's multiple-scattering double integral, ~0.5 ms an angle) is evaluated every
  // kCrossPolStride samples (0.5 deg) and interpolated linearly in dB in between: the curves are
  // smooth on that scale (Terrain.Sigma0TableInterpolatesTheModels checks HV too). The
  // catalogue (model total, backscatter) is cheap and evaluated at every sample. Angles are
  // spread over the cores; setup only. The validity bits of the polarisation's evaluation are
  // kept per sample (lookup_flags()).
  constexpr int kCrossPolStride = 10;
  static_assert((kSamples - 1) % kCrossPolStride == 0);
  auto theta_of = [](int i) {
    // Sample at most 89.95 deg: the models are finite there and the table stays continuous.
    return std::min(i * (kPi / 2.0) / (kSamples - 1), common::radians(89.95));
  };
  for (std::size_t m = 0; m < specs.size(); ++m) {
    float* row[4];
    std::uint32_t* frow[4];
    for (std::size_t p = 0; p < 4; ++p) {
      row[p] = values_.data() + (m * 4 + p) * kSamples;
      frow[p] = flags_.data() + (m * 4 + p) * kSamples;
    }
    const bool catalogue = model == Sigma0Model::kTotal && specs[m].curve != CatalogueCurve::kNone;
    if (catalogue) {
      for (int i = 0; i < kSamples; ++i) {
        const auto at = static_cast<std::size_t>(i);
        for (std::size_t p = 0; p < 4; ++p) {
          const Sigma0Value v = catalogue_sigma0(specs[m].curve, specs[m].sea_state, freq_hz,
                                                 static_cast<Sigma0Pol>(p), theta_of(i));
          row[p][at] = static_cast<float>(v.linear);
          frow[p][at] = v.flags;
        }
      }
      continue;
    }
    tbb::parallel_for(0, kSamples, [&](int i) {
      const bool node = i % kCrossPolStride == 0;
      const SurfaceScatter s =
          evaluate_sigma0(specs[m], model, freq_hz, Geometry::backscatter(theta_of(i)), node);
      const auto at = static_cast<std::size_t>(i);
      row[kHH][at] = static_cast<float>(s.incoherent.hh);
      row[kVV][at] = static_cast<float>(s.incoherent.vv);
      frow[kHH][at] = frow[kVV][at] = s.invalid;
      if (node) {
        row[kHV][at] = static_cast<float>(s.incoherent.hv);
        row[kVH][at] = static_cast<float>(s.incoherent.vh);
        frow[kHV][at] = frow[kVH][at] = s.invalid;
      }
    });
    for (std::size_t p : {std::size_t{kHV}, std::size_t{kVH}}) {
      for (int node = 0; node + kCrossPolStride < kSamples; node += kCrossPolStride) {
        const auto a = static_cast<double>(row[p][node]);
        const auto b = static_cast<double>(row[p][node + kCrossPolStride]);
        for (int j = 1; j < kCrossPolStride; ++j) {
          const double w = static_cast<double>(j) / kCrossPolStride;
          // Geometric (dB-linear) where both ends carry power, linear otherwise.
          const double v = (a > 0.0 && b > 0.0) ? a * std::pow(b / a, w) : a + w * (b - a);
          row[p][node + j] = static_cast<float>(v);
          frow[p][node + j] = frow[p][node] | frow[p][node + kCrossPolStride];
        }
      }
    }
  }
}

std::uint32_t Sigma0Table::lookup_flags(std::size_t index, Pol pol,
                                        double cos_incidence) const noexcept {
  if (index >= materials() || !(cos_incidence >= 0.0 && cos_incidence <= 1.0))
    return 0u;
  const double x = std::acos(cos_incidence) * ((kSamples - 1) / (kPi / 2.0));
  const int i = std::min(static_cast<int>(x), kSamples - 2);
  const std::uint32_t* row = flags_.data() + (index * 4 + pol) * kSamples;
  return row[i] | row[i + 1];
}

std::uint32_t Sigma0Table::row_flags(std::size_t index, Pol pol) const noexcept {
  if (index >= materials())
    return 0u;
  const std::uint32_t* row = flags_.data() + (index * 4 + pol) * kSamples;
  std::uint32_t out = 0u;
  for (int i = 0; i < kSamples; ++i)
    out |= row[i];
  return out;
}

float Sigma0Table::lookup(std::size_t index, Pol pol, double cos_incidence) const noexcept {
  if (index >= materials() || !(cos_incidence >= 0.0 && cos_incidence <= 1.0))
    return 0.0f;
  const double x = std::acos(cos_incidence) * ((kSamples - 1) / (kPi / 2.0));
  const int i = std::min(static_cast<int>(x), kSamples - 2);
  const float w = static_cast<float>(x - i);
  const float* row = values_.data() + (index * 4 + pol) * kSamples;
  return row[i] + w * (row[i + 1] - row[i]);
}

float Sigma0Table::lookup(std::size_t index, Pol pol, double cos_incidence,
                          std::uint32_t& flags) const noexcept {
  flags = 0u;
  if (index >= materials() || !(cos_incidence >= 0.0 && cos_incidence <= 1.0))
    return 0.0f;
  const double x = std::acos(cos_incidence) * ((kSamples - 1) / (kPi / 2.0));
  const int i = std::min(static_cast<int>(x), kSamples - 2);
  const float w = static_cast<float>(x - i);
  const std::size_t at = (index * 4 + pol) * kSamples;
  const float* row = values_.data() + at;
  flags = flags_[at + static_cast<std::size_t>(i)] | flags_[at + static_cast<std::size_t>(i) + 1];
  return row[i] + w * (row[i + 1] - row[i]);
}

void Sigma0Use::add(std::uint32_t sample_flags, double cos_incidence,
                    double patch_power_m2) noexcept {
  ++patches;
  power_m2 += patch_power_m2;
  if (sample_flags == 0u)
    return;
  ++flagged_patches;
  flags |= sample_flags;
  flagged_power_m2 += patch_power_m2;
  const double theta = std::acos(std::clamp(cos_incidence, 0.0, 1.0));
  flagged_incidence_min_rad = std::min(flagged_incidence_min_rad, theta);
  flagged_incidence_max_rad = std::max(flagged_incidence_max_rad, theta);
}

void Sigma0Use::merge(const Sigma0Use& o) noexcept {
  patches += o.patches;
  flagged_patches += o.flagged_patches;
  flags |= o.flags;
  power_m2 += o.power_m2;
  flagged_power_m2 += o.flagged_power_m2;
  flagged_incidence_min_rad = std::min(flagged_incidence_min_rad, o.flagged_incidence_min_rad);
  flagged_incidence_max_rad = std::max(flagged_incidence_max_rad, o.flagged_incidence_max_rad);
}

std::uint32_t sigma0_use_flags(std::span<const Sigma0Use> use) noexcept {
  std::uint32_t f = 0u;
  for (const Sigma0Use& u : use)
    f |= u.flagged_patches > 0 ? u.flags : 0u;
  return f;
}

double sigma0_use_patch_fraction(std::span<const Sigma0Use> use) noexcept {
  std::uint64_t n = 0, flagged = 0;
  for (const Sigma0Use& u : use) {
    n += u.patches;
    flagged += u.flagged_patches;
  }
  return n > 0 ? static_cast<double>(flagged) / static_cast<double>(n) : 0.0;
}

double sigma0_use_power_fraction(std::span<const Sigma0Use> use) noexcept {
  double p = 0.0, flagged = 0.0;
  for (const Sigma0Use& u : use) {
    p += u.power_m2;
    flagged += u.flagged_power_m2;
  }
  return p > 0.0 ? flagged / p : 0.0;
}

std::vector<std::string> sigma0_use_lines(std::span<const Sigma0Use> use,
                                          std::span<const std::string> names, double carrier_hz) {
  std::uint64_t all_patches = 0;
  double all_power = 0.0;
  for (const Sigma0Use& u : use) {
    all_patches += u.patches;
    all_power += u.power_m2;
  }
  std::vector<std::string> lines;
  for (std::size_t r = 0; r < use.size(); ++r) {
    const Sigma0Use& u = use[r];
    if (u.flagged_patches == 0)
      continue;
    const std::string name = r < names.size() ? names[r] : "row " + std::to_string(r);
    char buf[192];
    std::snprintf(buf, sizeof buf, " at %.4g GHz, %.0f-%.0f deg incidence: ", carrier_hz * 1e-9,
                  common::degrees(u.flagged_incidence_min_rad),
                  common::degrees(u.flagged_incidence_max_rad));
    char share[160];
    std::snprintf(share, sizeof share, " (%.1f %% of the terrain's patches, %.1f %% of its power)",
                  all_patches > 0 ? 100.0 * static_cast<double>(u.flagged_patches) /
                                        static_cast<double>(all_patches)
                                  : 0.0,
                  all_power > 0.0 ? 100.0 * u.flagged_power_m2 / all_power : 0.0);
    lines.push_back(name + buf + describe_validity(u.flags) + share);
  }
  return lines;
}

}  // namespace radar_emu::radar::clutter
