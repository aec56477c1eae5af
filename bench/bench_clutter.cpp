// Frame-path costs of the environment physics (issue 4 speed goals): a sigma0 lookup in the
// setup-time table (goal: 20 ns or less) and the two-way attenuation of a 10 km path through
// three media (goal: 1 us or less); with the direct model evaluations they replace, measured
// side by side in one run for the ratio, and the setup time of one material's table.
#include <benchmark/benchmark.h>

#include <cmath>
#include <vector>

#include "radar/clutter/terrain.hpp"
#include "radar/propagation/path.hpp"

namespace {

using namespace radar_emu::radar;

std::vector<clutter::SurfaceSpec> specs_at(double f_hz) {
  std::vector<clutter::SurfaceSpec> out;
  for (const clutter::TerrainMaterial& m : clutter::terrain_catalogue())
    out.push_back(clutter::resolve_surface(m, f_hz));
  return out;
}

void BM_Sigma0TableLookup(benchmark::State& state) {
  // Built once for the whole process (several seconds: 12 materials x 1801 angles, each with
  // the IEM's cross-polarised integral), not once per benchmark run.
  static const clutter::Sigma0Table table(specs_at(94e9), clutter::Sigma0Model::kTotal, 94e9);
  // A pseudo-random walk over materials and angles, as terrain hits arrive in a frame.
  std::uint32_t x = 12345;
  float sum = 0.0f;
  for (auto _ : state) {
    x = x * 1664525u + 1013904223u;
    const std::size_t m = (x >> 8) % table.materials();
    const double c = static_cast<double>(x >> 9) * (1.0 / 8388608.0);
    sum += table.lookup(m, clutter::Sigma0Table::kVV, c);
  }
  benchmark::DoNotOptimize(sum);
}
BENCHMARK(BM_Sigma0TableLookup);

void BM_Sigma0DirectIem(benchmark::State& state) {
  const auto spec = clutter::resolve_surface(*clutter::find_terrain_material("asphalt"), 94e9);
  double theta = 0.1;
  for (auto _ : state) {
    theta = theta > 1.4 ? 0.1 : theta + 0.01;
    benchmark::DoNotOptimize(clutter::evaluate_sigma0(spec, clutter::Sigma0Model::kTotal, 94e9,
                                                      clutter::Geometry::backscatter(theta)));
  }
}
BENCHMARK(BM_Sigma0DirectIem);

void BM_Sigma0TableBuildOneMaterial(benchmark::State& state) {
  // Setup cost the table moves out of the frame: 1801 angles of the surface + volume model,
  // four polarisations (the IEM's cross-polarised double integral dominates), all cores.
  const std::vector<clutter::SurfaceSpec> one{
      clutter::resolve_surface(*clutter::find_terrain_material("asphalt"), 94e9)};
  for (auto _ : state) {
    const clutter::Sigma0Table table(one, clutter::Sigma0Model::kTotal, 94e9);
    benchmark::DoNotOptimize(table.materials());
  }
}
BENCHMARK(BM_Sigma0TableBuildOneMaterial)->Unit(benchmark::kMillisecond)->Iterations(3);

void BM_TwoWayPathThreeMedia(benchmark::State& state) {
  const Atmosphere air{1013.25, 288.15, 7.5};
  const MediumSpec media[] = {
      {"clear", air, 0.0, 0.0}, {"rain", air, 10.0, 0.0}, {"fog", air, 0.0, 0.05}};
  const PathAttenuation table(94e9, 0.0, media);
  PathSegment path[] = {{0, 6000.0}, {1, 3000.0}, {2, 1000.0}};
  for (auto _ : state) {
    path[0].length_m += 1e-9;  // keep the compiler from hoisting the call
    benchmark::DoNotOptimize(table.two_way_loss_db(path));
  }
}
BENCHMARK(BM_TwoWayPathThreeMedia);

void BM_PathDirectItu(benchmark::State& state) {
  // What the table saves: evaluating P.676 line-by-line (and P.838, P.840) per query.
  const Atmosphere air{1013.25, 288.15, 7.5};
  for (auto _ : state) {
    const double gas = gaseous_specific_attenuation(94e9, air).total_db_per_km();
    const double rain = rain_specific_attenuation_db_per_km(94e9, 10.0, 0.0, 0.0);
    const double fog = cloud_fog_specific_attenuation_db_per_km(94e9, 0.05, 288.15);
    benchmark::DoNotOptimize(2.0 * (gas * 10.0 + rain * 3.0 + fog * 1.0));
  }
}
BENCHMARK(BM_PathDirectItu);

}  // namespace

BENCHMARK_MAIN();
