// The measured-data sigma0 catalogue (terrain.hpp, "The measured-data catalogue"): the anchor
// curves of every material, where each number comes from, and their evaluation. Pure
// computation. The sources, the points tested against them and what was not found are listed
// in docs/validation.md ("Terrain sigma0 catalogue"); tests/data/sigma0_catalogue_points.csv
// holds the published points the tests compare with.
//
// Sources (short names used beside the numbers below):
//   [UD]  Ulaby & Dobson (1989), Handbook of Radar Scattering Statistics for Terrain, the
//         regression sigma0(dB) = P1 + P2 exp(-P3 t) + P4 cos(P5 t + P6), t incidence [rad],
//         L, S and C band rows per class and polarisation (the rows in terrain.cpp, read through
//         empirical_row(); transcription DartsTST.jl, see docs/notes/clutter_data_sources.md
//         sec. 2.1). The handbook's X (except trees, [UDt]), Ku, Ka and W rows were not found.
//   [UDt] Ulaby & Dobson (1989), the trees class, X band, HH and VV regression rows, as
//         transcribed in a public Python file ("library of clutter P-values", function
//         get_P_vec_tree; repository not identified, found by exact-string search; see
//         docs/validation.md). Its HV row is malformed there (seven entries) and not used. The
//         only X-band row of the handbook found.
//   [BL]  Billingsley (2002), Low-Angle Radar Land Clutter, mean clutter strength sigma0 F^4 per
//         terrain type, band (L 1.23, S 3.24, X 9.2 GHz) and polarisation at depression angles
//         of a few degrees (the book's mean-strength tables, as transcribed in AFSIM,
//         WsfMIT_ClutterStrength.cpp, tables sLOW_RELIEF_* and sGENERAL_URBAN; the book's own
//         table numbers were not checked). The rows are the book's means over the 1.5-4 deg
//         depression range (Billingsley's depression-angle classes; 2.75 deg is its midpoint);
//         used at 2.75 deg (87.25 deg incidence). Depression, not grazing: the local slope of
//         the measured patches is not in it. The AFSIM copies found carry distribution and
//         export-control markings: the values are to be re-read from the book (ch. 5, sec. 5.4)
//         and cited by table; none is contradicted by a public source, none confirmed either.
//   [NRL] Gregers-Hansen & Mital (2012), An Improved Empirical Model for Radar Sea Clutter
//         Reflectivity, NRL/MR/5310-12-9346, eq. (7) and Table 1 (p. 6); fitted to Nathanson's
//         tables over 0.5-35 GHz, grazing 0.1-60 deg, sea state 0-6; mean absolute error
//         2.3 dB (H) / 2.2 dB (V) (Table 2).
//   [CM]  Cox & Munk (1954), J. Opt. Soc. Am. 44(11): clean-surface mean square slope
//         s^2 = 0.003 + 5.12e-3 U (U wind speed [m/s] at 12.5 m).
//   assumed: no published value was found; our choice, said so here and in docs/validation.md.

#include <algorithm>
#include <cmath>
#include <complex>
#include <stdexcept>
#include <string>
#include <vector>

#include "common/units.hpp"
#include "radar/clutter/terrain.hpp"
#include "radar/constants.hpp"
#include "radar/propagation/itu.hpp"

namespace radar_emu::radar::clutter {

namespace {

// The angle the regression rows are used to (the handbook's fits cover about 0-70/80 deg,
// docs/notes/clutter_data_sources.md sec. 2.1); beyond it the cos^p tail.
constexpr double kRowEndRad = common::radians(70.0);
// Largest incidence evaluated: 90 deg itself has no backscatter (cos^p -> 0, NRL's
// log10(sin(grazing)) -> -inf); values beyond are those at 89.95 deg, flagged.
constexpr double kThetaMaxRad = common::radians(89.95);
constexpr double kBillingsleyThetaDeg = 87.25;  // [BL] 1.5-4 deg depression, at its midpoint
constexpr double kAssumedGrazeThetaDeg = 85.0;

/// One polarisation of one anchor: a row up to 70 deg, a cos^p tail through a grazing point.
struct PolCurve {
  double p[6] = {};
  bool row_measured = false;  ///< the row is a published one (else assumed)
  double graze_theta_deg = kAssumedGrazeThetaDeg;
  double graze_db = -30.0;
  bool graze_measured = false;
};

struct Anchor {
  double freq_hz = 0.0;
  PolCurve pol[3];  // HH, VV, HV (VH = HV, reciprocity)
};

struct Graze {
  double hh_db, vv_db;
  bool measured;
  double theta_deg;
};

/// A published [UD] row of `cls` at `band_hz` (L 1.5, S 3, C 6 GHz) for each polarisation. A
/// missing row (soil L HH, a refit in the transcription) takes the VV row, marked assumed.
/// Cross-pol grazing point: VV - `hv_graze_offset_db` (assumed: [BL] has co-pol only).
Anchor ud_anchor(double freq_hz, EmpiricalClass cls, double band_hz, const Graze& g,
                 double row_offset_db = 0.0, double hv_graze_offset_db = 8.0) {
  Anchor a;
  a.freq_hz = freq_hz;
  for (int pol = 0; pol < 3; ++pol) {
    PolCurve& c = a.pol[pol];
    auto row = empirical_row(cls, band_hz, pol);
    c.row_measured = row.has_value() && row_offset_db == 0.0;
    if (!row)
      row = empirical_row(cls, band_hz, 1);
    for (int k = 0; k < 6; ++k)
      c.p[k] = row ? row->p[k] : 0.0;
    c.p[0] += row_offset_db;
    c.graze_theta_deg = g.theta_deg;
    c.graze_db = pol == 0 ? g.hh_db : (pol == 1 ? g.vv_db : g.vv_db - hv_graze_offset_db);
    c.graze_measured = g.measured && pol != 2;
  }
  return a;
}

/// An assumed anchor: the VV row P1 + P2 exp(-P3 t), HH = VV + hh_db, HV = VV + hv_db, and a
/// grazing point (measured where `g.measured`).
Anchor assumed_anchor(double freq_hz, double p1, double p2, double p3, const Graze& g, double hh_db,
                      double hv_db) {
  Anchor a;
  a.freq_hz = freq_hz;
  const double offset[3] = {hh_db, 0.0, hv_db};
  for (int pol = 0; pol < 3; ++pol) {
    PolCurve& c = a.pol[pol];
    c.p[0] = p1 + offset[pol];
    c.p[1] = p2;
    c.p[2] = p3;
    c.row_measured = false;
    c.graze_theta_deg = g.theta_deg;
    c.graze_db = pol == 0 ? g.hh_db : (pol == 1 ? g.vv_db : g.vv_db + hv_db);
    c.graze_measured = g.measured && pol != 2;
  }
  return a;
}

/// The X-band anchor of a [UD] class: the C row carried over to 10 GHz (no X row found), so
/// its 0-70 deg part is assumed.
Anchor carried(Anchor a) {
  for (PolCurve& c : a.pol)
    c.row_measured = false;
  return a;
}

/// A published row for the co-polarised curves of an anchor (HH = 0, VV = 1), marked measured;
/// the other polarisations keep theirs.
Anchor with_row(Anchor a, int pol, const double (&p)[6]) {
  for (int k = 0; k < 6; ++k)
    a.pol[pol].p[k] = p[k];
  a.pol[pol].row_measured = true;
  return a;
}

Graze bl(double hh_db, double vv_db) {  // a [BL] point at 87.25 deg incidence
  return {hh_db, vv_db, true, kBillingsleyThetaDeg};
}
Graze assumed_graze(double hh_db, double vv_db) {
  return {hh_db, vv_db, false, kAssumedGrazeThetaDeg};
}
Graze assumed_graze_at(double hh_db, double vv_db, double theta_deg) {
  return {hh_db, vv_db, false, theta_deg};
}

// Anchor frequencies: [UD] rows at L 1.25, S 3.2, C 6 GHz (the bands' rows placed near the
// band centre and near [BL]'s L 1.23 / S 3.24 GHz; our choice), X 10 GHz ([BL] 9.2 GHz),
// Ka 35 and W 94 GHz.
constexpr double kL = 1.25e9, kS = 3.2e9, kC = 6e9, kX = 10e9, kKa = 35e9, kW = 94e9;
constexpr double kUdL = 1.5e9, kUdS = 3e9, kUdC = 6e9;  // inside the [UD] bands

struct Curve {
  CatalogueCurve id;
  std::vector<Anchor> anchors;  // ascending frequency
};

std::vector<Curve> build_curves() {
  using E = EmpiricalClass;
  std::vector<Curve> k;
  // Mown grass: [UD] grass L/S/C; grazing points [BL] low-relief grassland (2.75 deg:
  // L -40.7/-39.5, S -37.3/-36.2, X -39.1/-36.8 dB HH/VV). C grazing point: mean of S and X
  // (assumed). X 0-70 deg: the C row carried over (assumed: no X row found). Ka, W: assumed.
  k.push_back({CatalogueCurve::kGrass,
               {ud_anchor(kL, E::kGrass, kUdL, bl(-40.7, -39.5)),
                ud_anchor(kS, E::kGrass, kUdS, bl(-37.3, -36.2)),
                ud_anchor(kC, E::kGrass, kUdC, assumed_graze_at(-38.2, -36.5, 87.25)),
                carried(ud_anchor(kX, E::kGrass, kUdC, bl(-39.1, -36.8))),
                assumed_anchor(kKa, -13.0, 16.0, 3.0, assumed_graze(-19.0, -19.0), 0.0, -9.0),
                assumed_anchor(kW, -11.0, 13.0, 2.5, assumed_graze(-16.0, -16.0), 0.0, -9.0)}});
  // Tall grass: [UD] shrubs L and C (the S row is mis-copied in the transcription and left
  // out); grazing points [BL] low-relief shrubland (L -28.8/-29.8, S -36.5/-33.5,
  // X -23.8/-22.4). Ka, W: assumed.
  k.push_back({CatalogueCurve::kTallGrass,
               {ud_anchor(kL, E::kShrubs, kUdL, bl(-28.8, -29.8)),
                ud_anchor(kC, E::kShrubs, kUdC, assumed_graze_at(-30.2, -28.0, 87.25)),
                carried(ud_anchor(kX, E::kShrubs, kUdC, bl(-23.8, -22.4))),
                assumed_anchor(kKa, -11.0, 13.0, 2.5, assumed_graze(-16.0, -16.0), 0.0, -8.0),
                assumed_anchor(kW, -10.0, 12.0, 2.5, assumed_graze(-14.0, -14.0), 0.0, -8.0)}});
  // Crops: [UD] short vegetation L/S/C; [BL] low-relief agricultural (L -32.2/-30.5,
  // S -37.0/-37.4, X -32.2/-31.4).
  k.push_back({CatalogueCurve::kCrops,
               {ud_anchor(kL, E::kShortVegetation, kUdL, bl(-32.2, -30.5)),
                ud_anchor(kS, E::kShortVegetation, kUdS, bl(-37.0, -37.4)),
                ud_anchor(kC, E::kShortVegetation, kUdC, assumed_graze_at(-34.6, -34.4, 87.25)),
                carried(ud_anchor(kX, E::kShortVegetation, kUdC, bl(-32.2, -31.4))),
                assumed_anchor(kKa, -12.0, 15.0, 3.0, assumed_graze(-18.0, -18.0), 0.0, -8.0),
                assumed_anchor(kW, -10.0, 12.0, 2.5, assumed_graze(-15.0, -15.0), 0.0, -8.0)}});
  // Forest: X band 0-70 deg HH and VV: the [UDt] trees rows, P1..P6 =
  // HH -12.078, 1e-6, -10, 4.574, 1.171, 0.583 (-8.3 dB at nadir, -13.8 dB at 70 deg);
  // VV -11.751, 2e-6, -10, 3.596, 2.033, 0.122 (-8.2 / -14.4 dB). X HV, and L and S rows:
  // assumed (a volume scatterer: flat, -12 dB at 70 deg; HV = VV - 7 dB). Grazing points [BL]
  // low-relief forest (L -25.8/-26.2, S -32.3/-30.7, X -25.1/-23.8).
  constexpr double kTreesXhh[6] = {-12.078, 1e-6, -10.0, 4.574, 1.171, 0.583};  // [UDt]
  constexpr double kTreesXvv[6] = {-11.751, 2e-6, -10.0, 3.596, 2.033, 0.122};  // [UDt]
  k.push_back({CatalogueCurve::kForest,
               {assumed_anchor(kL, -12.0, 8.0, 3.0, bl(-25.8, -26.2), 0.0, -7.0),
                assumed_anchor(kS, -12.0, 8.0, 3.0, bl(-32.3, -30.7), 0.0, -7.0),
                with_row(with_row(assumed_anchor(kX, -12.0, 8.0, 3.0, bl(-25.1, -23.8), 0.0, -7.0),
                                  0, kTreesXhh),
                         1, kTreesXvv),
                assumed_anchor(kKa, -9.0, 7.0, 3.0, assumed_graze(-15.0, -15.0), 0.0, -7.0),
                assumed_anchor(kW, -8.0, 6.0, 3.0, assumed_graze(-13.0, -13.0), 0.0, -7.0)}});
  // Dry soil: [UD] soil L/S/C less 3 dB (assumed: the handbook's soil class spans all
  // moistures; dry soil taken 3 dB under its mean). Grazing points [BL] level desert
  // (L -35.6/-39.2, S -38.0/-37.2, X -23.8/-23.5).
  k.push_back({CatalogueCurve::kSoilDry,
               {ud_anchor(kL, E::kSoil, kUdL, bl(-35.6, -39.2), -3.0, 10.0),
                ud_anchor(kS, E::kSoil, kUdS, bl(-38.0, -37.2), -3.0, 10.0),
                ud_anchor(kC, E::kSoil, kUdC, assumed_graze_at(-30.9, -30.4, 87.25), -3.0, 10.0),
                ud_anchor(kX, E::kSoil, kUdC, bl(-23.8, -23.5), -3.0, 10.0),
                assumed_anchor(kKa, -16.0, 22.0, 4.0, assumed_graze(-25.0, -25.0), 0.0, -10.0),
                assumed_anchor(kW, -13.0, 18.0, 3.5, assumed_graze(-21.0, -21.0), 0.0, -10.0)}});
  // Wet soil: [UD] soil L/S/C as published; grazing points assumed ([BL] desert + 3 dB).
  k.push_back(
      {CatalogueCurve::kSoilWet,
       {ud_anchor(kL, E::kSoil, kUdL, assumed_graze_at(-32.6, -36.2, 87.25), 0.0, 10.0),
        ud_anchor(kS, E::kSoil, kUdS, assumed_graze_at(-35.0, -34.2, 87.25), 0.0, 10.0),
        ud_anchor(kC, E::kSoil, kUdC, assumed_graze_at(-27.9, -27.4, 87.25), 0.0, 10.0),
        carried(ud_anchor(kX, E::kSoil, kUdC, assumed_graze_at(-20.8, -20.5, 87.25), 0.0, 10.0)),
        assumed_anchor(kKa, -14.0, 24.0, 4.0, assumed_graze(-23.0, -23.0), 0.0, -10.0),
        assumed_anchor(kW, -12.0, 20.0, 3.5, assumed_graze(-20.0, -20.0), 0.0, -10.0)}});
  // Gravel: rows as [UD] soil less 3 dB (assumed mapping); grazing points [BL] low-relief desert
  // (L -34.6/-38.1, S -38.0/-37.1, X -19.4/-22.1).
  k.push_back({CatalogueCurve::kGravel,
               {ud_anchor(kL, E::kSoil, kUdL, bl(-34.6, -38.1), -3.0, 10.0),
                ud_anchor(kS, E::kSoil, kUdS, bl(-38.0, -37.1), -3.0, 10.0),
                ud_anchor(kX, E::kSoil, kUdC, bl(-19.4, -22.1), -3.0, 10.0),
                assumed_anchor(kKa, -14.0, 18.0, 3.5, assumed_graze(-22.0, -22.0), 0.0, -10.0),
                assumed_anchor(kW, -12.0, 15.0, 3.0, assumed_graze(-19.0, -19.0), 0.0, -10.0)}});
  // Dry and wet snow: [UD] dry / wet snow L/S/C; no grazing measurement found (assumed);
  // X 0-70 deg: the C row carried over (assumed); Ka, W assumed (dry snow brightens with
  // frequency, wet snow absorbs).
  k.push_back({CatalogueCurve::kSnowDry,
               {ud_anchor(kL, E::kDrySnow, kUdL, assumed_graze(-30.0, -30.0)),
                ud_anchor(kS, E::kDrySnow, kUdS, assumed_graze(-30.0, -30.0)),
                ud_anchor(kC, E::kDrySnow, kUdC, assumed_graze(-28.0, -28.0)),
                carried(ud_anchor(kX, E::kDrySnow, kUdC, assumed_graze(-26.0, -26.0))),
                assumed_anchor(kKa, -10.0, 14.0, 3.0, assumed_graze(-18.0, -18.0), 0.0, -8.0),
                assumed_anchor(kW, -7.0, 10.0, 3.0, assumed_graze(-14.0, -14.0), 0.0, -8.0)}});
  k.push_back({CatalogueCurve::kSnowWet,
               {ud_anchor(kL, E::kWetSnow, kUdL, assumed_graze(-32.0, -32.0)),
                ud_anchor(kS, E::kWetSnow, kUdS, assumed_graze(-32.0, -32.0)),
                ud_anchor(kC, E::kWetSnow, kUdC, assumed_graze(-32.0, -32.0)),
                carried(ud_anchor(kX, E::kWetSnow, kUdC, assumed_graze(-32.0, -32.0))),
                assumed_anchor(kKa, -20.0, 25.0, 5.0, assumed_graze(-30.0, -30.0), 0.0, -10.0),
                assumed_anchor(kW, -17.0, 21.0, 4.0, assumed_graze(-26.0, -26.0), 0.0, -10.0)}});
  // Urban ground: rows assumed; grazing points [BL] general urban (L -18.4/-18.5,
  // S -20.8/-19.0, X -22.7/-17.0).
  k.push_back({CatalogueCurve::kUrban,
               {assumed_anchor(kL, -10.0, 12.0, 3.0, bl(-18.4, -18.5), 0.0, -8.0),
                assumed_anchor(kS, -10.0, 12.0, 3.0, bl(-20.8, -19.0), 0.0, -8.0),
                assumed_anchor(kX, -10.0, 12.0, 3.0, bl(-22.7, -17.0), 0.0, -8.0),
                assumed_anchor(kKa, -10.0, 12.0, 3.0, assumed_graze(-17.0, -17.0), 0.0, -8.0),
                assumed_anchor(kW, -9.0, 11.0, 3.0, assumed_graze(-15.0, -15.0), 0.0, -8.0)}});
  // Asphalt and concrete: no published values obtained (Li & Sarabandi 1999, 94 GHz roads at
  // 70-88 deg, and Ulaby et al. 1998, 95 GHz terrain at 70-90 deg: abstracts and the fading
  // statistics only; docs/validation.md lists what was searched). Assumed: a smooth surface (bright
  // nadir lobe, dark off nadir), at 94 GHz near grazing about 10 dB (asphalt) and 9 dB (concrete)
  // under mown grass, as the issue reports from 94 GHz landing imagery, and darker at lower
  // frequencies.
  k.push_back({CatalogueCurve::kAsphalt,
               {assumed_anchor(kX, -30.0, 38.0, 10.0, assumed_graze(-38.0, -38.0), -1.0, -15.0),
                assumed_anchor(kKa, -27.0, 33.0, 8.0, assumed_graze(-32.0, -32.0), -1.0, -13.0),
                assumed_anchor(kW, -23.0, 28.0, 6.0, assumed_graze(-27.0, -27.0), -1.0, -12.0)}});
  k.push_back({CatalogueCurve::kConcrete,
               {assumed_anchor(kX, -28.0, 36.0, 9.0, assumed_graze(-36.0, -36.0), -1.0, -15.0),
                assumed_anchor(kKa, -25.0, 31.0, 7.0, assumed_graze(-30.0, -30.0), -1.0, -13.0),
                assumed_anchor(kW, -21.0, 26.0, 5.5, assumed_graze(-25.0, -25.0), -1.0, -12.0)}});
  return k;
}

const std::vector<Curve>& curves() {
  static const std::vector<Curve> k = build_curves();
  return k;
}

const Curve* find_curve(CatalogueCurve id) noexcept {
  for (const Curve& c : curves())
    if (c.id == id)
      return &c;
  return nullptr;
}

/// One anchor, one polarisation, in dB; `flags` gets kAssumedValue / kOutsideMeasuredRange.
double anchor_db(const PolCurve& c, double theta_rad, std::uint32_t* flags) noexcept {
  auto row = [&](double t) {
    return c.p[0] + c.p[1] * std::exp(-c.p[2] * t) + c.p[3] * std::cos(c.p[4] * t + c.p[5]);
  };
  if (theta_rad <= kRowEndRad) {
    if (!c.row_measured)
      *flags |= kAssumedValue;
    return row(theta_rad);
  }
  // cos^p tail (a constant-gamma-like fall toward grazing, sigma0 = gamma cos^p(theta);
  // p = 1 is the constant-gamma model, Richards, Fundamentals of Radar Signal Processing,
  // 2nd ed., sec. 2.7) through the grazing point; p kept in [0, 4] (never rising to grazing).
  const double v_end = row(kRowEndRad);
  const double log_cos_end = std::log10(std::cos(kRowEndRad));
  const double drop = std::log10(std::cos(common::radians(c.graze_theta_deg))) - log_cos_end;
  const double p = std::clamp((c.graze_db - v_end) / (10.0 * drop), 0.0, 4.0);
  if (!c.graze_measured)
    *flags |= kAssumedValue;
  else if (theta_rad > common::radians(c.graze_theta_deg) + 1e-9)
    *flags |= kOutsideMeasuredRange;
  if (!c.row_measured)
    *flags |= kAssumedValue;
  return v_end + 10.0 * p * (std::log10(std::cos(theta_rad)) - log_cos_end);
}

// Sea state -> wind speed [m/s] for the quasi-specular lobe only: assumed (no table found);
// the order of the Douglas / WMO sea-state descriptions.
double wind_speed_m_s(double sea_state) noexcept {
  constexpr double kWind[] = {1.5, 3.5, 5.5, 7.5, 10.0, 12.5, 15.5};
  const double s = std::clamp(sea_state, 0.0, 6.0);
  const int i = std::min(static_cast<int>(s), 5);
  return kWind[i] + (s - i) * (kWind[i + 1] - kWind[i]);
}

}  // namespace

Sigma0Value sea_sigma0(double freq_hz, Sigma0Pol pol, double theta_rad, double sea_state) noexcept {
  Sigma0Value out;
  if (!(freq_hz > 0.0) || !std::isfinite(theta_rad))
    return out;
  if (theta_rad > kThetaMaxRad) {
    theta_rad = kThetaMaxRad;
    out.flags |= kOutsideMeasuredRange;
  }
  theta_rad = std::max(theta_rad, 0.0);
  const double ss = std::clamp(sea_state, 0.0, 6.0);
  double f_ghz = freq_hz * 1e-9;
  // [NRL] fitted 0.5-35 GHz: outside, the formula's own log10(f) dependence, flagged.
  if (f_ghz < 0.5 || f_ghz > 35.0)
    out.flags |= kOutsideMeasuredRange;
  f_ghz = std::max(f_ghz, 0.1);
  // [NRL] eq. (7), Table 1 (p. 6): H c1..c5 = -73.00, 20.78, 7.351, 25.65, 0.00540;
  // V = -50.79, 25.93, 0.7093, 21.58, 0.00211. alpha: grazing angle [deg], 0.1-60 deg.
  const bool h = pol == Sigma0Pol::kHH;
  const double c1 = h ? -73.00 : -50.79, c2 = h ? 20.78 : 25.93, c3 = h ? 7.351 : 0.7093,
               c4 = h ? 25.65 : 21.58, c5 = h ? 0.00540 : 0.00211;
  double alpha_deg = 90.0 - common::degrees(theta_rad);
  if (alpha_deg < 0.1)
    out.flags |= kOutsideMeasuredRange;
  // Above 60 deg grazing the fit's c5 alpha^2 term runs away: held at its 60 deg value, and
  // the quasi-specular lobe below takes over toward nadir (flagged).
  if (alpha_deg > 60.0) {
    alpha_deg = 60.0;
    out.flags |= kOutsideMeasuredRange;
  }
  const double nrl_db = c1 + c2 * std::log10(std::sin(common::radians(alpha_deg))) +
                        (27.5 + c3 * alpha_deg) * std::log10(f_ghz) / (1.0 + 0.95 * alpha_deg) +
                        c4 * std::pow(1.0 + ss, 1.0 / (2.0 + 0.085 * alpha_deg + 0.033 * ss)) +
                        c5 * alpha_deg * alpha_deg;
  // Quasi-specular (geometrical-optics) lobe near nadir: sigma0 = |R(0)|^2 sec^4(t)
  // exp(-tan^2(t) / s^2) / s^2 (Ulaby, Moore & Fung 1982, vol. II, eq. 12.61 form), s^2 from
  // [CM] at the assumed wind of the sea state; water permittivity ITU-R P.840 at 15 C.
  const std::complex<double> eps = water_permittivity(freq_hz, 288.15);
  const std::complex<double> n = std::sqrt(eps);
  const double r0 = std::norm((1.0 - n) / (1.0 + n));
  const double s2 = 0.003 + 5.12e-3 * wind_speed_m_s(ss);
  const double c = std::cos(theta_rad), t2 = std::tan(theta_rad) * std::tan(theta_rad);
  // The lobe is added below 30 deg incidence only (NRL's data, grazing <= 60 deg, already hold
  // whatever quasi-specular return there is): weight 1 up to 20 deg, a raised-cosine taper to 0
  // at 30 deg (our choice, smooth in angle).
  const double theta_deg = common::degrees(theta_rad);
  const double taper =
      theta_deg <= 20.0
          ? 1.0
          : (theta_deg >= 30.0 ? 0.0 : 0.5 * (1.0 + std::cos(kPi * (theta_deg - 20.0) / 10.0)));
  const double go = taper * r0 * std::exp(-t2 / s2) / (s2 * c * c * c * c);
  double linear = std::pow(10.0, nrl_db / 10.0) + go;
  if (theta_rad < common::radians(30.0))
    out.flags |= kAssumedValue;  // the lobe's wind speed is assumed
  if (pol == Sigma0Pol::kHV || pol == Sigma0Pol::kVH) {
    // [NRL] is co-polarised only: cross-pol assumed 15 dB under VV.
    linear = sea_sigma0(freq_hz, Sigma0Pol::kVV, theta_rad, ss).linear * std::pow(10.0, -1.5);
    out.flags |= kAssumedValue;
  }
  out.linear = linear;
  return out;
}

Sigma0Value catalogue_sigma0(CatalogueCurve id, double sea_state, double freq_hz, Sigma0Pol pol,
                             double theta_rad) noexcept {
  Sigma0Value out;
  if (id == CatalogueCurve::kNone || !(freq_hz > 0.0) || !std::isfinite(freq_hz) ||
      !std::isfinite(theta_rad))
    return out;
  if (id == CatalogueCurve::kWater)
    return sea_sigma0(freq_hz, pol, theta_rad, sea_state);
  const Curve* curve = find_curve(id);
  if (curve == nullptr || curve->anchors.empty())
    return out;
  theta_rad = std::max(theta_rad, 0.0);
  if (theta_rad > kThetaMaxRad) {
    theta_rad = kThetaMaxRad;
    out.flags |= kOutsideMeasuredRange;
  }
  const int p = pol == Sigma0Pol::kVH ? 2 : static_cast<int>(pol);
  const auto& a = curve->anchors;
  double db = 0.0;
  if (freq_hz <= a.front().freq_hz || a.size() == 1) {
    // Below the first anchor: held flat (flagged outside the measured frequencies).
    if (freq_hz < a.front().freq_hz * (1.0 - 1e-12))
      out.flags |= kOutsideMeasuredRange;
    db = anchor_db(a.front().pol[p], theta_rad, &out.flags);
  } else if (freq_hz >= a.back().freq_hz) {
    if (freq_hz > a.back().freq_hz * (1.0 + 1e-12))
      out.flags |= kOutsideMeasuredRange;
    db = anchor_db(a.back().pol[p], theta_rad, &out.flags);
  } else {
    std::size_t i = 0;
    while (freq_hz > a[i + 1].freq_hz)
      ++i;
    // Linear in dB against log frequency between neighbouring anchors (continuous in f).
    const double w = std::log(freq_hz / a[i].freq_hz) / std::log(a[i + 1].freq_hz / a[i].freq_hz);
    std::uint32_t f0 = 0, f1 = 0;
    const double d0 = anchor_db(a[i].pol[p], theta_rad, &f0);
    const double d1 = anchor_db(a[i + 1].pol[p], theta_rad, &f1);
    db = (1.0 - w) * d0 + w * d1;
    out.flags |= (w < 1.0 ? f0 : 0u) | (w > 0.0 ? f1 : 0u);
  }
  out.linear = std::pow(10.0, db / 10.0);
  return out;
}

Sigma0Value sigma0(const TerrainMaterial& m, double freq_hz, Sigma0Pol pol,
                   double theta_rad) noexcept {
  return catalogue_sigma0(m.curve, m.sea_state, freq_hz, pol, theta_rad);
}

Sigma0Value sigma0(std::string_view material, double freq_hz, Sigma0Pol pol, double theta_rad) {
  return sigma0(terrain_material(material), freq_hz, pol, theta_rad);
}

const TerrainMaterial& terrain_material(std::string_view name) {
  const TerrainMaterial* m = find_terrain_material(name);
  if (m == nullptr)
    throw std::invalid_argument("unknown terrain material '" + std::string(name) +
                                "' (known: " + terrain_material_names() + ")");
  return *m;
}

}  // namespace radar_emu::radar::clutter
