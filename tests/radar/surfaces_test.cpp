// The one material resolver (radar/em/surfaces.hpp): each scene material resolved once at the
// carrier into its specular model, sigma0 row and conductor flag; overrides first; no carrier
// for frequency sweeps; the names it knows and what it says about the others.

#include "radar/em/surfaces.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <complex>
#include <initializer_list>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include "radar/clutter/terrain.hpp"

namespace rd = radar_emu::radar;
namespace cl = radar_emu::radar::clutter;
namespace sc = radar_emu::scene;

namespace {
std::vector<sc::Material> named(std::initializer_list<const char*> names) {
  std::vector<sc::Material> out;
  for (const char* n : names)
    out.push_back({n, {}});
  return out;
}
}  // namespace

TEST(Surfaces, CatalogueMaterialsAtTheCarrier) {
  // Conductors (the catalogue's metal and its other names) are PEC without a sigma0 row; the
  // others are a dielectric half-space of the catalogue's permittivity at the carrier, with the
  // sigma0 row of the model "total" there (the table the tracer and the SAR cells read).
  constexpr double kF = 94e9;
  const std::vector<sc::Material> m = named({"grass", "metal", "asphalt", "steel", "aluminium"});
  const rd::SurfaceSet set = rd::resolve_surfaces(m, {kF, rd::Polarisation::kHH, {}});
  ASSERT_EQ(set.surfaces.size(), m.size());
  for (std::size_t i = 0; i < m.size(); ++i)
    EXPECT_EQ(set.surfaces[i].name, m[i].name);
  for (std::size_t i : {1u, 3u, 4u}) {
    EXPECT_TRUE(set.surfaces[i].conductor) << m[i].name;
    EXPECT_EQ(set.surfaces[i].specular.kind, rd::SurfaceModel::Kind::kPec) << m[i].name;
    EXPECT_EQ(set.surfaces[i].sigma0_row, -1) << m[i].name;
    EXPECT_EQ(set.sigma0(i, 0.5), 0.0f) << m[i].name;
  }
  const std::vector<cl::SurfaceSpec> specs{
      cl::resolve_surface(*cl::find_terrain_material("grass"), kF),
      cl::resolve_surface(*cl::find_terrain_material("asphalt"), kF)};
  const cl::Sigma0Table table(specs, cl::Sigma0Model::kTotal, kF);
  int row = 0;
  for (std::size_t i : {0u, 2u}) {
    const rd::Surface& s = set.surfaces[i];
    EXPECT_FALSE(s.conductor) << s.name;
    EXPECT_EQ(s.specular.kind, rd::SurfaceModel::Kind::kDielectric) << s.name;
    EXPECT_EQ(s.specular.relative_permittivity,
              cl::permittivity(*cl::find_terrain_material(s.name), kF))
        << s.name;
    EXPECT_EQ(s.sigma0_row, row) << s.name;
    for (double c : {0.1, 0.5, 0.9}) {
      EXPECT_EQ(set.sigma0(i, c),
                table.lookup(static_cast<std::size_t>(row), cl::Sigma0Table::kHH, c))
          << s.name << " cos " << c;
      EXPECT_GT(set.sigma0(i, c), 0.0f) << s.name;
    }
    ++row;
  }
  EXPECT_EQ(set.channel, cl::Sigma0Table::kHH);
  EXPECT_EQ(set.sigma0(m.size(), 0.5), 0.0f);  // no such material
  EXPECT_EQ(rd::sigma0_channel(rd::Polarisation::kVV), cl::Sigma0Table::kVV);
  EXPECT_EQ(rd::sigma0_channel(rd::Polarisation::kHV), cl::Sigma0Table::kHV);
  EXPECT_EQ(rd::sigma0_channel(rd::Polarisation::kVH), cl::Sigma0Table::kVH);
}

TEST(Surfaces, UnknownNamesAndBadCarriersAreRefusedWithContext) {
  const std::vector<sc::Material> m = named({"metal", "soil"});
  try {
    (void)rd::resolve_surfaces(m, {10e9, rd::Polarisation::kVV, {}});
    ADD_FAILURE() << "\"soil\" was accepted";
  } catch (const rd::UnresolvedMaterial& e) {
    EXPECT_EQ(e.index(), 1u);
    EXPECT_EQ(e.name(), "soil");
    EXPECT_EQ(std::string(e.what()),
              "radar materials: scene material 1 'soil' is unknown (known: " +
                  rd::surface_material_names() + ")");
  }
  EXPECT_EQ(rd::surface_material_names(), cl::terrain_material_names() + ", steel, aluminium");
  EXPECT_TRUE(rd::is_surface_material("soil_wet"));
  EXPECT_TRUE(rd::is_surface_material("aluminium"));
  EXPECT_FALSE(rd::is_surface_material("soil"));
  EXPECT_FALSE(rd::is_surface_material(""));
  for (double bad : {0.0, -1.0, std::nan("")})
    EXPECT_THROW((void)rd::resolve_surfaces(named({"metal"}), {bad, rd::Polarisation::kVV, {}}),
                 std::invalid_argument);
}

TEST(Surfaces, WithoutACarrierOnlyConductorsAndOverridesResolve) {
  // The RCS tool's frequency sweeps: no carrier, its --material definitions as overrides, which
  // come before the catalogue (even over a catalogue name).
  std::vector<rd::SurfaceOverride> over(3);
  over[0].name = "glass";
  over[0].model.kind = rd::SurfaceModel::Kind::kDielectric;
  over[0].model.relative_permittivity = {6.5, -0.3};
  over[1].name = "grass";
  over[1].model.kind = rd::SurfaceModel::Kind::kCoatedPec;
  over[1].model.relative_permittivity = {3.0, -0.1};
  over[1].model.thickness_m = 0.002;
  over[2].name = "skin";  // a PEC override: a conductor
  const std::vector<sc::Material> m = named({"steel", "glass", "grass", "skin"});
  const rd::SurfaceSet set = rd::resolve_surfaces(m, {std::nullopt, rd::Polarisation::kVV, over});
  ASSERT_EQ(set.surfaces.size(), 4u);
  EXPECT_TRUE(set.surfaces[0].conductor);
  EXPECT_EQ(set.surfaces[1].specular.relative_permittivity, std::complex<double>(6.5, -0.3));
  EXPECT_FALSE(set.surfaces[1].conductor);
  EXPECT_EQ(set.surfaces[2].specular.kind, rd::SurfaceModel::Kind::kCoatedPec);
  EXPECT_EQ(set.surfaces[2].specular.thickness_m, 0.002);
  EXPECT_TRUE(set.surfaces[3].conductor);
  for (const rd::Surface& s : set.surfaces)
    EXPECT_EQ(s.sigma0_row, -1) << s.name;
  EXPECT_EQ(set.sigma0_table.materials(), 0u);
  try {
    (void)rd::resolve_surfaces(named({"metal", "asphalt"}),
                               {std::nullopt, rd::Polarisation::kVV, {}});
    ADD_FAILURE() << "asphalt resolved without a carrier";
  } catch (const rd::UnresolvedMaterial& e) {
    EXPECT_EQ(e.name(), "asphalt");
    EXPECT_EQ(std::string(e.what()),
              "material 'asphalt' is not a conductor of the catalogue (metal, steel, aluminium)");
  }
}
