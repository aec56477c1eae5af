#pragma once
// Physical constants (SI). CODATA 2018 exact values where defined.

namespace radar_emu::radar {

inline constexpr double kSpeedOfLight_mps = 299792458.0;
inline constexpr double kBoltzmann_jpk = 1.380649e-23;
inline constexpr double kPi = 3.14159265358979323846;
inline constexpr double kReferenceTemperature_k = 290.0;  ///< IEEE Std 145 / noise figure T0

}  // namespace radar_emu::radar
