// `radar-emu scene target`: a canonical target mesh (conventions in scene/targets.hpp).

#include <cstdio>
#include <memory>
#include <stdexcept>
#include <string>

#include "app/cli_common.hpp"
#include "app/cmd.hpp"
#include "config/cli_checks.hpp"
#include "scene/targets.hpp"
#include "tools/scene.hpp"

namespace radar_emu::app {
namespace {

// The dimensions a target kind reads (scene/targets.hpp): 1 (a), 2 (a, b) or 3 (a, b, c).
int target_dimensions(radar_emu::scene::TargetKind kind) {
  using radar_emu::scene::TargetKind;
  switch (kind) {
    case TargetKind::kTrihedralSquare:
    case TargetKind::kTrihedralTriangular:
    case TargetKind::kSphere:
      return 1;
    case TargetKind::kPlate:
    case TargetKind::kDihedral:
    case TargetKind::kCylinder:
      return 2;
    default:
      return 3;
  }
}

// Default of `scene target --max-triangles` (README): about 4 GB at the measured 210 bytes a
// triangle (scene/targets.hpp kTargetBytesPerTriangle).
constexpr double kDefaultMaxTargetTriangles = 20e6;

int target_command(const std::string& kind_name, radar_emu::scene::TargetSpec spec,
                   const std::string& out, const CLI::App& cmd, double max_triangles) {
  namespace sc = radar_emu::scene;
  const auto kind = sc::target_kind_from_name(kind_name);
  if (!kind) {
    throw std::runtime_error("unknown target '" + kind_name + "' (known: " + sc::target_names() +
                             ")");
  }
  spec.kind = *kind;
  // A dimension the kind does not read is refused, not silently ignored.
  const int dims = target_dimensions(*kind);
  const char* takes = dims == 1 ? "--a-m only" : dims == 2 ? "--a-m and --b-m only" : "";
  for (int d = dims; d < 3; ++d) {
    const std::string name = d == 1 ? "--b-m" : "--c-m";
    if (cmd.count(name) > 0)
      throw std::invalid_argument(name + ": a " + kind_name + " takes " + takes);
  }
  // Refuse a mesh past the memory limit before making it, with the estimate.
  const double triangles = sc::target_triangle_estimate(spec);
  if (triangles > max_triangles) {
    char text[320];
    std::snprintf(text, sizeof text,
                  "--facet-m %g: a %s would have about %.3g triangles (about %s of memory), over "
                  "the limit of %.3g triangles (raise it with --max-triangles, or use a coarser "
                  "--facet-m)",
                  spec.facet_m, kind_name.c_str(), triangles,
                  si_bytes(triangles * sc::kTargetBytesPerTriangle).c_str(), max_triangles);
    throw std::invalid_argument(text);
  }
  const std::size_t written = tools::write_scene_target(spec, out);
  std::printf("%s: %s, %zu triangles\n", out.c_str(), kind_name.c_str(), written);
  return 0;
}

}  // namespace

void add_scene_target_command(CLI::App& scene, Commands& commands) {
  CLI::App* target = scene.add_subcommand(
      "target", "Write a canonical target mesh (conventions in scene/targets.hpp)");
  struct Args {
    std::string kind, out;
    radar_emu::scene::TargetSpec spec;
    double max_triangles = kDefaultMaxTargetTriangles;
  };
  auto a = std::make_shared<Args>();
  target->add_option("kind", a->kind, radar_emu::scene::target_names())->required();
  target
      ->add_option("--a-m", a->spec.a_m,
                   "First dimension [m]: plate/box x, fold length, trihedral edge, radius")
      ->check(config::in_range(0.0, 1e5, "m", true));
  target
      ->add_option("--b-m", a->spec.b_m,
                   "Second dimension [m]: plate/box y, face width, length (not for trihedrals "
                   "and spheres)")
      ->check(config::in_range(0.0, 1e5, "m", true));
  target
      ->add_option("--c-m", a->spec.c_m,
                   "Third dimension [m]: box, vehicle and aircraft z (only those)")
      ->check(config::in_range(0.0, 1e5, "m", true));
  target
      ->add_option("--facet-m", a->spec.facet_m,
                   "Largest facet edge [m] (0: coarsest exact mesh, 32 segments for curves)")
      ->check(config::in_range(0.0, 1e5, "m"));
  target
      ->add_option("--max-triangles", a->max_triangles,
                   "Refuse a mesh estimated past this many triangles (about 210 bytes each "
                   "while written; default 2e7)")
      ->check(config::in_range(1.0, 1.4e9, "triangles"));
  target->add_option("--out", a->out, "Output file: .glb, .gltf, .obj or .stl")
      ->required()
      ->check(config::output_file({".glb", ".gltf", ".obj", ".stl"}));
  commands.push_back({target, [target, a] {
                        return target_command(a->kind, a->spec, a->out, *target, a->max_triangles);
                      }});
}

}  // namespace radar_emu::app
