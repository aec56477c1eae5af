#pragma once
// The one material resolver: each scene material, resolved once at setup at the carrier, into
// everything the engines read of it: its specular model for the SBR core (radar/em/sbr_core.hpp:
// PEC, dielectric half-space, layer on a PEC), its sigma0 row for the diffuse clutter (the frame
// tracer, the SAR terrain cells) and whether it is a conductor (which makes its object a target).
//
// Names: the terrain catalogue (radar/clutter/terrain.hpp: asphalt, concrete, grass, ..., metal;
// it names the source of every permittivity and sigma0 model), plus "steel" and "aluminium" as
// other names of its conductor "metal" (perfect electric conductors: R_perp = -1, R_par = +1,
// seed paper "Radar features"). A caller's overrides (the RCS tool's --material definitions) come
// before the catalogue.
//
// Setup only (allocates, throws std::invalid_argument with the material and what is known);
// SurfaceSet::sigma0() is real-time safe.

#include <cstddef>
#include <optional>
#include <span>
#include <stdexcept>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "radar/clutter/terrain.hpp"
#include "radar/em/sbr_core.hpp"
#include "scene/types.hpp"

namespace radar_emu::radar {

/// One scene material as the radar sees it, resolved at setup.
struct Surface {
  std::string name;        ///< the scene material's name
  bool conductor = false;  ///< perfect electric conductor: specular GO + PO, makes a target
  SurfaceModel specular;   ///< how it reflects, for the SBR core (at the carrier)
  /// Row of SurfaceSet::sigma0_table; -1: no diffuse clutter (conductors, overrides, and every
  /// material when resolved without a carrier).
  int sigma0_row = -1;
};

/// A caller's definition of one material, before the catalogue (the RCS tool's --material).
struct SurfaceOverride {
  std::string name;    ///< the scene material it defines
  SurfaceModel model;  ///< used as given, at every frequency
};

/// What resolve_surfaces() resolves for.
struct SurfaceRequest {
  /// The carrier [Hz], > 0: permittivities and sigma0 rows are evaluated there. nullopt for
  /// frequency sweeps (the RCS tool): only what does not depend on frequency resolves then
  /// (conductors, overrides), and there is no sigma0 table.
  std::optional<double> carrier_hz;
  Polarisation polarisation = Polarisation::kVV;  ///< the channel SurfaceSet::sigma0() reads
  std::span<const SurfaceOverride> overrides;     ///< first match by name wins
};

/// Every scene material resolved, in the scene's material order.
struct SurfaceSet {
  std::vector<Surface> surfaces;
  /// sigma0 of the non-conducting catalogue materials at the carrier, model "total" (surface +
  /// volume), all four channels (radar/clutter/terrain.hpp); one row per Surface::sigma0_row.
  clutter::Sigma0Table sigma0_table;
  clutter::Sigma0Table::Pol channel = clutter::Sigma0Table::kVV;  ///< SurfaceRequest's channel

  /// Linear sigma0 of scene material `material` at incidence cos(theta_i) = cos_incidence, in
  /// `channel`; 0 for a material without a row (or out of range). Real-time safe.
  [[nodiscard]] float sigma0(std::size_t material, double cos_incidence) const noexcept;
  /// The same, and the validity flags of the table's samples it read (Sigma0Table::
  /// lookup_flags; 0 without a row). Real-time safe.
  [[nodiscard]] float sigma0(std::size_t material, double cos_incidence,
                             std::uint32_t& flags) const noexcept;
};

/// Thrown by resolve_surfaces() for a material it cannot resolve.
class UnresolvedMaterial : public std::invalid_argument {
 public:
  UnresolvedMaterial(const std::string& what, std::size_t index, std::string name)
      : std::invalid_argument(what), index_(index), name_(std::move(name)) {}
  [[nodiscard]] std::size_t index() const noexcept { return index_; }  ///< scene material index
  [[nodiscard]] const std::string& name() const noexcept { return name_; }

 private:
  std::size_t index_;
  std::string name_;
};

/// Resolves every scene material for `request` (setup; the one resolver: the frame tracer, the
/// RCS tool and, through the tracer, the loop and the SAR terrain cells call it). An override
/// of the same name is taken as given (a conductor when it is kPec); a catalogue conductor is
/// PEC; another catalogue material is a dielectric half-space of the catalogue's permittivity
/// at the carrier with its sigma0 row. Throws UnresolvedMaterial for an unknown name ("scene
/// material I 'NAME' is unknown (known: ...)") and, without a carrier, for any name that is
/// neither overridden nor a conductor ("material 'NAME' is not a conductor of the catalogue
/// (metal, steel, aluminium)"); std::invalid_argument for a carrier that is not > 0 or outside
/// the permittivity models' range.
[[nodiscard]] SurfaceSet resolve_surfaces(std::span<const scene::Material> materials,
                                          const SurfaceRequest& request);

/// Whether resolve_surfaces() knows `name` (at a carrier, without overrides): the name check of
/// the scenario and of mesh files, without building sigma0 tables.
[[nodiscard]] bool is_surface_material(std::string_view name) noexcept;
/// "asphalt, concrete, ..., metal, steel, aluminium": the names it knows, for messages.
[[nodiscard]] std::string surface_material_names();

/// The sigma0 table's channel of a polarisation.
[[nodiscard]] clutter::Sigma0Table::Pol sigma0_channel(Polarisation p) noexcept;

}  // namespace radar_emu::radar
