#pragma once
// Radar properties of the scene's materials, looked up by material name at setup: the terrain
// catalogue (radar/clutter/terrain.hpp: physical sigma0 models and permittivities, its
// conductor "metal"), plus "steel" and "aluminium" as other names of that conductor (perfect
// electric conductors: R_perp = -1, R_par = +1, seed paper "Radar features").

#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "radar/em/sbr_core.hpp"
#include "scene/types.hpp"

namespace radar_emu::radar {

struct RadarMaterial {
  std::string name;
  bool conductor = false;  ///< perfect electric conductor: specular GO bounce + PO
  /// Non-conductors (all of the terrain catalogue) get their sigma0 from the physical models
  /// through a setup-time Sigma0Table.
  bool terrain_catalogue = false;
};

/// Radar properties for each scene material, in the scene's material order. A name of the
/// terrain catalogue (radar/clutter/terrain.hpp: asphalt, concrete, grass, crops, forest, ...,
/// metal): "metal" is a conductor, the others are terrain_catalogue materials; "steel" and
/// "aluminium" are conductors. Throws std::invalid_argument naming the material and the known
/// names when one is unknown (setup).
[[nodiscard]] std::vector<RadarMaterial> resolve_materials(
    std::span<const scene::Material> scene_materials);

/// How the material named `name` reflects specularly, for the SBR core (the one mapping of
/// material names to SurfaceModel, used by the frame tracer and the RCS tool): a perfect
/// conductor for the conductors of either catalogue (metal, steel, aluminium); a dielectric
/// half-space with the terrain catalogue's permittivity at `freq_hz` for its other materials
/// (asphalt, concrete, grass, soil_dry, water, ...; radar/clutter/terrain.hpp names the source
/// of each permittivity); nullopt for unknown names. Setup only: may throw std::invalid_argument
/// from the permittivity models for a frequency outside their range.
[[nodiscard]] std::optional<SurfaceModel> surface_model(std::string_view name, double freq_hz);

}  // namespace radar_emu::radar
