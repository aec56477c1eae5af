#pragma once
// `radar-emu sigma0`: terrain backscattering (or bistatic scattering) coefficient against angle
// for a catalogue material or a surface given by its parameters, under one of the clutter
// models (radar/clutter), as CSV and a chart, with each row's validity.

#include <optional>
#include <string>
#include <vector>

namespace radar_emu::tools {

struct Sigma0ToolOptions {
  std::string material;                      ///< catalogue name, or empty for a custom surface
  std::optional<double> eps_real, eps_loss;  ///< custom: eps = eps_real - j eps_loss
  std::optional<double> rms_height_m, corr_length_m;
  std::string correlation = "exponential";  ///< gaussian | exponential | xpower
  double x_power = 1.5;
  double freq_hz = 0.0;
  std::string model = "total";
  std::vector<double> theta_deg;    ///< incidence angles
  std::vector<double> theta_s_deg;  ///< bistatic scattering angles (empty: backscatter)
  double phi_s_deg = 0.0;
  std::string pols = "HH,VV,HV,VH";
  std::string out_csv = "sigma0.csv";
  std::string plot_png;
  bool quiet = false;
  std::string catalogue_chart_png;  ///< --catalogue-chart: run_catalogue_chart()
  std::string chart_materials = "grass,asphalt,forest,water";
  std::string points_csv = "tests/data/sigma0_catalogue_points.csv";
};

/// Writes `theta_deg[,theta_s_deg,phi_s_deg],sigma0_P_db...,valid,flags` (flags: the
/// validity bits of radar/clutter/surface.hpp, e.g. 1024 kOutsideMeasuredRange, 2048
/// kAssumedValue of the catalogue). Throws std::invalid_argument with a one-line reason for
/// unusable input.
int run_sigma0_tool(const Sigma0ToolOptions& options);

/// The catalogue chart (docs/validation.md): three panels (10, 35, 94 GHz), sigma0 VV of each of
/// `chart_materials` against incidence 0-89.9 deg (dashed where flagged assumed or outside the
/// measured range), with the points of `points_csv` within 10 % of the panel's frequency.
int run_catalogue_chart(const Sigma0ToolOptions& options);

}  // namespace radar_emu::tools
