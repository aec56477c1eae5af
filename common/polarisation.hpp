#pragma once
// The polarisation channel, its name and its parser: the one answer for the tracer, the RCS
// engine, the tools, the scenario and the Python module.

#include <cstdint>
#include <stdexcept>
#include <string>
#include <string_view>

namespace radar_emu::common {

/// Polarisation channel, receive letter first ("HV" = receive H, transmit V).
enum class Polarisation : std::uint8_t { kHH, kHV, kVH, kVV };

/// "HH", "HV", "VH" or "VV". Real-time safe.
[[nodiscard]] constexpr std::string_view polarisation_name(Polarisation p) noexcept {
  switch (p) {
    case Polarisation::kHH:
      return "HH";
    case Polarisation::kHV:
      return "HV";
    case Polarisation::kVH:
      return "VH";
    case Polarisation::kVV:
      return "VV";
  }
  return "?";
}

/// "HH", "HV", "VH" or "VV", letters in either case ("hv" = kHV). Anything else throws
/// std::invalid_argument("'NAME' is not one of HH, HV, VH, VV"); callers prefix the option or
/// key. Set-up only.
[[nodiscard]] inline Polarisation parse_polarisation(std::string_view name) {
  if (name.size() == 2) {
    const auto up = [](char c) { return c == 'h' ? 'H' : c == 'v' ? 'V' : c; };
    const char rx = up(name[0]), tx = up(name[1]);
    if ((rx == 'H' || rx == 'V') && (tx == 'H' || tx == 'V'))
      return rx == 'H' ? (tx == 'H' ? Polarisation::kHH : Polarisation::kHV)
                       : (tx == 'H' ? Polarisation::kVH : Polarisation::kVV);
  }
  throw std::invalid_argument("'" + std::string(name) + "' is not one of HH, HV, VH, VV");
}

}  // namespace radar_emu::common
