#pragma once
// Physical constants (SI). CODATA 2018 exact values where defined. pi and the speed of light are
// common/units.hpp's.

#include "common/units.hpp"

namespace radar_emu::radar {

inline constexpr double kSpeedOfLight_mps = common::kC;
inline constexpr double kBoltzmann_jpk = 1.380649e-23;
using common::kPi;
inline constexpr double kReferenceTemperature_k = 290.0;  ///< IEEE Std 145 / noise figure T0

}  // namespace radar_emu::radar
