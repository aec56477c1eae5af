#include "radar/products/sar_terrain.hpp"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <complex>
#include <stdexcept>

#include "radar/clutter/terrain.hpp"
#include "radar/em/surfaces.hpp"

namespace radar_emu::radar {

TerrainCells terrain_cells(const scene::Scene& scene, const SbrTracer& tracer, const SarParams& p,
                           const TerrainCellSpec& spec) {
  validate(p);
  clutter::validate(spec.speckle);
  if (!(spec.cell_m > 0.0) || !std::isfinite(spec.cell_m))
    throw std::invalid_argument("sar terrain: cell size must be > 0");
  if (spec.along * spec.across > 200'000'000ull)
    throw std::invalid_argument("sar terrain: more than 2e8 cells; make the cells larger");
  // sigma0 of the scene's materials: the tracer's, resolved once at its carrier.
  if (tracer.config().carrier_hz != p.carrier_hz)
    throw std::invalid_argument("sar terrain: the tracer's carrier differs from the SAR carrier");
  const SurfaceSet& surfaces = tracer.surfaces();
  TerrainCells out;
  if (std::none_of(surfaces.surfaces.begin(), surfaces.surfaces.end(),
                   [](const Surface& s) { return s.sigma0_row >= 0; }))
    return out;
  const clutter::Sigma0Table::Pol pol = sigma0_channel(spec.polarisation);
  const glm::dvec3 track = sar_track_dir(p), look = sar_look_dir(p);

  struct Line {
    std::vector<SarScatterer> cells;
    std::size_t shadowed = 0, empty = 0;
  };
  std::vector<Line> lines(spec.along);
  tbb::parallel_for(std::size_t{0}, spec.along, [&](std::size_t i) {
    Line& line = lines[i];
    for (std::size_t j = 0; j < spec.across; ++j) {
      const std::uint64_t index = static_cast<std::uint64_t>(i) * spec.across + j;
      const glm::dvec3 xy = spec.origin_m + static_cast<double>(i) * spec.cell_m * track +
                            static_cast<double>(j) * spec.cell_m * look;
      const scene::Ray down{{xy.x, xy.y, xy.z + 5000.0}, {0.0, 0.0, -1.0}, 0.0, 10000.0};
      scene::Hit hit;
      if (!scene.intersect(down, hit) || tracer.is_target(hit.object_id) ||
          hit.material_id >= surfaces.surfaces.size() ||
          surfaces.surfaces[hit.material_id].sigma0_row < 0) {
        ++line.empty;
        continue;
      }
      glm::dvec3 n = hit.normal;
      if (n.z < 0.0)
        n = -n;
      // The platform at broadside of the cell.
      const glm::dvec3 radar =
          p.start_position_m + glm::dot(hit.position_m - p.start_position_m, track) * track;
      const glm::dvec3 to = radar - hit.position_m;
      const double dist = glm::length(to);
      const double cos_inc = glm::dot(n, to / dist);
      const scene::Ray up{hit.position_m + 0.01 * n, to / dist, 0.0, dist};
      if (cos_inc <= 0.0 || scene.occluded(up)) {
        ++line.shadowed;
        continue;
      }
      const double s0 = static_cast<double>(surfaces.sigma0_table.lookup(
          static_cast<std::size_t>(surfaces.surfaces[hit.material_id].sigma0_row), pol, cos_inc));
      const clutter::SpeckleSample s = clutter::speckle_sample(spec.speckle, index);
      const double area = spec.cell_m * spec.cell_m / std::max(n.z, 1e-3);
      line.cells.push_back(
          {hit.position_m, std::polar(std::sqrt(s0 * area * static_cast<double>(s.intensity)),
                                      static_cast<double>(s.phase_rad))});
    }
  });
  std::size_t total = 0;
  for (const Line& l : lines)
    total += l.cells.size();
  out.cells.reserve(total);
  for (const Line& l : lines) {
    out.cells.insert(out.cells.end(), l.cells.begin(), l.cells.end());
    out.shadowed += l.shadowed;
    out.empty += l.empty;
  }
  (void)look;
  return out;
}

}  // namespace radar_emu::radar
