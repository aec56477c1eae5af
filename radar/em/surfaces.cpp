#include "radar/em/surfaces.hpp"

#include <algorithm>
#include <array>
#include <cmath>

namespace radar_emu::radar {

namespace {

// Other names of the catalogue's conductor ("metal", radar/clutter/terrain.hpp): the names
// scenes and meshes have used for it since issue 2 (README, docs/scene_format.md).
constexpr std::array<std::string_view, 2> kConductorAliases{"steel", "aluminium"};

bool is_conductor_alias(std::string_view name) noexcept {
  return std::find(kConductorAliases.begin(), kConductorAliases.end(), name) !=
         kConductorAliases.end();
}

// "metal, steel, aluminium": the conductors, for the message of a resolution without carrier.
std::string conductor_names() {
  std::string out;
  for (const clutter::TerrainMaterial& t : clutter::terrain_catalogue()) {
    if (t.permittivity_model != clutter::PermittivityModel::kConductor)
      continue;
    out += out.empty() ? "" : ", ";
    out += t.name;
  }
  for (std::string_view alias : kConductorAliases)
    out += ", " + std::string(alias);
  return out;
}

}  // namespace

float SurfaceSet::sigma0(std::size_t material, double cos_incidence) const noexcept {
  if (material >= surfaces.size() || surfaces[material].sigma0_row < 0)
    return 0.0f;
  return sigma0_table.lookup(static_cast<std::size_t>(surfaces[material].sigma0_row), channel,
                             cos_incidence);
}

float SurfaceSet::sigma0(std::size_t material, double cos_incidence,
                         std::uint32_t& flags) const noexcept {
  flags = 0u;
  if (material >= surfaces.size() || surfaces[material].sigma0_row < 0)
    return 0.0f;
  return sigma0_table.lookup(static_cast<std::size_t>(surfaces[material].sigma0_row), channel,
                             cos_incidence, flags);
}

SurfaceSet resolve_surfaces(std::span<const scene::Material> materials,
                            const SurfaceRequest& request) {
  if (request.carrier_hz && !(std::isfinite(*request.carrier_hz) && *request.carrier_hz > 0.0))
    throw std::invalid_argument("radar materials: carrier_hz must be > 0");
  SurfaceSet out;
  out.channel = sigma0_channel(request.polarisation);
  out.surfaces.reserve(materials.size());
  std::vector<clutter::SurfaceSpec> specs;  // the sigma0 rows, in row order
  for (std::size_t i = 0; i < materials.size(); ++i) {
    Surface s;
    s.name = materials[i].name;
    const auto over = std::find_if(request.overrides.begin(), request.overrides.end(),
                                   [&](const SurfaceOverride& o) { return o.name == s.name; });
    const clutter::TerrainMaterial* t = clutter::find_terrain_material(s.name);
    const bool conductor =
        is_conductor_alias(s.name) ||
        (t != nullptr && t->permittivity_model == clutter::PermittivityModel::kConductor);
    if (over != request.overrides.end()) {
      s.specular = over->model;
      s.conductor = over->model.kind == SurfaceModel::Kind::kPec;
    } else if (conductor) {
      s.conductor = true;  // SurfaceModel{} is a PEC
    } else if (!request.carrier_hz) {
      throw UnresolvedMaterial("material '" + s.name + "' is not a conductor of the catalogue (" +
                                   conductor_names() + ")",
                               i, s.name);
    } else if (t == nullptr) {
      throw UnresolvedMaterial("radar materials: scene material " + std::to_string(i) + " '" +
                                   s.name + "' is unknown (known: " + surface_material_names() +
                                   ")",
                               i, s.name);
    } else {
      s.specular.kind = SurfaceModel::Kind::kDielectric;
      s.specular.relative_permittivity = clutter::permittivity(*t, *request.carrier_hz);
      s.sigma0_row = static_cast<int>(specs.size());
      specs.push_back(clutter::resolve_surface(*t, *request.carrier_hz));
    }
    out.surfaces.push_back(std::move(s));
  }
  if (!specs.empty())
    out.sigma0_table =
        clutter::Sigma0Table(specs, clutter::Sigma0Model::kTotal, *request.carrier_hz);
  return out;
}

bool is_surface_material(std::string_view name) noexcept {
  return clutter::find_terrain_material(name) != nullptr || is_conductor_alias(name);
}

std::string surface_material_names() {
  std::string known = clutter::terrain_material_names();
  for (std::string_view alias : kConductorAliases)
    known += ", " + std::string(alias);
  return known;
}

clutter::Sigma0Table::Pol sigma0_channel(Polarisation p) noexcept {
  switch (p) {
    case Polarisation::kHH:
      return clutter::Sigma0Table::kHH;
    case Polarisation::kHV:
      return clutter::Sigma0Table::kHV;
    case Polarisation::kVH:
      return clutter::Sigma0Table::kVH;
    case Polarisation::kVV:
      break;
  }
  return clutter::Sigma0Table::kVV;
}

}  // namespace radar_emu::radar
