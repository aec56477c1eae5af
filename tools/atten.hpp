#pragma once
// `radar-emu atten`: specific attenuation of gases (ITU-R P.676-13), rain (P.838-3) and fog or
// cloud (P.840-9), and the excess loss of a woodland crossing (P.833-10 sec. 2), over a
// frequency sweep, as CSV and a chart.

#include <string>
#include <vector>

namespace radar_emu::tools {

struct AttenToolOptions {
  std::vector<double> freqs_hz;
  double dry_pressure_hpa = 1013.25;
  double temperature_c = 15.0;
  double water_vapour_gm3 = 7.5;
  double rain_mm_per_h = 0.0;
  double fog_gm3 = 0.0;
  double veg_depth_m = 0.0;  ///< woodland crossed (P.833), one way
  bool out_of_leaf = false;
  std::string out_csv = "atten.csv";
  std::string plot_png;
  bool quiet = false;
};

/// Writes `freq_hz,gas_dry_db_km,gas_vapour_db_km,rain_h_db_km,rain_v_db_km,fog_db_km,veg_db`
/// (rain on a horizontal path; veg_db: P.833 excess loss of veg_depth_m of woodland, one way,
/// left empty outside P.833's 1-30 GHz). Throws std::invalid_argument naming the model and the
/// input out of range.
int run_atten_tool(const AttenToolOptions& options);

}  // namespace radar_emu::tools
