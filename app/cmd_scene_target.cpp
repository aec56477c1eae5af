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
  // The kind's dimensions and default size: the table a scenario's [[target]] reads too.
  const sc::TargetKindSize size = sc::target_kind_size(*kind);
  const int dims = size.dims;
  const char* takes = dims == 1 ? "--a-m only" : dims == 2 ? "--a-m and --b-m only" : "";
  static const std::string kOption[3] = {"--a-m", "--b-m", "--c-m"};
  for (int d = dims; d < 3; ++d) {
    if (cmd.count(kOption[d]) > 0)  // a dimension the kind does not read: refused, not ignored
      throw std::invalid_argument(kOption[d] + ": a " + kind_name + " takes " + takes);
  }
  double* dim[3] = {&spec.a_m, &spec.b_m, &spec.c_m};
  for (int d = 0; d < dims; ++d) {
    if (cmd.count(kOption[d]) > 0)
      continue;
    if (!size.default_m) {
      std::string need = "--a-m";
      if (dims > 1)
        need += dims == 2 ? " and --b-m" : ", --b-m and --c-m";
      throw std::invalid_argument(kOption[d] + ": a " + kind_name + " has no default size: give " +
                                  need + " " + std::string(size.meaning) + " in metres");
    }
    *dim[d] = (*size.default_m)[static_cast<std::size_t>(d)];
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
  const std::size_t written = sc::write_target_file(spec, out);
  std::printf("%s: %s, %zu triangles\n", out.c_str(), sc::target_size_text(spec).c_str(), written);
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
      ->add_option(
          "--a-m", a->spec.a_m,
          "First dimension [m]: plate/box x, fold length, trihedral edge, radius, vehicle or "
          "aircraft length (default: the vehicles' and aircraft's sizes of "
          "scene/targets.hpp, as [[target]]; the shapes have none)")
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
