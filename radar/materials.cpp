#include "radar/materials.hpp"

#include <algorithm>
#include <array>
#include <stdexcept>

#include "radar/clutter/terrain.hpp"

namespace radar_emu::radar {

namespace {

// Other names of the catalogue's conductor ("metal", radar/clutter/terrain.hpp): the names
// scenes and meshes have used for it since issue 2 (README, docs/scene_format.md).
constexpr std::array<std::string_view, 2> kConductorAliases{"steel", "aluminium"};

bool is_conductor_alias(std::string_view name) noexcept {
  return std::find(kConductorAliases.begin(), kConductorAliases.end(), name) !=
         kConductorAliases.end();
}

}  // namespace

std::vector<RadarMaterial> resolve_materials(std::span<const scene::Material> scene_materials) {
  std::vector<RadarMaterial> out;
  out.reserve(scene_materials.size());
  for (std::size_t i = 0; i < scene_materials.size(); ++i) {
    const std::string& name = scene_materials[i].name;
    RadarMaterial m;
    m.name = name;
    if (const clutter::TerrainMaterial* t = clutter::find_terrain_material(name)) {
      m.conductor = t->permittivity_model == clutter::PermittivityModel::kConductor;
      m.terrain_catalogue = !m.conductor;
    } else if (is_conductor_alias(name)) {
      m.conductor = true;
    } else {
      std::string known = clutter::terrain_material_names();
      for (std::string_view alias : kConductorAliases)
        known += ", " + std::string(alias);
      throw std::invalid_argument("radar materials: scene material " + std::to_string(i) + " '" +
                                  name + "' is unknown (known: " + known + ")");
    }
    out.push_back(std::move(m));
  }
  return out;
}

std::optional<SurfaceModel> surface_model(std::string_view name, double freq_hz) {
  if (const clutter::TerrainMaterial* t = clutter::find_terrain_material(name)) {
    if (t->permittivity_model == clutter::PermittivityModel::kConductor)
      return SurfaceModel{};
    SurfaceModel m;
    m.kind = SurfaceModel::Kind::kDielectric;
    m.relative_permittivity = clutter::permittivity(*t, freq_hz);
    return m;
  }
  if (is_conductor_alias(name))
    return SurfaceModel{};
  return std::nullopt;
}

}  // namespace radar_emu::radar
