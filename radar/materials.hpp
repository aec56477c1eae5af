#pragma once
// Radar properties of the scene's materials, looked up by material name at setup.
//
// Issue 2 ships a first, deliberately small catalogue: metals are perfect electric conductors
// (R_perp = -1, R_par = +1, seed paper "Radar features"), terrain classes scatter diffusely
// with the constant-gamma model sigma0 = gamma * cos(theta_i) (Richards, Principles of Modern
// Radar, 2010, sec. 5.3; theta_i from the surface normal). The gamma values below are
// placeholders of the right order for mm-wave land clutter, chosen by us, until the material
// catalogue of issue 4 replaces them with sourced, frequency- and polarisation-dependent models.

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
  double gamma = 0.0;      ///< constant-gamma clutter coefficient (linear) for non-conductors
  /// Non-conductors of the terrain catalogue (radar/clutter/terrain.hpp) get their sigma0 from
  /// the physical models through a setup-time Sigma0Table instead of `gamma`.
  bool terrain_catalogue = false;
};

/// The catalogue of known material names.
[[nodiscard]] std::span<const RadarMaterial> material_catalogue() noexcept;

/// Radar properties for each scene material, in the scene's material order. A name of the
/// terrain catalogue (radar/clutter/terrain.hpp: asphalt, concrete, grass, crops, forest, ...,
/// metal) takes precedence: "metal" is a conductor, the others are terrain_catalogue materials.
/// The remaining names of the first catalogue ("steel", "aluminium", "soil") keep their constant
/// gamma. Throws std::invalid_argument naming the material and the known names when one is
/// unknown (setup).
[[nodiscard]] std::vector<RadarMaterial> resolve_materials(
    std::span<const scene::Material> scene_materials);

/// How the material named `name` reflects specularly, for the SBR core (the one mapping of
/// material names to SurfaceModel, used by the frame tracer and the RCS tool): a perfect
/// conductor for the conductors of either catalogue (metal, steel, aluminium); a dielectric
/// half-space with the terrain catalogue's permittivity at `freq_hz` for its other materials
/// (asphalt, concrete, grass, soil_dry, water, ...; radar/clutter/terrain.hpp names the source
/// of each permittivity); nullopt for names with no known permittivity (the first catalogue's
/// placeholder "soil", unknown names). Setup only: may throw std::invalid_argument from the
/// permittivity models for a frequency outside their range.
[[nodiscard]] std::optional<SurfaceModel> surface_model(std::string_view name, double freq_hz);

}  // namespace radar_emu::radar
