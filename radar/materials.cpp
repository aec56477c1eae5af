#include "radar/materials.hpp"

#include <array>
#include <stdexcept>

#include "radar/clutter/terrain.hpp"

namespace radar_emu::radar {

namespace {

// 10^(dB/10) at compile time is not constexpr in C++20's <cmath>; these literals are the linear
// values of the placeholder gammas named beside them (issue 4 replaces the whole table).
const std::array<RadarMaterial, 8>& catalogue() {
  static const std::array<RadarMaterial, 8> k{{
      {"metal", true, 0.0},
      {"steel", true, 0.0},
      {"aluminium", true, 0.0},
      {"asphalt", false, 3.1622776601683794e-3},   // gamma -25 dB (placeholder)
      {"concrete", false, 6.3095734448019324e-3},  // gamma -22 dB (placeholder)
      {"grass", false, 3.1622776601683794e-2},     // gamma -15 dB (placeholder)
      {"soil", false, 1.5848931924611134e-2},      // gamma -18 dB (placeholder)
      {"water", false, 3.1622776601683794e-4},     // gamma -35 dB (placeholder)
  }};
  return k;
}

}  // namespace

std::span<const RadarMaterial> material_catalogue() noexcept {
  return catalogue();
}

std::vector<RadarMaterial> resolve_materials(std::span<const scene::Material> scene_materials) {
  std::vector<RadarMaterial> out;
  out.reserve(scene_materials.size());
  for (std::size_t i = 0; i < scene_materials.size(); ++i) {
    const std::string& name = scene_materials[i].name;
    if (const clutter::TerrainMaterial* t = clutter::find_terrain_material(name)) {
      RadarMaterial m;
      m.name = name;
      m.conductor = t->permittivity_model == clutter::PermittivityModel::kConductor;
      m.terrain_catalogue = !m.conductor;
      out.push_back(std::move(m));
      continue;
    }
    const RadarMaterial* found = nullptr;
    for (const RadarMaterial& m : catalogue()) {
      if (m.name == name) {
        found = &m;
        break;
      }
    }
    if (found == nullptr) {
      std::string known = clutter::terrain_material_names();
      for (const RadarMaterial& m : catalogue()) {
        if (clutter::find_terrain_material(m.name) != nullptr)
          continue;
        known += known.empty() ? "" : ", ";
        known += m.name;
      }
      throw std::invalid_argument("radar materials: scene material " + std::to_string(i) + " '" +
                                  name + "' is unknown (known: " + known + ")");
    }
    out.push_back(*found);
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
  for (const RadarMaterial& m : catalogue()) {
    if (m.name == name && m.conductor)
      return SurfaceModel{};
  }
  return std::nullopt;
}

}  // namespace radar_emu::radar
