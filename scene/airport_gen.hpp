#pragma once
// A generated airport for the enhanced-vision approach (issue 7): the default scene's runway and
// closed-loop objects inside a full aerodrome, in the same frame and anchor as
// scene/default_scene.hpp (ENU metres, runway along +y = north, threshold at the origin, WGS84
// anchor 43.6 N, 1.4 E, 150 m).
//
// Layout (x east, y north, z up; pavements at z = 0.05 m over the grass, touching, never
// overlapping; every object's ObjectDesc::area is "airport"):
//   ground           "grass"     x [-3000, 3000], y [-6000, 4000], z 0 (2 triangles)
//   runway           45 x 3000 m, x [-22.5, 22.5], y [0, 3000], "asphalt" with its painted
//                    markings as "concrete" (no catalogue material is paint; concrete is the
//                    smooth, bright surface nearest to it), at both ends, after ICAO Annex 14
//                    Vol. I, chapter 5.2 (runway markings) for a 45 m runway of 2400 m or more:
//                      threshold: 12 stripes 1.8 x 30 m, 1.8 m apart, double space at the
//                        centreline (|x| from 1.8 + 3.6 k to 3.6 + 3.6 k), from 6 m
//                      centreline: 58 dashes 0.9 x 30 m, 20 m gaps, y from 60 to 2940
//                      aiming point: 2 blocks 10 x 60 m, |x| [9, 19], from 400 m
//                      touchdown zone (stripes 1.8 m wide, 1.5 m apart, 22.5 m long, inner
//                        sides as far apart as the aiming point's): pairs at 150, 300, 600, 750,
//                        900 and 1050 m of 3, 3, 2, 2, 1, 1 stripes (the pair at 450 m would
//                        fall within 50 m of the aiming point and is left out)
//                      side stripes: 0.9 m along both edges, the whole length
//                    Asphalt 122,394 m^2 + markings 12,606 m^2 = 135,000 m^2.
//   taxiways         "asphalt" 23 m wide: the parallel taxiway x [-131.5, -108.5], y [0, 3000]
//                    (the moving vehicle's), four links to the runway's west edge, one east to
//                    the main apron (y [1188.5, 1211.5]) and one to the remote stand
//   aprons           "concrete": main apron x [150, 470], y [950, 1450]; remote stand under
//                    the parked aircraft x [85, 135], y [670, 730]; hangar apron x [-270,
//                    -131.5], y [1450, 1800]; helipad x [-215, -185], y [1285, 1315]
//   approach_lights  "metal", ONE object (the radar traces every metal object with its own ray
//                    bundle): masts 0.3 x 0.3 x 1.8 m carrying 4 m barrettes 0.3 x 0.3 m on the
//                    extended centreline every 30 m from 30 to 900 m south of the threshold,
//                    and the 30 m crossbar at 300 m on four more masts at x +-7 and +-14
//                    (ICAO Annex 14 Vol. I, 5.3.4: precision approach category I system)
//   terminal         "concrete" 40 x 440 x 14 m east of the main apron (x [475, 515]) under a
//                    1 m roof slab, and a control tower 7 x 7 x 32 m with its cab at (545, 1200)
//   hangar_1..3      "concrete" walls x [-270 - depth, -270] with a gabled roof (eaves 0.5 m),
//                    doors facing the taxiway; depth 50..70 m, width 60..75 m, walls 14..20 m
//                    high, ridge 4..6 m higher (seeded)
//   transport_1..    transport_aircraft targets (37.57 x 35.8 x 11.76 m, A320 size) at
//                    `parked_transports` of the six gates y = 1010 + 80 k (seeded), nose east
//                    7 m from the terminal, position jittered +-1 m and heading +-2 deg
//   service_truck, service_jeep  truck (8 x 2.5 x 3.4 m) and jeep (4 x 1.8 x 1.9 m) targets on
//                    the main apron between gates (seeded positions and headings)
//   helicopter       helicopter target (12.7 x 14.6 x 4.4 m) on the helipad (seeded heading)
//   parked_aircraft, parked_vehicle, light_mast, moving_vehicle: the default scene's closed-loop
//                    objects, same names, positions, meshes and motion (with their trihedral
//                    reflectors when `corner_reflectors`).
// About 6,700 triangles with the defaults (runway 1,682); 11 metal objects (4 closed-loop, the
// approach lights, 3 aircraft, 2 vehicles, the helicopter). Materials: grass, asphalt, concrete,
// metal (names known to both the radar's material table and the clutter catalogue).

#include <cstdint>

#include "scene/types.hpp"

namespace radar_emu::scene {

struct AirportSpec {
  std::uint64_t seed = 1;  ///< picks the occupied gates, building sizes, jitters
  /// The closed-loop objects carry 0.5 m trihedrals, as on a test range. Off by default: they
  /// are seen by their own edges, multi-bounce and ground coupling.
  bool corner_reflectors = false;
  int parked_transports = 3;     ///< transport aircraft at the terminal's 6 gates, 0..6
  bool service_vehicles = true;  ///< a truck and a jeep on the main apron
  bool helicopter = true;        ///< a helicopter on the helipad
  bool approach_lights = true;   ///< the approach-light masts south of the threshold
};

/// Builds the airport (layout above). Deterministic: the same spec gives the same description,
/// on every platform (the seed drives a SplitMix64 generator, not <random>'s distributions).
/// Throws std::invalid_argument naming the field when parked_transports is outside 0..6.
/// Setup only (allocates).
[[nodiscard]] SceneDescription generate_airport(const AirportSpec& spec);

}  // namespace radar_emu::scene
