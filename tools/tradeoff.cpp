#include "tools/tradeoff.hpp"

#include <tbb/parallel_invoke.h>

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <complex>
#include <cstdarg>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <functional>
#include <limits>
#include <memory>
#include <optional>
#include <span>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "common/units.hpp"
#include "config/progress.hpp"
#include "loop/closed_loop.hpp"
#include "loop/scenario.hpp"
#include "plot/charts.hpp"
#include "radar/clutter/surface.hpp"
#include "radar/constants.hpp"
#include "radar/em/mom.hpp"
#include "radar/em/rcs.hpp"
#include "radar/em/sbr.hpp"
#include "radar/products/range_profile.hpp"
#include "radar/products/terrain_returns.hpp"
#include "radar/reference/mie.hpp"
#include "radar/sensor/sensor.hpp"
#include "radar/sensor/waveform.hpp"
#include "scene/scene.hpp"
#include "scene/targets.hpp"

namespace radar_emu::tools {

using loop::default_scenario_toml;
using loop::FidelityGovernor;
using loop::parse_scenario;
using loop::Scenario;
using loop::scene_description;
using loop::scripted_pose;
using loop::terrain_returns_config;
using plot::LineChart;
using plot::Series;
using plot::series_colour;
using plot::write_line_chart_png;

namespace {

using radar::kPi;
using radar::kSpeedOfLight_mps;
using Clock = std::chrono::steady_clock;

double ms_since(Clock::time_point t0) {
  return std::chrono::duration<double, std::milli>(Clock::now() - t0).count();
}

double db10(double linear) {
  return common::db_from_power(std::max(linear, 1e-40));
}

// ---------------------------------------------------------------------------------------------
// Rows and progress

struct Row {
  std::string case_name, knob;
  double value = 0.0;
  double cost_ms = 0.0;
  std::uint64_t rays = 0;
  std::string metric;
  double error = 0.0;
  std::string reference;
  std::string validity = "ok";
  /// Where a row pools several measurements (the governor levels over frames along the
  /// approach): the range of the cost and of the error over them (NaN: one measurement). For
  /// the charts; the CSV keeps the pooled values.
  double cost_lo_ms = std::numeric_limits<double>::quiet_NaN();
  double cost_hi_ms = std::numeric_limits<double>::quiet_NaN();
  double error_lo = std::numeric_limits<double>::quiet_NaN();
  double error_hi = std::numeric_limits<double>::quiet_NaN();
};

class Log {
 public:
  /// Lines go through `control.note` (above the progress line) when it is set, else to stderr.
  Log(bool quiet, const common::WorkControl& control) : quiet_(quiet), control_(control) {}
  __attribute__((format(printf, 2, 3))) void operator()(const char* format, ...) const {
    if (quiet_)
      return;
    char buf[512];
    va_list args;
    va_start(args, format);
    std::vsnprintf(buf, sizeof buf, format, args);
    va_end(args);
    if (control_.note) {
      control_.note(buf);
    } else {
      std::fputs(buf, stderr);
      std::fflush(stderr);
    }
  }

 private:
  bool quiet_;
  const common::WorkControl& control_;
};

__attribute__((format(printf, 1, 2))) std::string fmt(const char* format, ...) {
  char buf[128];
  va_list args;
  va_start(args, format);
  std::vsnprintf(buf, sizeof buf, format, args);
  va_end(args);
  return buf;
}

// dB RMS of the difference of two equally long dB series (the convergence measure,
// docs/performance.md "Offline RCS engine": sqrt(mean((a_i - b_i)^2)) over the samples used).
double db_rms(const std::vector<double>& a, const std::vector<double>& b) {
  double s = 0.0;
  for (std::size_t i = 0; i < a.size(); ++i)
    s += (a[i] - b[i]) * (a[i] - b[i]);
  return a.empty() ? 0.0 : std::sqrt(s / static_cast<double>(a.size()));
}

// ---------------------------------------------------------------------------------------------
// RCS engine runs (vehicle, profile, sphere, grazing)

struct Sweep {
  std::vector<std::complex<double>> vv;  ///< [direction][frequency]
  double ms = 0.0;
  std::uint64_t rays = 0;
};

std::vector<radar::SurfaceModel> pec_surfaces(const scene::SceneDescription& d) {
  return std::vector<radar::SurfaceModel>(std::max<std::size_t>(d.materials.size(), 1));
}

// Monostatic VV at every direction and frequency; wall time of the compute() calls only (the
// engine's facet set-up is not a per-look cost).
Sweep rcs_sweep(const scene::Scene& scene, const std::vector<radar::SurfaceModel>& surfaces,
                const radar::RcsConfig& config, const std::vector<radar::Direction>& dirs,
                const std::vector<double>& freqs_hz) {
  const radar::RcsEngine engine(scene, surfaces, config);
  Sweep s;
  s.vv.reserve(dirs.size() * freqs_hz.size());
  std::vector<radar::ScatteringMatrix> out(freqs_hz.size());
  radar::RcsStats stats;
  const auto t0 = Clock::now();
  for (const radar::Direction& d : dirs) {
    engine.compute(d, d, freqs_hz, out, stats);
    for (const auto& m : out)
      s.vv.push_back(m.vv);
  }
  s.ms = ms_since(t0);
  s.rays = stats.rays;
  return s;
}

struct KnobSweep {
  std::string name;
  std::vector<double> values;  ///< coarse to fine; the last is the reference
};

// One knob of an RCS case swept from coarse to fine (the other knob at `base`), each setting's
// error against the finest; prints whether the last two agree (the reference's convergence).
void rcs_knob_rows(const std::string& case_name, const KnobSweep& knob,
                   const radar::RcsConfig& base, const std::string& held,
                   const std::function<Sweep(const radar::RcsConfig&)>& run,
                   const std::function<double(const Sweep&, const Sweep&)>& error,
                   const std::string& metric, double converged_db, const Log& log,
                   std::vector<Row>& rows) {
  std::vector<Sweep> results;
  for (double v : knob.values) {
    radar::RcsConfig c = base;
    if (knob.name == "rays_per_wavelength")
      c.rays_per_wavelength = v;
    else
      c.max_bounces = static_cast<int>(v);
    results.push_back(run(c));
    log("  %s %s %g: %.0f ms, %llu rays\n", case_name.c_str(), knob.name.c_str(), v,
        results.back().ms, static_cast<unsigned long long>(results.back().rays));
  }
  const Sweep& ref = results.back();
  const std::string ref_text =
      knob.name + " " + fmt("%g", knob.values.back()) + " (finest; " + held + ")";
  const double last_two = results.size() >= 2 ? error(results[results.size() - 2], ref) : 0.0;
  const bool converged = last_two <= converged_db;
  log("  %s %s: the last two settings (%g, %g) differ by %.3f dB: %s (criterion %.2g dB)\n",
      case_name.c_str(), knob.name.c_str(),
      knob.values.size() >= 2 ? knob.values[knob.values.size() - 2] : knob.values.back(),
      knob.values.back(), last_two, converged ? "converged" : "NOT converged", converged_db);
  for (std::size_t i = 0; i < results.size(); ++i) {
    Row r;
    r.case_name = case_name;
    r.knob = knob.name;
    r.value = knob.values[i];
    r.cost_ms = results[i].ms;
    r.rays = results[i].rays;
    r.metric = metric;
    r.error = i + 1 == results.size() ? 0.0 : error(results[i], ref);
    r.reference = ref_text;
    if (i + 1 == results.size())
      r.validity =
          converged
              ? "reference (converged: last two within " + fmt("%.3f", last_two) + " dB)"
              : "reference NOT converged (last two differ by " + fmt("%.3f", last_two) + " dB)";
    rows.push_back(r);
    if (i + 1 < results.size())
      log("  %s %s %g: %s %.3f dB\n", case_name.c_str(), knob.name.c_str(), r.value, metric.c_str(),
          r.error);
  }
}

struct Vehicle {
  scene::SceneDescription description;
  scene::Scene scene;
  std::vector<radar::SurfaceModel> surfaces;
  Vehicle()
      : description(scene::make_target({scene::TargetKind::kVehicle, 7.0, 3.5, 2.5, 0.0})),
        scene(description),
        surfaces(pec_surfaces(description)) {}
};

std::vector<KnobSweep> vehicle_knobs(bool quick) {
  if (quick)
    return {{"rays_per_wavelength", {0.25, 0.5, 1.0, 2.0, 4.0, 8.0}},
            {"max_bounces", {1, 2, 3, 4}}};
  return {{"rays_per_wavelength", {0.25, 0.5, 1.0, 2.0, 4.0, 8.0, 16.0}},
          {"max_bounces", {1, 2, 3, 4, 5}}};
}

// Case 1: the vehicle's RCS over an aspect cut at 10 GHz, VV.
void vehicle_case(Vehicle& v, bool quick, const Log& log, std::vector<Row>& rows) {
  const double theta = 80.0;
  std::vector<radar::Direction> dirs;
  const int n = quick ? 5 : 21;
  const double phi0 = quick ? 25.0 : 20.0, dphi = quick ? 2.5 : 1.0;
  for (int i = 0; i < n; ++i)
    dirs.push_back({common::radians(theta), common::radians(phi0 + i * dphi)});
  const std::vector<double> freqs{10e9};
  log("vehicle: %zu-facet vehicle, 10 GHz VV, theta %g deg, phi %g-%g deg (%d aspects)\n",
      v.scene.triangle_count(), theta, phi0, phi0 + (n - 1) * dphi, n);
  auto run = [&](const radar::RcsConfig& c) {
    return rcs_sweep(v.scene, v.surfaces, c, dirs, freqs);
  };
  auto error = [](const Sweep& a, const Sweep& ref) {
    std::vector<double> da, dr;
    for (std::size_t i = 0; i < a.vv.size(); ++i) {
      da.push_back(radar::dbsm(a.vv[i]));
      dr.push_back(radar::dbsm(ref.vv[i]));
    }
    return db_rms(da, dr);
  };
  const auto knobs = vehicle_knobs(quick);
  radar::RcsConfig base;
  base.max_bounces = 3;
  rcs_knob_rows("vehicle", knobs[0], base, "max_bounces 3", run, error, "rcs_vv_db_rms", 0.5, log,
                rows);
  base.rays_per_wavelength = 4.0;
  rcs_knob_rows("vehicle", knobs[1], base,
                "rays_per_wavelength " + fmt("%g", base.rays_per_wavelength), run, error,
                "rcs_vv_db_rms", 0.5, log, rows);
}

// Case 2: range profile of the vehicle, 9.5-10.5 GHz, one aspect.
void profile_case(Vehicle& v, bool quick, const Log& log, std::vector<Row>& rows) {
  const radar::FrequencyGrid grid{9.5e9, 1e9 / (quick ? 64.0 : 128.0), quick ? 64u : 128u};
  std::vector<double> freqs;
  for (std::size_t i = 0; i < grid.count; ++i)
    freqs.push_back(grid.start_hz + static_cast<double>(i) * grid.step_hz);
  const std::vector<radar::Direction> dirs{{common::radians(80.0), common::radians(30.0)}};
  log("profile: vehicle at theta 80 deg, phi 30 deg, %zu frequencies 9.5-%.4g GHz, VV, Hann\n",
      grid.count, freqs.back() * 1e-9);
  auto run = [&](const radar::RcsConfig& c) {
    return rcs_sweep(v.scene, v.surfaces, c, dirs, freqs);
  };
  // dB RMS over the bins within 30 dB of the reference profile's peak.
  auto error = [&](const Sweep& a, const Sweep& ref) {
    const radar::RangeProfile pa = radar::range_profile(a.vv, grid, radar::Window::kHann);
    const radar::RangeProfile pr = radar::range_profile(ref.vv, grid, radar::Window::kHann);
    double peak = -1e300;
    for (const auto& x : pr.amplitude_m)
      peak = std::max(peak, db10(std::norm(x)));
    std::vector<double> da, dr;
    for (std::size_t i = 0; i < pr.amplitude_m.size(); ++i) {
      const double r = db10(std::norm(pr.amplitude_m[i]));
      if (r < peak - 30.0)
        continue;
      dr.push_back(r);
      da.push_back(db10(std::norm(pa.amplitude_m[i])));
    }
    return db_rms(da, dr);
  };
  const auto knobs = vehicle_knobs(quick);
  radar::RcsConfig base;
  base.max_bounces = 3;
  rcs_knob_rows("profile", knobs[0], base, "max_bounces 3", run, error,
                "profile_db_rms_within_30db", 0.5, log, rows);
  base.rays_per_wavelength = 4.0;
  rcs_knob_rows("profile", knobs[1], base,
                "rays_per_wavelength " + fmt("%g", base.rays_per_wavelength), run, error,
                "profile_db_rms_within_30db", 0.5, log, rows);
}

// Case 4a: the sphere. PO through the facet integrator (max_bounces 1) against the PO closed
// form sigma/(pi a^2) = 1 - sin(2ka)/(ka) + sin^2(ka)/(ka)^2 (Knott, Shaeffer & Tuley 2004,
// sec. 5.5; radar/reference/mie.hpp) and the exact Mie series (Ruck et al. 1970, sec. 3.2). Radius
// 0.1 m; facets lambda/8 (lambda/16 below ka 10), at least 96 around, as tests/radar/rcs_test.cpp.
// Up to ka 5 (3 in the quick run) the method of moments (radar/em/mom.hpp, EFIE) on the same
// kind of sphere, facets lambda / 12 and at least 32 around, is run beside it: exact up to the mesh
// where PO is not, at the cost of a matrix fill and factorisation.
void sphere_case(bool quick, const Log& log, std::vector<Row>& rows, std::vector<double>& ka_out,
                 std::array<std::vector<double>, 3>& norm_db, std::vector<double>& mom_ka,
                 std::vector<double>& mom_norm_db) {
  const double a = 0.1;
  const std::vector<double> kas =
      quick ? std::vector<double>{0.5, 1.0, 1.5, 3.0, 5.0, 10.0, 25.0}
            : std::vector<double>{0.5,  0.75, 1.0,  1.5,  2.0,  3.0,  5.0,  7.0,
                                  10.0, 15.0, 20.0, 30.0, 50.0, 70.0, 100.0};
  log("sphere: radius %g m, ka %g-%g, PO facet integrator vs PO closed form vs Mie\n", a,
      kas.front(), kas.back());
  const std::string ref_mie = "Mie series (exact)";
  const std::string ref_po = "PO closed form 1 - sin(2ka)/ka + sin^2(ka)/ka^2";
  for (double ka : kas) {
    const double k = ka / a, lambda = 2.0 * kPi / k;
    const double facet_m =
        std::min((ka < 10.0 ? 1.0 / 16.0 : 1.0 / 8.0) * lambda, 2.0 * kPi * a / 96.0);
    const scene::SceneDescription d =
        scene::make_target({scene::TargetKind::kSphere, a, 1.0, 1.0, facet_m});
    const scene::Scene scene(d);
    radar::RcsConfig c;
    c.max_bounces = 1;  // convex: no multi-bounce path
    const double f = k * kSpeedOfLight_mps / (2.0 * kPi);
    const Sweep s =
        rcs_sweep(scene, pec_surfaces(d), c, {{common::radians(37.0), common::radians(11.0)}}, {f});
    const double faceted = db10(std::norm(s.vv[0]));
    const double po = db10(radar::po_sphere_rcs_m2(a, k));
    const double mie = db10(radar::mie_sphere_rcs_m2(a, k));
    const double norm = db10(kPi * a * a);
    ka_out.push_back(ka);
    norm_db[0].push_back(faceted - norm);
    norm_db[1].push_back(po - norm);
    norm_db[2].push_back(mie - norm);
    const std::string validity = ka < 10.0 ? "PO invalid (ka < 10)" : "ok";
    auto add = [&](const std::string& metric, double err, const std::string& ref) {
      rows.push_back({"sphere", "ka", ka, s.ms, s.rays, metric, err, ref, validity});
    };
    add("po_faceted_sigma_over_pi_a2_db", faceted - norm, "none (value, for independent checks)");
    add("po_faceted_minus_po_closed_form_db", faceted - po, ref_po);
    add("po_faceted_minus_mie_db", faceted - mie, ref_mie);
    add("po_closed_form_minus_mie_db", po - mie, ref_mie);
    log("  sphere ka %g (%zu facets, %.0f ms): faceted PO %+.2f dB vs PO closed form, %+.2f dB "
        "vs Mie%s\n",
        ka, scene.triangle_count(), s.ms, faceted - po, faceted - mie,
        ka < 10.0 ? "  [PO invalid]" : "");
    if (ka <= (quick ? 3.0 : 5.0)) {
      const auto t0 = std::chrono::steady_clock::now();
      const scene::SceneDescription md = scene::make_target(
          {scene::TargetKind::kSphere, a, 1.0, 1.0, std::min(lambda / 12.0, 2.0 * kPi * a / 32.0)});
      radar::MomSolver mom(md, pec_surfaces(md));
      mom.factor(f);
      const radar::Direction dir{common::radians(37.0), common::radians(11.0)};
      radar::ScatteringMatrix sm;
      mom.scatter({&dir, 1}, {&dir, 1}, {&sm, 1});
      const double ms =
          std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
      const double got = db10(std::norm(sm.vv));
      mom_ka.push_back(ka);
      mom_norm_db.push_back(got - norm);
      rows.push_back({"sphere", "ka", ka, ms, 0, "mom_minus_mie_db", got - mie, ref_mie, "ok"});
      log("  sphere ka %g, method of moments (%zu unknowns, %.0f ms): %+.2f dB vs Mie\n", ka,
          mom.mesh_info().unknowns, ms, got - mie);
    }
  }
}

// Case 4b: SBR near grazing. A 0.3 m x 0.3 m-face right dihedral at 10 GHz seen in the plane
// normal to its fold, with one face at incidence alpha (80-89 deg): the double-bounce term
// S(max_bounces 2) - S(max_bounces 1) (the facet PO of bounce 1 has no ray-density error,
// radar/em/rcs.hpp) against rays_per_wavelength, error against the densest; an incidence where
// the densest two disagree by more than 0.5 dB is flagged as not converged.
struct GrazingCurve {
  double incidence_deg;
  std::vector<double> rpw, err_db;
};
void grazing_case(bool quick, const Log& log, std::vector<Row>& rows,
                  std::vector<GrazingCurve>& curves) {
  const scene::SceneDescription d =
      scene::make_target({scene::TargetKind::kDihedral, 0.3, 0.3, 1.0, 0.0});
  const scene::Scene scene(d);
  const auto surfaces = pec_surfaces(d);
  const std::vector<double> incidences =
      quick ? std::vector<double>{80.0, 85.0, 89.0, 89.5}
            : std::vector<double>{80.0, 82.0, 84.0, 86.0, 88.0, 89.0, 89.5, 89.8};
  const std::vector<double> rpws = quick ? std::vector<double>{0.5, 1.0, 2.0, 4.0, 8.0, 16.0}
                                         : std::vector<double>{0.5, 1, 2, 4, 8, 16, 32};
  const std::vector<double> freqs{10e9};
  log("grazing: dihedral 0.3 x 0.3 m faces, 10 GHz VV, one face at %g-%g deg incidence, "
      "rays per wavelength %g-%g\n",
      incidences.front(), incidences.back(), rpws.front(), rpws.back());
  for (double alpha : incidences) {
    // Face normals at +-45 deg from +z in the x-z plane: a radar at theta in that plane meets
    // one face at theta + 45 deg (scene/targets.hpp).
    const std::vector<radar::Direction> dir{{common::radians(alpha - 45.0), 0.0}};
    radar::RcsConfig c1;
    c1.max_bounces = 1;
    const Sweep single = rcs_sweep(scene, surfaces, c1, dir, freqs);
    std::vector<Sweep> s;
    for (double rpw : rpws) {
      radar::RcsConfig c;
      c.max_bounces = 2;
      c.rays_per_wavelength = rpw;
      s.push_back(rcs_sweep(scene, surfaces, c, dir, freqs));
      s.back().vv[0] -= single.vv[0];
      s.back().ms += single.ms;
    }
    const double ref_db = db10(std::norm(s.back().vv[0]));
    const double last_two = db10(std::norm(s[s.size() - 2].vv[0])) - ref_db;
    const bool converged = std::abs(last_two) <= 0.5;
    GrazingCurve curve{alpha, {}, {}};
    const std::string metric = "double_bounce_db_error_at_" + fmt("%g", alpha) + "deg";
    const std::string ref = "rays_per_wavelength " + fmt("%g", rpws.back()) + " (densest)";
    for (std::size_t i = 0; i < s.size(); ++i) {
      const bool missing = std::norm(s[i].vv[0]) == 0.0;
      const double err = db10(std::norm(s[i].vv[0])) - ref_db;
      std::string validity = !converged            ? "SBR not converged at this incidence"
                             : missing             ? "no double-bounce path traced at this density"
                             : std::abs(err) > 0.5 ? "not converged at this density (> 0.5 dB)"
                                                   : "ok";
      if (i + 1 == s.size())
        validity = (converged ? "reference (last two within " : "reference NOT converged (") +
                   fmt("%.2f", std::abs(last_two)) + " dB)";
      rows.push_back({"grazing", "rays_per_wavelength", rpws[i], s[i].ms, s[i].rays, metric, err,
                      ref, validity});
      if (i + 1 < s.size() && !missing) {
        curve.rpw.push_back(rpws[i]);
        curve.err_db.push_back(std::abs(err));
      }
    }
    curves.push_back(curve);
    log("  grazing %g deg: double bounce %.2f dBsm at %g rays/lambda; last two differ %.2f dB: "
        "%s\n",
        alpha, ref_db, rpws.back(), std::abs(last_two), converged ? "converged" : "NOT converged");
  }
}

// Case 4c: IEM beyond its validity. sigma0 VV at 10 GHz, 40 deg incidence, eps 15 - j3, against
// ks 0.1-5 for two surfaces: exponential correlation with kl = 3 (where SPM holds at small ks;
// Kirchhoff needs kl >= 6) and Gaussian with kl = 10 (the Kirchhoff regime; SPM needs kl <= 3).
// SPM and Kirchhoff beside IEM, each row flagged with the model's own validity mask
// (radar/clutter/surface.hpp: SPM ks < 0.3, rms slope < 0.3, kl <= 3; KA kl >= 6 and
// l^2 >= 2.76 s lambda; IEM ks <= 3; Ulaby & Long 2014, sec. 10-3).
struct IemSurface {
  std::string tag;  ///< in metric names and labels
  radar::clutter::Correlation correlation;
  double kl;
};
struct IemCurves {
  std::vector<double> ks;
  std::array<std::vector<double>, 3> db;  ///< IEM, SPM, KA
  std::array<std::vector<bool>, 3> valid;
};
void iem_case(bool quick, const Log& log, std::vector<Row>& rows, const IemSurface& surf,
              IemCurves& curves) {
  namespace cl = radar::clutter;
  const double f = 10e9, k = 2.0 * kPi * f / kSpeedOfLight_mps, theta = common::radians(40.0);
  const int n = quick ? 10 : 25;
  log("iem: sigma0 VV at 10 GHz, 40 deg, eps 15-j3, %s, ks 0.1-5 (%d points)\n", surf.tag.c_str(),
      n);
  const std::uint32_t ignore = cl::kCrossPolNotModelled;
  for (int i = 0; i < n; ++i) {
    const double ks = 0.1 * std::pow(50.0, static_cast<double>(i) / (n - 1));
    cl::SurfaceParams p;
    p.relative_permittivity = {15.0, -3.0};
    p.roughness.rms_height_m = ks / k;
    p.roughness.corr_length_m = surf.kl / k;
    p.roughness.correlation = surf.correlation;
    cl::validate(p, f);
    const cl::Geometry g = cl::Geometry::backscatter(theta);
    const auto t0 = Clock::now();
    const cl::SurfaceScatter iem = cl::iem(p, f, g, cl::IemConventions::kPublishedEquations, false);
    const double cost = ms_since(t0);
    const cl::SurfaceScatter spm = cl::spm(p, f, g);
    const cl::SurfaceScatter ka = cl::kirchhoff(p, f, g);
    const std::array<const cl::SurfaceScatter*, 3> m{&iem, &spm, &ka};
    curves.ks.push_back(ks);
    std::array<std::string, 3> why;
    for (std::size_t j = 0; j < 3; ++j) {
      const std::uint32_t flags = m[j]->invalid & ~ignore;
      curves.db[j].push_back(db10(m[j]->incoherent.vv));
      curves.valid[j].push_back(flags == 0);
      why[j] = flags == 0 ? "ok" : cl::describe_validity(flags);
    }
    const std::string iem_validity = why[0] == "ok" ? "ok" : "IEM outside validity: " + why[0];
    const std::string sfx = "_" + surf.tag;
    rows.push_back({"iem", "ks", ks, cost, 0, "sigma0_vv_iem_db" + sfx, curves.db[0].back(),
                    "none (model value)", iem_validity});
    rows.push_back({"iem", "ks", ks, cost, 0, "iem_minus_spm_vv_db" + sfx,
                    curves.db[0].back() - curves.db[1].back(), "SPM (first order)",
                    why[1] == "ok" ? iem_validity : "SPM outside validity: " + why[1]});
    rows.push_back({"iem", "ks", ks, cost, 0, "iem_minus_ka_vv_db" + sfx,
                    curves.db[0].back() - curves.db[2].back(), "Kirchhoff (KA)",
                    why[2] == "ok" ? iem_validity : "KA outside validity: " + why[2]});
    log("  iem %s ks %.3g: IEM %.2f dB%s, SPM %.2f dB%s, KA %.2f dB%s\n", surf.tag.c_str(), ks,
        curves.db[0].back(), curves.valid[0].back() ? "" : " [invalid]", curves.db[1].back(),
        curves.valid[1].back() ? "" : " [invalid]", curves.db[2].back(),
        curves.valid[2].back() ? "" : " [invalid]");
  }
}

// ---------------------------------------------------------------------------------------------
// Case 3: one closed-loop frame of the default scenario

struct FrameSetting {
  double target_spacing_m, terrain_spacing_rad;
  int bounces, pulses;
  /// >= 0: the scenario's own sampling (the first four fields ignored but pulses) at this level
  /// of the fidelity governor (loop/governor.hpp).
  int governor_level = -1;
  /// [radar] terrain = "engine": the engine's column width [rad]; 0: the scenario's.
  double terrain_cell_rad = 0.0;
};

struct FrameResult {
  std::vector<radar::Detection> detections;
  double trace_ms = 0.0, sensor_ms = 0.0;
  std::uint64_t rays = 0, coarsened = 0, contributions = 0;
  std::uint64_t terrain_returns = 0;  ///< the terrain engine's cells ([radar] terrain = "engine")
};

class FrameBench {
 public:
  FrameBench(std::size_t max_rays_per_target)
      : s_(parse_scenario(default_scenario_toml(), "<default scenario>")),
        scene_(scene_description(s_)),
        pose_(scripted_pose(s_)),
        max_rays_per_target_(max_rays_per_target) {
    scene_.set_time(0.0);
  }

  /// The pose and the scene at scenario time t_s along the ownship's straight flight.
  void set_time(double t_s) {
    pose_ = scripted_pose(s_, t_s);
    scene_.set_time(t_s);
  }

  FrameResult run(const FrameSetting& f) {
    radar::SbrConfig c = s_.sbr;
    if (f.governor_level < 0) {
      c.target_ray_spacing_m = f.target_spacing_m;
      c.terrain_ray_spacing_rad = f.terrain_spacing_rad;
      c.max_bounces = f.bounces;
      c.max_rays_per_target = max_rays_per_target_;
    }
    // The closed loop's view volume (loop/closed_loop.cpp): terrain level of detail follows
    // the terrain ray spacing.
    scene::ViewVolume view;
    view.position_m = pose_.position_m;
    view.world_from_antenna = pose_.world_from_antenna;
    view.azimuth_min_rad = c.azimuth_min_rad;
    view.azimuth_max_rad = c.azimuth_max_rad;
    view.elevation_min_rad = c.elevation_min_rad;
    view.elevation_max_rad = c.elevation_max_rad;
    view.max_range_m = c.max_range_m;
    view.range_cell_m = radar::range_resolution_m(s_.sensor.processing.waveform);
    view.angular_cell_rad = c.terrain_ray_spacing_rad;
    scene_.set_view(view);
    radar::SbrTracer tracer(scene_, c);
    // [radar] terrain = "engine" (the default): terrain clutter from the engine's cells, as the
    // closed loop takes it (loop/closed_loop.cpp); the tracer's terrain rays are off.
    std::optional<radar::TerrainReturns> terrain;
    if (s_.terrain_engine) {
      radar::TerrainReturnsConfig tc = terrain_returns_config(s_);
      if (f.terrain_cell_rad > 0.0)
        tc.azimuth_cell_rad = f.terrain_cell_rad;
      terrain.emplace(scene_, tracer, tc);
    }
    const std::size_t cap = tracer.max_contributions();
    std::vector<radar::Contribution> contributions(cap + (terrain ? terrain->max_returns() : 0));
    FrameResult r;
    radar::TraceStats ts;
    radar::SensorConfig sc = s_.sensor;
    sc.thermal_noise = false;  // deterministic comparison
    sc.processing.waveform.pulses = f.pulses;
    sc.max_contributions = std::max<std::size_t>(sc.max_contributions, contributions.size());
    sc.max_detections = 512;  // no truncation difference between settings
    radar::Sensor sensor(sc);
    radar::TraceKnobs knobs;
    std::optional<FidelityGovernor> governor;
    if (f.governor_level >= 0) {
      governor.emplace(s_.governor, scene_, tracer, sensor, 1.0 / s_.rate_hz);
      knobs = governor->decide_at(pose_, f.governor_level).knobs;
    }
    auto t0 = Clock::now();
    std::size_t n = 0;
    if (terrain) {
      // Beside each other on TBB, each into its own part of the buffer, as in the loop.
      const std::span<radar::Contribution> all(contributions);
      std::size_t m = 0;
      radar::clutter::TerrainStats es;
      std::uint64_t dropped = 0;
      tbb::parallel_invoke([&] { n = tracer.trace(pose_, all.first(cap), ts, knobs); },
                           [&] {
                             m = terrain->compute(pose_, all.subspan(cap), es, dropped,
                                                  knobs.terrain_spacing_scale);
                           });
      std::copy_n(all.begin() + static_cast<std::ptrdiff_t>(cap), m,
                  all.begin() + static_cast<std::ptrdiff_t>(n));
      n += m;
      r.terrain_returns = m;
    } else {
      n = tracer.trace(pose_, contributions, ts, knobs);
    }
    r.trace_ms = ms_since(t0);
    r.rays = ts.rays;
    r.coarsened = ts.coarsened_bundles;
    r.contributions = n;
    r.detections.resize(sc.max_detections);
    radar::SensorStats ss;
    t0 = Clock::now();
    const std::size_t nd = sensor.process(
        std::span<const radar::Contribution>(contributions.data(), n), r.detections, ss);
    r.sensor_ms = ms_since(t0);
    r.detections.resize(nd);
    range_cell_m_ = sensor.range_cell_m();
    return r;
  }
  [[nodiscard]] const Scenario& scenario() const noexcept { return s_; }
  void set_max_rays_per_target(std::size_t n) noexcept { max_rays_per_target_ = n; }
  [[nodiscard]] double range_cell_m() const noexcept { return range_cell_m_; }

 private:
  Scenario s_;
  scene::Scene scene_;
  radar::RadarPose pose_;
  std::size_t max_rays_per_target_;
  double range_cell_m_ = 1.0;
};

struct MatchStats {
  std::size_t matched = 0, missed = 0, added = 0;
  double range_m = 0.0, azimuth_deg = 0.0, snr_db = 0.0;  ///< mean absolute errors
};

// Gated global-nearest-neighbour assignment, done greedily (Blackman & Popoli, Design and
// Analysis of Modern Tracking Systems, 1999, sec. 6.2-6.4: rectangular gates, then the closest
// pairs first): a pair may match when |dR| <= range gate and |dAz| <= azimuth gate; pairs are
// taken by increasing normalised distance (dR/gate)^2 + (dAz/gate)^2.
MatchStats match(const std::vector<radar::Detection>& ref, const std::vector<radar::Detection>& d,
                 double range_gate_m, double azimuth_gate_rad) {
  struct Pair {
    double cost;
    std::size_t i, j;
  };
  std::vector<Pair> pairs;
  for (std::size_t i = 0; i < ref.size(); ++i)
    for (std::size_t j = 0; j < d.size(); ++j) {
      const double dr = std::abs(ref[i].range_m - d[j].range_m);
      const double da = std::abs(ref[i].azimuth_rad - d[j].azimuth_rad);
      if (dr <= range_gate_m && da <= azimuth_gate_rad) {
        const double a = dr / range_gate_m, b = da / azimuth_gate_rad;
        pairs.push_back({a * a + b * b, i, j});
      }
    }
  std::sort(pairs.begin(), pairs.end(), [](const Pair& x, const Pair& y) {
    return x.cost < y.cost || (x.cost == y.cost && (x.i < y.i || (x.i == y.i && x.j < y.j)));
  });
  std::vector<bool> used_ref(ref.size()), used_d(d.size());
  MatchStats m;
  for (const Pair& p : pairs) {
    if (used_ref[p.i] || used_d[p.j])
      continue;
    used_ref[p.i] = used_d[p.j] = true;
    ++m.matched;
    m.range_m += std::abs(ref[p.i].range_m - d[p.j].range_m);
    m.azimuth_deg += std::abs(ref[p.i].azimuth_rad - d[p.j].azimuth_rad) / common::kRadPerDeg;
    m.snr_db += std::abs(db10(ref[p.i].snr) - db10(d[p.j].snr));
  }
  if (m.matched > 0) {
    const auto n = static_cast<double>(m.matched);
    m.range_m /= n;
    m.azimuth_deg /= n;
    m.snr_db /= n;
  }
  m.missed = ref.size() - m.matched;
  m.added = d.size() - m.matched;
  return m;
}

struct FrameKnob {
  std::string name;
  std::vector<double> values;  ///< coarse to fine, the last equal to the reference's
};

void frame_case(bool quick, const Log& log, std::vector<Row>& rows) {
  // Reference: every knob at its finest, the others held there while one knob moves. The
  // per-target ray cap is raised so that a bundle's spacing is the knob's value (the default
  // scenario caps bundles at 20,000 rays and coarsens the larger ones).
  // With the terrain engine (the default scenario's [radar] terrain = "engine") the terrain
  // knob is the engine's column width (0.25 deg in the reference, a quarter of the beamwidth);
  // with the tracer's terrain rays, their spacing.
  const double deg = common::kRadPerDeg;
  FrameSetting ref_setting{0.05, 0.5e-3, 4, 64, -1, 0.25 * deg};
  std::size_t cap = 100'000;
  std::vector<FrameKnob> knobs(4);
  knobs[0].name = "target_ray_spacing_m";
  knobs[0].values = {0.4, 0.2, 0.1, 0.05};
  FrameBench bench(cap);
  const bool engine = bench.scenario().terrain_engine;
  knobs[1].name = engine ? "terrain_cell_azimuth_rad" : "terrain_ray_spacing_rad";
  knobs[1].values = engine ? std::vector<double>{2.0 * deg, 1.0 * deg, 0.5 * deg, 0.25 * deg}
                           : std::vector<double>{4e-3, 2e-3, 1e-3, 0.5e-3};
  knobs[2].name = "max_bounces";
  knobs[2].values = {1, 2, 3, 4};
  knobs[3].name = "pulses";
  knobs[3].values = {8, 16, 32, 64};

  if (quick) {
    ref_setting = {0.1, 1e-3, 3, 32, -1, 0.25 * deg};
    cap = 20'000;
    bench.set_max_rays_per_target(cap);
    // Coarse grids: each knob's finest value goes (the reference is coarser too), but the
    // engine's columns keep their 0.25 deg reference and lose the 2 deg setting instead (columns
    // of 1 and 2 deg, one and two beamwidths, both misplace the clutter between beams alike).
    for (FrameKnob& k : knobs) {
      if (k.name == "terrain_cell_azimuth_rad")
        k.values.erase(k.values.begin());
      else
        k.values.pop_back();
    }
  }
  log("frame: default scenario (%s) at its start pose, thermal noise off\n",
      bench.scenario().name.c_str());
  const FrameResult ref = bench.run(ref_setting);
  const double range_gate_m = 2.0 * bench.range_cell_m();
  const double az_gate_rad = common::radians(0.5);
  char terrain_text[64];
  if (engine)
    std::snprintf(terrain_text, sizeof terrain_text, "terrain engine, %g deg columns",
                  ref_setting.terrain_cell_rad / deg);
  else
    std::snprintf(terrain_text, sizeof terrain_text, "terrain rays %g mrad",
                  ref_setting.terrain_spacing_rad * 1e3);
  char ref_text[256];
  std::snprintf(ref_text, sizeof ref_text,
                "target %g m; %s; %d bounces; %d pulses; %zu rays a target max; "
                "no thermal noise (%zu detections)",
                ref_setting.target_spacing_m, terrain_text, ref_setting.bounces, ref_setting.pulses,
                cap, ref.detections.size());
  log("  reference: %s; %llu rays (%llu bundles coarsened), %llu terrain engine cells, trace %.0f "
      "ms, sensor %.0f ms; gates %.2f m, %.2f deg\n",
      ref_text, static_cast<unsigned long long>(ref.rays),
      static_cast<unsigned long long>(ref.coarsened),
      static_cast<unsigned long long>(ref.terrain_returns), ref.trace_ms, ref.sensor_ms,
      range_gate_m, az_gate_rad / common::kRadPerDeg);
  for (const FrameKnob& k : knobs) {
    for (std::size_t i = 0; i < k.values.size(); ++i) {
      const bool is_ref = i + 1 == k.values.size();
      FrameSetting fs = ref_setting;
      if (k.name == "target_ray_spacing_m")
        fs.target_spacing_m = k.values[i];
      else if (k.name == "terrain_ray_spacing_rad")
        fs.terrain_spacing_rad = k.values[i];
      else if (k.name == "terrain_cell_azimuth_rad")
        fs.terrain_cell_rad = k.values[i];
      else if (k.name == "max_bounces")
        fs.bounces = static_cast<int>(k.values[i]);
      else
        fs.pulses = static_cast<int>(k.values[i]);
      // The reference setting is run again for its cost (and its zero error is a check of
      // determinism, not of accuracy).
      const FrameResult r = bench.run(fs);
      const MatchStats m = match(ref.detections, r.detections, range_gate_m, az_gate_rad);
      const double cost = r.trace_ms + r.sensor_ms;
      const std::string validity = is_ref ? "reference setting (rerun)" : "ok";
      auto add = [&](const char* metric, double v) {
        rows.push_back({"frame", k.name, k.values[i], cost, r.rays, metric, v, ref_text, validity});
      };
      add("detections", static_cast<double>(r.detections.size()));
      add("matched", static_cast<double>(m.matched));
      add("missed", static_cast<double>(m.missed));
      add("added", static_cast<double>(m.added));
      add("missed_plus_added", static_cast<double>(m.missed + m.added));
      add("mean_abs_range_error_m", m.range_m);
      add("mean_abs_azimuth_error_deg", m.azimuth_deg);
      add("mean_abs_snr_error_db", m.snr_db);
      log("  frame %s %g: %.0f ms (trace %.0f, sensor %.0f), %llu rays: %zu detections, %zu "
          "matched, %zu missed, %zu added; |dR| %.3f m, |dAz| %.4f deg, |dSNR| %.2f dB\n",
          k.name.c_str(), k.values[i], cost, r.trace_ms, r.sensor_ms,
          static_cast<unsigned long long>(r.rays), r.detections.size(), m.matched, m.missed,
          m.added, m.range_m, m.azimuth_deg, m.snr_db);
    }
  }

  // The fidelity governor's levels over the scenario's own sampling (level 0 is the scenario,
  // not the reference), pooled over frames along the approach: each frame against the
  // reference at the same pose. The mean |SNR error| per level is the governor's estimated
  // error (loop/governor.cpp, kLevelSnrError_db).
  const std::vector<double> times_s =
      quick ? std::vector<double>{0.0} : std::vector<double>{0.0, 3.0, 6.0, 9.0};
  const std::vector<int> levels =
      quick ? std::vector<int>{4, 2, 0} : std::vector<int>{10, 8, 6, 5, 4, 3, 2, 1, 0};
  struct Pool {
    std::size_t detections = 0, matched = 0, missed = 0, added = 0;
    double range_m = 0, azimuth_deg = 0, snr_db = 0, cost_ms = 0;
    std::uint64_t rays = 0;
    // The spread over the frames pooled: cost, |SNR error| and missed + added per frame.
    double cost_lo = std::numeric_limits<double>::infinity(), cost_hi = 0.0;
    double snr_lo = std::numeric_limits<double>::infinity(), snr_hi = 0.0;
    double wrong_lo = std::numeric_limits<double>::infinity(), wrong_hi = 0.0;
  };
  std::vector<Pool> pools(levels.size());
  for (double t : times_s) {
    bench.set_time(t);
    const FrameResult rt = bench.run(ref_setting);
    for (std::size_t i = 0; i < levels.size(); ++i) {
      FrameSetting fs = ref_setting;
      fs.governor_level = levels[i];
      fs.terrain_cell_rad = 0.0;  // the scenario's, as the other sampling
      const FrameResult r = bench.run(fs);
      const MatchStats m = match(rt.detections, r.detections, range_gate_m, az_gate_rad);
      Pool& p = pools[i];
      p.detections += r.detections.size();
      p.matched += m.matched;
      p.missed += m.missed;
      p.added += m.added;
      const auto n = static_cast<double>(m.matched);
      p.range_m += m.range_m * n;
      p.azimuth_deg += m.azimuth_deg * n;
      p.snr_db += m.snr_db * n;
      p.cost_ms += (r.trace_ms + r.sensor_ms) / static_cast<double>(times_s.size());
      p.cost_lo = std::min(p.cost_lo, r.trace_ms + r.sensor_ms);
      p.cost_hi = std::max(p.cost_hi, r.trace_ms + r.sensor_ms);
      if (m.matched > 0) {
        p.snr_lo = std::min(p.snr_lo, m.snr_db);
        p.snr_hi = std::max(p.snr_hi, m.snr_db);
      }
      const auto wrong = static_cast<double>(m.missed + m.added);
      p.wrong_lo = std::min(p.wrong_lo, wrong);
      p.wrong_hi = std::max(p.wrong_hi, wrong);
      p.rays += r.rays / times_s.size();
    }
  }
  bench.set_time(0.0);
  std::string ref_pooled = std::string(ref_text) + "; pooled over frames at t =";
  for (double t : times_s)
    ref_pooled += " " + std::to_string(static_cast<int>(t)) + " s";
  for (std::size_t i = 0; i < levels.size(); ++i) {
    const Pool& p = pools[i];
    const double n = p.matched > 0 ? static_cast<double>(p.matched) : 1.0;
    auto add = [&](const char* metric, double v, double lo = std::nan(""),
                   double hi = std::nan("")) {
      Row row{"frame",   "governor_level", static_cast<double>(levels[i]),
              p.cost_ms, p.rays,           metric,
              v,         ref_pooled,       "ok"};
      if (times_s.size() > 1) {
        row.cost_lo_ms = p.cost_lo;
        row.cost_hi_ms = p.cost_hi;
        row.error_lo = lo;
        row.error_hi = hi;
      }
      rows.push_back(std::move(row));
    };
    add("detections", static_cast<double>(p.detections));
    add("matched", static_cast<double>(p.matched));
    add("missed", static_cast<double>(p.missed));
    add("added", static_cast<double>(p.added));
    // (Pooled: the sum over the frames; its spread is that of a frame times the frames.)
    const auto frames = static_cast<double>(times_s.size());
    add("missed_plus_added", static_cast<double>(p.missed + p.added), p.wrong_lo * frames,
        p.wrong_hi * frames);
    add("mean_abs_range_error_m", p.range_m / n);
    add("mean_abs_azimuth_error_deg", p.azimuth_deg / n);
    add("mean_abs_snr_error_db", p.snr_db / n, p.snr_hi >= p.snr_lo ? p.snr_lo : std::nan(""),
        p.snr_hi >= p.snr_lo ? p.snr_hi : std::nan(""));
    log("  frame governor_level %d (%zu frames): %.0f ms a frame, %llu rays: %zu detections, %zu "
        "matched, %zu missed, %zu added; |dR| %.3f m, |dAz| %.4f deg, |dSNR| %.2f dB\n",
        levels[i], times_s.size(), p.cost_ms, static_cast<unsigned long long>(p.rays), p.detections,
        p.matched, p.missed, p.added, p.range_m / n, p.azimuth_deg / n, p.snr_db / n);
  }
}

// ---------------------------------------------------------------------------------------------
// Charts (plot/charts.hpp): a marker at every point, the legend outside the plot.

using PlotSeries = Series;

struct Plot : LineChart {
  Plot() {
    width = 1200;
    height = 820;
  }
};

void write_plot_png(Plot plot, const std::filesystem::path& path) {
  for (Series& s : plot.series)
    s.markers = true;
  write_line_chart_png(plot, path);
}

// ---------------------------------------------------------------------------------------------

// `incomplete`: "" or a last comment line ("# incomplete: ...") for a run stopped early.
void write_csv(const std::vector<Row>& rows, const std::filesystem::path& path,
               const std::string& incomplete) {
  FILE* f = std::fopen(path.string().c_str(), "w");
  if (f == nullptr)
    throw std::runtime_error(path.string() + ": cannot open for writing");
  std::fprintf(f, "case,knob,value,cost_ms,rays,metric,error,reference,validity\n");
  for (const Row& r : rows)
    std::fprintf(f, "%s,%s,%.6g,%.3f,%llu,%s,%.6g,\"%s\",\"%s\"\n", r.case_name.c_str(),
                 r.knob.c_str(), r.value, r.cost_ms, static_cast<unsigned long long>(r.rays),
                 r.metric.c_str(), r.error, r.reference.c_str(), r.validity.c_str());
  if (!incomplete.empty())
    std::fprintf(f, "%s\n", incomplete.c_str());
  const bool ok = std::fflush(f) == 0 && std::ferror(f) == 0;  // a full disk shows at flush
  if (std::fclose(f) != 0 || !ok)
    throw std::runtime_error(path.string() + ": write failed");
}

// Errors below this are drawn at it (a frame whose detections all match to 1e-6 dB would
// otherwise stretch the log axis over six empty decades).
constexpr double kChartFloorDb = 0.01;

// The knobs of the cases, in the order of their series (a knob keeps its colour in every panel).
const std::array<const char*, 7> kKnobs{
    "rays_per_wavelength",      "max_bounces", "target_ray_spacing_m", "terrain_ray_spacing_rad",
    "terrain_cell_azimuth_rad", "pulses",      "governor_level"};

// One panel of the summary: error against cost for one error metric, a series per knob, each
// point labelled with its knob value and, where it pools several frames, bars over their
// spread. The reference settings (zero error by construction) are left out.
struct MetricPanel {
  const char* case_name;
  const char* metric;
  const char* title;
  const char* y_label;
  bool log_y;
};

LineChart metric_panel(const std::vector<Row>& rows, const MetricPanel& mp) {
  LineChart p;
  p.title = mp.title;
  p.x_label = "cost [ms] (wall, 2 threads)";
  p.y_label = mp.y_label;
  p.log_x = true;
  p.log_y = mp.log_y;
  p.legend_below = true;
  auto floor = [&](double v) { return mp.log_y ? std::max(v, kChartFloorDb) : v; };
  for (std::size_t k = 0; k < kKnobs.size(); ++k) {
    PlotSeries s;
    s.label = kKnobs[k];
    s.colour = series_colour(k);
    s.markers = true;
    bool spread = false;
    for (const Row& r : rows) {
      if (r.case_name != mp.case_name || r.knob != kKnobs[k] || r.metric != mp.metric ||
          r.validity.rfind("reference", 0) == 0)
        continue;
      s.x.push_back(r.cost_ms);
      s.y.push_back(floor(r.error));
      s.point_labels.push_back(fmt("%g", r.value));
      const bool has = std::isfinite(r.cost_lo_ms) && std::isfinite(r.error_lo);
      spread = spread || has;
      s.x_lo.push_back(has ? r.cost_lo_ms : r.cost_ms);
      s.x_hi.push_back(has ? r.cost_hi_ms : r.cost_ms);
      s.y_lo.push_back(has ? floor(r.error_lo) : s.y.back());
      s.y_hi.push_back(has ? floor(r.error_hi) : s.y.back());
    }
    if (!spread)
      s.x_lo = s.x_hi = s.y_lo = s.y_hi = {};
    else
      s.label += " (bars: spread over the frames pooled)";
    if (!s.x.empty())
      p.series.push_back(std::move(s));
  }
  return p;
}

// The summary: one panel per error metric measured (two columns), error against cost.
plot::Figure summary_figure(const std::vector<Row>& rows) {
  static const std::array<MetricPanel, 4> panels{{
      {"vehicle", "rcs_vv_db_rms", "vehicle RCS over a turn: RMS error against the finest",
       "RCS error [dB RMS] (floored at 0.01 dB)", true},
      {"profile", "profile_db_rms_within_30db", "vehicle range profile: RMS error (top 30 dB)",
       "profile error [dB RMS] (floored at 0.01 dB)", true},
      {"frame", "mean_abs_snr_error_db", "default frame: mean |SNR error| of matched detections",
       "|SNR error| [dB] (floored at 0.01 dB)", true},
      {"frame", "missed_plus_added", "default frame: detections missed + added",
       "missed + added detections [count]", false},
  }};
  plot::Figure f;
  f.title =
      "radar-emu tradeoff: error against cost, one panel per error metric (point labels: "
      "the knob's value)";
  f.columns = 2;
  for (const MetricPanel& mp : panels) {
    LineChart p = metric_panel(rows, mp);
    if (!p.series.empty())
      f.panels.emplace_back(std::move(p));
  }
  const int n = static_cast<int>(f.panels.size());
  f.columns = n > 1 ? 2 : 1;
  f.width = n > 1 ? 1500 : 900;
  f.height = 150 + 560 * ((n + 1) / 2);
  return f;
}

}  // namespace

const std::vector<std::string>& tradeoff_case_names() {
  static const std::vector<std::string> names{"vehicle", "profile", "frame",
                                              "sphere",  "grazing", "iem"};
  return names;
}

std::vector<std::string> parse_tradeoff_cases(std::string_view text) {
  std::vector<std::string> out;
  std::size_t start = 0;
  const auto& known = tradeoff_case_names();
  std::string list;
  for (const auto& n : known)
    list += (list.empty() ? "" : ",") + n;
  while (start <= text.size()) {
    const std::size_t comma = std::min(text.find(',', start), text.size());
    const std::string name(text.substr(start, comma - start));
    if (std::find(known.begin(), known.end(), name) == known.end())
      throw std::invalid_argument("--cases: '" + name + "' is not a case (expected a list of " +
                                  list + ")");
    if (std::find(out.begin(), out.end(), name) == out.end())
      out.push_back(name);
    start = comma + 1;
  }
  return out;
}

int run_tradeoff_tool(const TradeoffOptions& o) {
  const std::vector<std::string> cases = o.cases.empty() ? tradeoff_case_names() : o.cases;
  for (const auto& c : cases)
    (void)parse_tradeoff_cases(c);  // names checked before any work
  if (o.out_dir.empty())
    throw std::invalid_argument("--out: expected a directory");
  const std::filesystem::path dir(o.out_dir);
  std::error_code ec;
  std::filesystem::create_directories(dir, ec);
  if (ec || !std::filesystem::is_directory(dir))
    throw std::runtime_error("--out: cannot create directory " + o.out_dir);
  const Log log(o.quiet, o.control);
  auto has = [&](const char* c) { return std::find(cases.begin(), cases.end(), c) != cases.end(); };
  const auto t_start = Clock::now();
  std::vector<Row> rows;
  std::vector<std::string> written;
  // A stop request is heard between cases: the cases done keep their rows and charts, the rest
  // are left out, and the CSV's last line says so.
  std::size_t cases_done = 0;
  std::string stopped_before;  // the first case not run
  auto run_case = [&](const char* c) {
    if (!has(c) || !stopped_before.empty())
      return false;
    if (o.control.stop_signal() != 0) {
      stopped_before = c;
      return false;
    }
    return true;
  };
  auto case_done = [&] { o.control.report(++cases_done, cases.size()); };
  o.control.report(0, cases.size());
  std::unique_ptr<Vehicle> vehicle;
  if (has("vehicle") || has("profile"))
    vehicle = std::make_unique<Vehicle>();
  if (run_case("vehicle")) {
    vehicle_case(*vehicle, o.quick, log, rows);
    case_done();
  }
  if (run_case("profile")) {
    profile_case(*vehicle, o.quick, log, rows);
    case_done();
  }
  const bool frame_run = run_case("frame");
  if (frame_run) {
    frame_case(o.quick, log, rows);
    case_done();
  }
  if (run_case("sphere")) {
    std::vector<double> ka;
    std::array<std::vector<double>, 3> norm;
    std::vector<double> mom_ka, mom_norm;
    sphere_case(o.quick, log, rows, ka, norm, mom_ka, mom_norm);
    Plot p;
    p.title = "PEC sphere: PO and the method of moments against Mie; PO invalid below ka 10";
    p.x_label = "ka (wavenumber x radius) [1]";
    p.y_label = "sigma / (pi a^2) [dB]";
    p.log_x = true;
    p.series = {{"PO, faceted sphere (RcsEngine, 1 bounce)", ka, norm[0]},
                {"PO closed form", ka, norm[1]},
                {"Mie series (exact)", ka, norm[2]},
                {"method of moments (EFIE)", mom_ka, mom_norm}};
    write_plot_png(p, dir / "tradeoff_sphere.png");
    written.push_back("tradeoff_sphere.png");
    case_done();
  }
  if (run_case("grazing")) {
    std::vector<GrazingCurve> curves;
    grazing_case(o.quick, log, rows, curves);
    Plot p;
    p.title = "Dihedral double bounce near grazing: |error| against the densest rays, 10 GHz";
    p.x_label = "ray density [rays per wavelength]";
    p.y_label = "|error| [dB]";
    p.log_x = p.log_y = true;
    for (const auto& c : curves)
      p.series.push_back(
          {"one face at " + fmt("%g", c.incidence_deg) + " deg incidence", c.rpw, c.err_db});
    write_plot_png(p, dir / "tradeoff_grazing.png");
    written.push_back("tradeoff_grazing.png");
    case_done();
  }
  if (run_case("iem")) {
    namespace cl = radar::clutter;
    const std::array<IemSurface, 2> surfaces{{{"exp_kl3", cl::Correlation::kExponential, 3.0},
                                              {"gauss_kl10", cl::Correlation::kGaussian, 10.0}}};
    Plot p;
    p.title = "sigma0 VV, 10 GHz, 40 deg, eps 15-j3: IEM, SPM, Kirchhoff inside/outside validity";
    p.x_label = "ks (wavenumber x rms height) [1]";
    p.y_label = "sigma0 VV [dB]";
    p.log_x = true;
    for (const IemSurface& surf : surfaces) {
      IemCurves curves;
      iem_case(o.quick, log, rows, surf, curves);
      // The model that can hold on this surface beside IEM: SPM (kl 3) or Kirchhoff (kl 10).
      const std::array<std::size_t, 2> models{0, surf.kl <= 3.0 ? std::size_t{1} : std::size_t{2}};
      const std::array<const char*, 3> names{"IEM", "SPM", "Kirchhoff"};
      for (std::size_t j : models) {
        PlotSeries in{std::string(names[j]) + " " + surf.tag + " (valid)", {}, {}};
        PlotSeries out{std::string(names[j]) + " " + surf.tag + " (outside validity)", {}, {}};
        out.dashed = true;
        in.colour = out.colour = series_colour(p.series.size() / 2);
        for (std::size_t i = 0; i < curves.ks.size(); ++i) {
          const bool v = curves.valid[j][i];
          in.x.push_back(curves.ks[i]);
          in.y.push_back(v ? curves.db[j][i] : std::nan(""));
          out.x.push_back(curves.ks[i]);
          out.y.push_back(v ? std::nan("") : curves.db[j][i]);
        }
        p.series.push_back(std::move(in));
        p.series.push_back(std::move(out));
      }
    }
    write_plot_png(p, dir / "tradeoff_iem.png");
    written.push_back("tradeoff_iem.png");
    case_done();
  }
  if (frame_run) {
    LineChart p = metric_panel(
        rows, {"frame", "missed_plus_added",
               "Default-scenario frame: detections missed + added against the reference frame",
               "missed + added detections [count]", false});
    p.x_label = "frame cost: trace + sensor [ms] (wall, 2 threads)";
    p.width = 1200;
    p.height = 820;
    p.legend_below = std::nullopt;
    plot::write_line_chart_png(p, dir / "tradeoff_frame.png");
    written.push_back("tradeoff_frame.png");
  }
  std::string incomplete;
  if (!stopped_before.empty()) {
    incomplete = "# incomplete: stopped by " + config::signal_name(o.control.stop_signal()) +
                 " after " + std::to_string(cases_done) + " of " + std::to_string(cases.size()) +
                 " cases, before " + stopped_before + " (" + std::to_string(rows.size()) + " rows)";
  }
  write_csv(rows, dir / "tradeoff.csv", incomplete);
  written.insert(written.begin(), "tradeoff.csv");
  plot::Figure summary = summary_figure(rows);
  if (!summary.panels.empty()) {
    plot::write_figure(std::move(summary), dir / "tradeoff.png");
    written.insert(written.begin() + 1, "tradeoff.png");
  }
  if (!o.quiet) {
    std::printf("tradeoff: %zu rows from %zu case(s) in %.1f s; wrote", rows.size(), cases.size(),
                ms_since(t_start) * 1e-3);
    for (const auto& w : written)
      std::printf(" %s", (dir / w).string().c_str());
    std::printf("\n");
  }
  return stopped_before.empty() ? 0 : 128 + o.control.stop_signal();
}

}  // namespace radar_emu::tools
