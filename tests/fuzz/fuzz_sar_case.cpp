// Harness: the TOML case parser of `radar-emu sar` (tools/sar_case.hpp, parse_sar_case) on
// arbitrary text.
//
// Oracle: parse_sar_case() returns or throws std::invalid_argument whose message starts with the
// origin (its documented contract: any other exception is a finding). A case it returns has
// every parameter finite and inside the range examples/sar_seed.toml documents, radar::validate()
// accepts its SarParams, and the derived values hold what the parser promises: at most 200000
// pulses, a near range beyond the altitude, a processed aperture no wider than the beam,
// positive spacings and clutter cell.

#include <cmath>
#include <stdexcept>
#include <string>
#include <string_view>

#include "common/units.hpp"
#include "radar/constants.hpp"
#include "radar/products/sar.hpp"
#include "tests/fuzz/fuzz_input.hpp"
#include "tests/fuzz/harnesses.hpp"
#include "tools/sar_case.hpp"

namespace radar_emu::fuzz {

namespace {

bool in(double v, double lo, double hi) {
  return std::isfinite(v) && v >= lo && v <= hi;
}
bool finite3(const glm::dvec3& v, double limit) {
  return in(v.x, -limit, limit) && in(v.y, -limit, limit) && in(v.z, -limit, limit);
}

}  // namespace

int sar_case(const std::uint8_t* data, std::size_t size) {
  const std::string_view text(reinterpret_cast<const char*>(data), size);
  try {
    const tools::SarCase c = tools::parse_sar_case(text, "fuzz.toml");
    const radar::SarParams& p = c.p;
    FUZZ_CHECK(in(p.carrier_hz, 1e8, 1e12));
    FUZZ_CHECK(in(p.bandwidth_hz, 1e5, 1e10));
    FUZZ_CHECK(in(p.sample_rate_hz, 1e5, 2e10));
    FUZZ_CHECK(in(p.pulse_duration_s, 1e-8, 1e-3));
    FUZZ_CHECK(in(p.prf_hz, 1.0, 1e6));
    FUZZ_CHECK(in(p.transmit_power_w, 1e-6, 1e9));
    FUZZ_CHECK(in(p.peak_gain, 1e-2 * (1 - 1e-12), 1e8 * (1 + 1e-12)));
    FUZZ_CHECK(in(c.altitude_m, 10.0, 20000.0));
    FUZZ_CHECK(in(c.speed_mps, 0.1, 2000.0));
    FUZZ_CHECK(in(c.heading_rad, common::radians(-360.0), common::radians(360.0)));
    FUZZ_CHECK(in(p.incidence_rad, common::radians(5.0), common::radians(85.0)));
    FUZZ_CHECK(p.azimuth_beamwidth_rad > 0.0 && p.azimuth_beamwidth_rad <= common::radians(30.0));
    FUZZ_CHECK(p.elevation_beamwidth_rad > 0.0 &&
               p.elevation_beamwidth_rad <= common::radians(60.0));
    FUZZ_CHECK(p.gates >= 8 && p.gates <= 65536);
    FUZZ_CHECK(c.synthetic_beamwidth_rad > 0.0 &&
               c.synthetic_beamwidth_rad <= common::radians(5.0));
    FUZZ_CHECK(c.upsample >= 1 && c.upsample <= 64);
    FUZZ_CHECK(in(c.image_width_m, 1.0, 20000.0));
    FUZZ_CHECK(c.azimuth_spacing_m > 0.0 && in(c.azimuth_spacing_m, 0.0, 1e6));
    FUZZ_CHECK(c.ground_range_spacing_m > 0.0 && in(c.ground_range_spacing_m, 0.0, 1e6));
    FUZZ_CHECK(c.clutter_cell_m > 0.0 && in(c.clutter_cell_m, 0.0, 1e6));
    FUZZ_CHECK(in(c.target_ray_spacing_m, 1e-3, 10.0));
    FUZZ_CHECK(c.max_bounces >= 1 && c.max_bounces <= 16);
    FUZZ_CHECK(in(c.latitude_deg, -89.0, 89.0) && in(c.longitude_deg, -180.0, 180.0));
    FUZZ_CHECK(c.pol_name == "HH" || c.pol_name == "HV" || c.pol_name == "VH" ||
               c.pol_name == "VV");
    // Derived geometry.
    FUZZ_CHECK(std::isfinite(c.theta_rad) && c.theta_rad > 0.0 &&
               c.theta_rad <= p.azimuth_beamwidth_rad);
    FUZZ_CHECK(std::isfinite(c.ground_centre_m) && c.ground_centre_m > 0.0);
    FUZZ_CHECK(std::isfinite(p.near_range_m) && p.near_range_m > c.altitude_m);
    FUZZ_CHECK(p.pulses >= 2 && p.pulses <= 200000);
    FUZZ_CHECK(finite3(p.start_position_m, 1e9) && finite3(p.velocity_mps, 2000.0 * (1 + 1e-12)));
    for (const tools::TargetCase& t : c.targets) {
      FUZZ_CHECK(in(t.spec.a_m, 0.0, 100.0) && t.spec.a_m > 0.0);
      FUZZ_CHECK(in(t.spec.b_m, 0.0, 100.0) && t.spec.b_m > 0.0);
      FUZZ_CHECK(in(t.spec.c_m, 0.0, 100.0) && t.spec.c_m > 0.0);
      FUZZ_CHECK(finite3(t.position_m, 15000.0) && finite3(t.velocity_mps, 1000.0));
      FUZZ_CHECK(in(t.heading_rad, common::radians(-360.0), common::radians(360.0)));
    }
    radar::validate(p);  // a throw here names no origin: the check below fails
  } catch (const std::invalid_argument& e) {
    FUZZ_CHECK(std::string_view(e.what()).starts_with("fuzz.toml"));
  }
  return 0;
}

}  // namespace radar_emu::fuzz
