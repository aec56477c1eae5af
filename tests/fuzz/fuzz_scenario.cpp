// Harness: the scenario TOML parser (loop/scenario.hpp) on arbitrary text.
//
// Oracle: parse_scenario() returns or throws std::runtime_error naming the origin (its
// documented contract: any other exception is a finding); a scenario it returns has a frame
// rate, a frame count and a sensor it could build.

#include <cmath>
#include <stdexcept>
#include <string>
#include <string_view>

#include "loop/scenario.hpp"
#include "tests/fuzz/fuzz_input.hpp"
#include "tests/fuzz/harnesses.hpp"

namespace radar_emu::fuzz {

int scenario_toml(const std::uint8_t* data, std::size_t size) {
  const std::string_view text(reinterpret_cast<const char*>(data), size);
  try {
    const loop::Scenario s = loop::parse_scenario(text, "fuzz.toml");
    FUZZ_CHECK(std::isfinite(s.rate_hz) && s.rate_hz > 0.0);
    FUZZ_CHECK(std::isfinite(s.state_timeout_s) && s.state_timeout_s >= 0.0);
  } catch (const std::runtime_error& e) {
    FUZZ_CHECK(std::string_view(e.what()).find("fuzz.toml") != std::string_view::npos);
  }
  return 0;
}

}  // namespace radar_emu::fuzz
