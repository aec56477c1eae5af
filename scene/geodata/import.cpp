#include "scene/geodata/import.hpp"

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <csignal>
#include <cstdio>
#include <limits>
#include <optional>
#include <sstream>
#include <stdexcept>
#include <string>
#include <utility>

#include "common/units.hpp"
#include "scene/geo.hpp"
#include "scene/geodata/osm.hpp"
#include "scene/geodata/polygon.hpp"
#include "scene/scene_builders.hpp"
#include "scene/terrain_gen.hpp"

namespace radar_emu::scene::geodata {
namespace {

constexpr std::uint64_t kBytesPerLoadedTriangle = 64;  // Embree BVH and references, about

std::size_t sz(int i) {
  return static_cast<std::size_t>(i);
}

std::string deg_text(double rad) {
  char b[32];
  std::snprintf(b, sizeof b, "%.6f", common::degrees(rad));
  return b;
}

// A regular grid of square cells; nodes (i, j), i west-east 0..nx, j south-north 0..ny.
struct Grid {
  double x0_m = 0.0, y0_m = 0.0, cell_m = 1.0;
  int nx = 0, ny = 0;
  // Cells skipped (entirely inside this rectangle): the surround's hole.
  bool has_hole = false;
  double hole_x0 = 0, hole_y0 = 0, hole_x1 = 0, hole_y1 = 0;
  std::vector<float> z_m;                // (nx + 1) (ny + 1) node heights, ENU
  std::vector<std::uint16_t> material;   // nx ny level-0 cell materials
  std::vector<std::int64_t> cell_class;  // nx ny land-cover class (or kNoClass)
  int rows_sampled = 0;                  // node rows 0 .. rows_sampled - 1 have heights

  [[nodiscard]] double x(int i) const { return x0_m + cell_m * i; }
  [[nodiscard]] double y(int j) const { return y0_m + cell_m * j; }
  [[nodiscard]] std::size_t node(int i, int j) const {
    return static_cast<std::size_t>(j) * static_cast<std::size_t>(nx + 1) +
           static_cast<std::size_t>(i);
  }
  [[nodiscard]] std::size_t cell(int i, int j) const {
    return static_cast<std::size_t>(j) * static_cast<std::size_t>(nx) + static_cast<std::size_t>(i);
  }
  // Whether the box [xa, xb] x [ya, yb] lies entirely inside the hole.
  [[nodiscard]] bool in_hole(double xa, double ya, double xb, double yb) const {
    constexpr double kTol = 1e-6;
    return has_hole && xa >= hole_x0 - kTol && xb <= hole_x1 + kTol && ya >= hole_y0 - kTol &&
           yb <= hole_y1 + kTol;
  }
  [[nodiscard]] bool covers(double px, double py) const {
    return px >= x0_m && py >= y0_m && px <= x(nx) && py <= y(ny);
  }
  // Height of the level-0 mesh at (px, py) (the cell's two triangles split along (i,j)-(i+1,j+1)).
  [[nodiscard]] double height(double px, double py) const {
    const double u0 = std::clamp((px - x0_m) / cell_m, 0.0, static_cast<double>(nx));
    const double v0 = std::clamp((py - y0_m) / cell_m, 0.0, static_cast<double>(ny));
    const int i = std::min(static_cast<int>(u0), nx - 1),
              j = std::min(static_cast<int>(v0), ny - 1);
    const double u = u0 - i, v = v0 - j;
    const double z00 = static_cast<double>(z_m[node(i, j)]),
                 z10 = static_cast<double>(z_m[node(i + 1, j)]),
                 z11 = static_cast<double>(z_m[node(i + 1, j + 1)]),
                 z01 = static_cast<double>(z_m[node(i, j + 1)]);
    if (u >= v)
      return z00 + u * (z10 - z00) + v * (z11 - z10);
    return z00 + u * (z11 - z01) + v * (z01 - z00);
  }
};
constexpr std::int64_t kNoClass = std::numeric_limits<std::int64_t>::min();

// Node index lists of a tile at one level: every step-th node from a to b, b always included.
std::vector<int> lod_nodes(int a, int b, int step) {
  std::vector<int> v;
  for (int k = a; k < b; k += step)
    v.push_back(k);
  v.push_back(b);
  return v;
}

struct GridShape {
  int nx = 0, ny = 0;
};

// Triangles and vertices of a grid's tiles over all levels (what build_tiles makes).
void count_grid(const Grid& g, int tile_cells, int levels, std::uint64_t& triangles,
                std::uint64_t& vertices) {
  for (int tj = 0; tj * tile_cells < g.ny; ++tj) {
    for (int ti = 0; ti * tile_cells < g.nx; ++ti) {
      const int i0 = ti * tile_cells, i1 = std::min(g.nx, i0 + tile_cells);
      const int j0 = tj * tile_cells, j1 = std::min(g.ny, j0 + tile_cells);
      if (g.in_hole(g.x(i0), g.y(j0), g.x(i1), g.y(j1)))
        continue;
      for (int l = 0; l < levels; ++l) {
        const auto is = lod_nodes(i0, i1, 1 << l), js = lod_nodes(j0, j1, 1 << l);
        std::uint64_t cells = 0;
        for (std::size_t b = 0; b + 1 < js.size(); ++b) {
          for (std::size_t a = 0; a + 1 < is.size(); ++a)
            cells += g.in_hole(g.x(is[a]), g.y(js[b]), g.x(is[a + 1]), g.y(js[b + 1])) ? 0u : 1u;
        }
        triangles += 2 * cells;
        vertices += static_cast<std::uint64_t>(is.size()) * js.size();
      }
    }
  }
}

Grid central_grid(const ImportSpec& s) {
  Grid g;
  g.cell_m = s.central_cell_m;
  g.nx = std::max(1, static_cast<int>(std::lround(s.central_east_m / s.central_cell_m)));
  g.ny = std::max(1, static_cast<int>(std::lround(s.central_north_m / s.central_cell_m)));
  g.x0_m = -0.5 * g.nx * g.cell_m;
  g.y0_m = -0.5 * g.ny * g.cell_m;
  return g;
}

Grid surround_grid(const ImportSpec& s, const Grid& central) {
  Grid g;
  g.cell_m = s.surround_cell_m;
  g.nx = g.ny = std::max(1, static_cast<int>(std::lround(s.surround_side_m / s.surround_cell_m)));
  g.x0_m = g.y0_m = -0.5 * g.nx * g.cell_m;
  g.has_hole = true;
  g.hole_x0 = central.x0_m;
  g.hole_y0 = central.y0_m;
  g.hole_x1 = central.x(central.nx);
  g.hole_y1 = central.y(central.ny);
  return g;
}

void check_spec(const ImportSpec& s) {
  auto bad = [](const std::string& field, const std::string& what) {
    throw std::invalid_argument("geodata import: " + field + ": " + what);
  };
  auto positive = [&](const char* field, double v) {
    if (!(std::isfinite(v) && v > 0.0))
      bad(field, "must be a positive number of metres");
  };
  if (s.dem.empty())
    bad("dem", "is required");
  if (!(std::abs(s.anchor_latitude_rad) < common::radians(89.0)) ||
      !(std::abs(s.anchor_longitude_rad) <= common::kPi))
    bad("anchor", "latitude must be within +-89 deg, longitude within +-180 deg");
  positive("central_east_m", s.central_east_m);
  positive("central_north_m", s.central_north_m);
  positive("central_cell_m", s.central_cell_m);
  if (s.central_east_m > 40000.0 || s.central_north_m > 40000.0)
    bad("central", "at most 40 km a side (float vertices keep mm precision within +-20 km)");
  if (s.surround_side_m != 0.0) {
    positive("surround_side_m", s.surround_side_m);
    positive("surround_cell_m", s.surround_cell_m);
    if (s.surround_side_m > 40000.0)
      bad("surround_side_m", "at most 40 km");
    if (s.surround_side_m < std::max(s.central_east_m, s.central_north_m))
      bad("surround_side_m", "must be at least the central area's larger side");
  }
  if (s.lod_levels < 1 || s.lod_levels > 4)
    bad("lod_levels", "must be 1 .. 4");
  if (s.tile_cells < 2 || s.tile_cells > 1024 || s.tile_cells % (1 << (s.lod_levels - 1)) != 0)
    bad("tile_cells", "must be 2 .. 1024 and a multiple of 2^(lod_levels - 1)");
  if (!s.landcover.empty() && s.classes.material_by_class.empty())
    bad("classes", "a land-cover raster needs a class -> material table");
  positive("level_height_m", s.level_height_m);
  positive("default_levels", s.default_levels);
  if (!(s.draped_offset_m >= 0.0 && s.draped_offset_m < 10.0))
    bad("draped_offset_m", "must be in [0, 10) m");
}

// Material registry; preview colours from the generated database's table (terrain_gen.hpp).
class Materials {
 public:
  explicit Materials(SceneDescription& d) : d_(d) {}
  std::uint16_t operator()(const std::string& name) {
    for (std::size_t k = 0; k < d_.materials.size(); ++k) {
      if (d_.materials[k].name == name)
        return static_cast<std::uint16_t>(k);
    }
    const Material m{name, terrain_preview_colour(name)};
    d_.materials.push_back(m);
    return static_cast<std::uint16_t>(d_.materials.size() - 1);
  }

 private:
  SceneDescription& d_;
};

// Heights of the DEM at WGS84 points, on the ellipsoid.
class Heights {
 public:
  Heights(const GeoRaster& dem, const Egm96* geoid) : dem_(dem), geoid_(geoid) {}
  // h[i] (ellipsoidal) at the points; false at points off the DEM (h NaN).
  void sample(std::span<const double> lat, std::span<const double> lon, std::span<double> h,
              std::vector<double>& col, std::vector<double>& row) const {
    col.resize(lat.size());
    row.resize(lat.size());
    dem_.pixels_from_geodetic(lat, lon, col, row);
    for (std::size_t k = 0; k < lat.size(); ++k) {
      if (!dem_.contains(col[k], row[k])) {
        h[k] = std::numeric_limits<double>::quiet_NaN();
        continue;
      }
      h[k] = dem_.bilinear(col[k], row[k]) + (geoid_ ? geoid_->undulation_m(lat[k], lon[k]) : 0.0);
    }
  }
  [[nodiscard]] const GeoRaster& dem() const { return dem_; }

 private:
  const GeoRaster& dem_;
  const Egm96* geoid_;
};

void progress(const ImportSpec& s, const std::string& line) {
  if (s.progress)
    s.progress(line);
}

std::string signal_text(int signal) {
  return signal == SIGINT    ? "SIGINT"
         : signal == SIGTERM ? "SIGTERM"
                             : "signal " + std::to_string(signal);
}

// The import's rows of work (height-grid node rows, then rows of tiles) for the progress line,
// and the stop flag polled between them.
struct Steps {
  const common::WorkControl& control;
  std::size_t done = 0, total = 0;
  int stopped = 0;  // the signal that stopped the import, 0 while it runs
  bool stop() {
    if (stopped == 0)
      stopped = control.stop_signal();
    return stopped != 0;
  }
  void step() { control.report(++done, total); }
};

// Node heights of a grid (two passes per node, see import.hpp).
void sample_grid(Grid& g, const Heights& heights, const wgs84::EnuFrame& frame,
                 const ImportSpec& spec, const char* label, Steps& steps) {
  g.z_m.assign(sz(g.nx + 1) * sz(g.ny + 1), 0.0f);
  g.rows_sampled = 0;
  const std::size_t n = static_cast<std::size_t>(g.nx) + 1;
  std::vector<double> lat(n), lon(n), h(n), col, row, z(n, 0.0);
  int next_report = 1;
  for (int j = 0; j <= g.ny; ++j) {
    if (steps.stop())
      return;
    std::fill(z.begin(), z.end(), 0.0);
    for (int pass = 0; pass < 2; ++pass) {
      for (int i = 0; i <= g.nx; ++i) {
        const wgs84::Geodetic geo = frame.geodetic_from_enu({g.x(i), g.y(j), z[sz(i)]});
        lat[sz(i)] = geo.latitude_rad;
        lon[sz(i)] = geo.longitude_rad;
      }
      heights.sample(lat, lon, h, col, row);
      for (int i = 0; i <= g.nx; ++i) {
        if (!std::isfinite(h[sz(i)])) {
          std::ostringstream os;
          os << heights.dem().path().string() << ": dem: the " << label << " grid's node at E "
             << g.x(i) << " m, N " << g.y(j) << " m (latitude " << deg_text(lat[sz(i)])
             << " deg, longitude " << deg_text(lon[sz(i)])
             << " deg) is outside the raster: give a smaller area or a larger DEM";
          throw std::runtime_error(os.str());
        }
        z[sz(i)] = frame.enu_from_geodetic({lat[sz(i)], lon[sz(i)], h[sz(i)]}).z;
      }
    }
    for (int i = 0; i <= g.nx; ++i)
      g.z_m[g.node(i, j)] = static_cast<float>(z[sz(i)]);
    g.rows_sampled = j + 1;
    steps.step();
    if (j * 10 >= next_report * g.ny) {
      progress(spec, std::string("import: ") + label + " heights " +
                         std::to_string(next_report * 10) + " %");
      ++next_report;
    }
  }
}

// Land-cover classes and materials of a grid's level-0 cells.
void classify_grid(Grid& g, const GeoRaster* landcover, const ClassTable& table,
                   std::uint16_t default_material, Materials& materials,
                   const wgs84::EnuFrame& frame, ImportReport& report) {
  g.material.assign(sz(g.nx) * sz(g.ny), default_material);
  g.cell_class.assign(g.material.size(), kNoClass);
  if (landcover == nullptr)
    return;
  std::map<std::int64_t, std::uint16_t> index;
  for (const auto& [code, name] : table.material_by_class)
    index[code] = materials(name);
  std::optional<std::uint16_t> fallback;
  if (table.fallback)
    fallback = materials(*table.fallback);
  const std::size_t n = static_cast<std::size_t>(g.nx);
  std::vector<double> lat(n), lon(n), col(n), row(n);
  for (int j = 0; j < g.ny; ++j) {
    for (int i = 0; i < g.nx; ++i) {
      const double cx = g.x(i) + 0.5 * g.cell_m, cy = g.y(j) + 0.5 * g.cell_m;
      const double cz =
          0.25 * static_cast<double>(g.z_m[g.node(i, j)] + g.z_m[g.node(i + 1, j)] +
                                     g.z_m[g.node(i, j + 1)] + g.z_m[g.node(i + 1, j + 1)]);
      const wgs84::Geodetic geo = frame.geodetic_from_enu({cx, cy, cz});
      lat[sz(i)] = geo.latitude_rad;
      lon[sz(i)] = geo.longitude_rad;
    }
    landcover->pixels_from_geodetic(lat, lon, col, row);
    for (int i = 0; i < g.nx; ++i) {
      if (g.in_hole(g.x(i), g.y(j), g.x(i + 1), g.y(j + 1)))
        continue;
      const bool on = landcover->contains(col[sz(i)], row[sz(i)]);
      const int c = on ? std::min(static_cast<int>(col[sz(i)]), landcover->width() - 1) : 0;
      const int r = on ? std::min(static_cast<int>(row[sz(i)]), landcover->height() - 1) : 0;
      const bool nodata = !on || landcover->was_nodata(c, r);
      const std::int64_t code = nodata ? kNoClass : static_cast<std::int64_t>(landcover->at(c, r));
      const auto it = index.find(code);
      std::uint16_t m = 0;
      if (it != index.end()) {
        m = it->second;
      } else if (fallback) {
        m = *fallback;
        ++report.unknown_class_cells;
      } else {
        std::ostringstream os;
        os << landcover->path().string() << ": landcover: ";
        if (nodata)
          os << "no class (no-data or off the raster)";
        else
          os << "class " << code << " is not in the table \"" << table.name << "\"";
        os << " at latitude " << deg_text(lat[sz(i)]) << " deg, longitude " << deg_text(lon[sz(i)])
           << " deg: add it to the table or give the table a fallback material";
        throw std::runtime_error(os.str());
      }
      g.material[g.cell(i, j)] = m;
      g.cell_class[g.cell(i, j)] = code;
    }
  }
}

// Tiles of a grid as LOD objects.
// Rows of tiles of a grid.
int tile_rows(const Grid& g, const ImportSpec& spec) {
  return (g.ny + spec.tile_cells - 1) / spec.tile_cells;
}

// The tiles of the grid's rows of tiles whose every node has its height (all of them unless the
// import was stopped while sampling): meshing the heights is quick, so a stop heard later (while
// the OpenStreetMap file is read) still keeps every height sampled. Returns the rows built.
int build_tiles(const Grid& g, const ImportSpec& spec, const char* prefix, const char* area,
                std::int32_t& next_group, SceneDescription& d, Steps& steps) {
  int built = 0;
  for (int tj = 0; tj * spec.tile_cells < g.ny; ++tj) {
    if (std::min(g.ny, (tj + 1) * spec.tile_cells) >= g.rows_sampled)
      break;
    ++built;
    for (int ti = 0; ti * spec.tile_cells < g.nx; ++ti) {
      const int i0 = ti * spec.tile_cells, i1 = std::min(g.nx, i0 + spec.tile_cells);
      const int j0 = tj * spec.tile_cells, j1 = std::min(g.ny, j0 + spec.tile_cells);
      if (g.in_hole(g.x(i0), g.y(j0), g.x(i1), g.y(j1)))
        continue;
      const std::int32_t group = next_group++;
      for (int l = 0; l < spec.lod_levels; ++l) {
        const auto is = lod_nodes(i0, i1, 1 << l), js = lod_nodes(j0, j1, 1 << l);
        ObjectDesc o;
        char name[64];
        std::snprintf(name, sizeof name, "%s_r%02d_c%02d_lod%d", prefix, tj, ti, l);
        o.name = name;
        o.area = area;
        o.lod_group = group;
        o.lod_level = static_cast<std::uint8_t>(l);
        Mesh& m = o.mesh;
        m.positions_m.reserve(is.size() * js.size());
        for (int j : js) {
          for (int i : is)
            m.positions_m.emplace_back(g.x(i), g.y(j), g.z_m[g.node(i, j)]);
        }
        const auto w = static_cast<std::uint32_t>(is.size());
        for (std::size_t b = 0; b + 1 < js.size(); ++b) {
          for (std::size_t a = 0; a + 1 < is.size(); ++a) {
            if (g.in_hole(g.x(is[a]), g.y(js[b]), g.x(is[a + 1]), g.y(js[b + 1])))
              continue;
            // The level-0 cell under the coarse cell's centre gives its material.
            const int ci = std::min((is[a] + is[a + 1]) / 2, g.nx - 1);
            const int cj = std::min((js[b] + js[b + 1]) / 2, g.ny - 1);
            const std::uint16_t mat = g.material[g.cell(ci, cj)];
            const auto v00 = static_cast<std::uint32_t>(b) * w + static_cast<std::uint32_t>(a);
            const std::uint32_t v10 = v00 + 1, v01 = v00 + w, v11 = v01 + 1;
            m.triangles.push_back({v00, v10, v11});
            m.triangles.push_back({v00, v11, v01});
            m.triangle_material.push_back(mat);
            m.triangle_material.push_back(mat);
          }
        }
        if (!m.triangles.empty())
          d.objects.push_back(std::move(o));
      }
    }
    steps.step();
  }
  return built;
}

// ---- OSM features -------------------------------------------------------------------------

double parse_metres(const std::string& text) {
  if (text.empty())
    return std::numeric_limits<double>::quiet_NaN();
  char* end = nullptr;
  const double v = std::strtod(text.c_str(), &end);
  if (end == text.c_str() || !std::isfinite(v) || v <= 0.0)
    return std::numeric_limits<double>::quiet_NaN();
  std::string rest(end);
  rest.erase(0, rest.find_first_not_of(' '));
  if (rest == "ft" || rest == "'")
    return v * 0.3048;
  return v;  // "m", "" and anything else: metres (OSM's default unit)
}

struct Terrain {
  const Grid& central;
  const Grid* surround;
  [[nodiscard]] std::optional<double> height(glm::dvec2 p) const {
    if (central.covers(p.x, p.y))
      return central.height(p.x, p.y);
    if (surround && surround->covers(p.x, p.y))
      return surround->height(p.x, p.y);
    return std::nullopt;
  }
};

class Features {
 public:
  Features(const ImportSpec& spec, const wgs84::EnuFrame& frame, const Heights& central,
           const Heights* surround, const Terrain& terrain, Materials& materials,
           SceneDescription& d, ImportReport& report)
      : spec_(spec),
        frame_(frame),
        central_(central),
        surround_(surround),
        terrain_(terrain),
        mat_(materials),
        d_(d),
        report_(report) {}

  // ENU x, y of a WGS84 point at the terrain's height there; nullopt off both DEMs.
  std::optional<glm::dvec2> enu(const LonLat& p) {
    const double lat[1] = {p.latitude_rad}, lon[1] = {p.longitude_rad};
    double h[1] = {0.0};
    central_.sample(lat, lon, h, col_, row_);
    if (!std::isfinite(h[0]) && surround_)
      surround_->sample(lat, lon, h, col_, row_);
    if (!std::isfinite(h[0]))
      return std::nullopt;
    const glm::dvec3 e = frame_.enu_from_geodetic({p.latitude_rad, p.longitude_rad, h[0]});
    return glm::dvec2(e.x, e.y);
  }
  // ENU z of the DEM's surface under (x, y) (`z_guess` near it); z_guess off the DEMs.
  double dem_z(glm::dvec2 q, double z_guess) {
    const wgs84::Geodetic g = frame_.geodetic_from_enu({q.x, q.y, z_guess});
    const double lat[1] = {g.latitude_rad}, lon[1] = {g.longitude_rad};
    double h[1] = {0.0};
    central_.sample(lat, lon, h, col_, row_);
    if (!std::isfinite(h[0]) && surround_)
      surround_->sample(lat, lon, h, col_, row_);
    if (!std::isfinite(h[0]))
      return z_guess;
    return frame_.enu_from_geodetic({g.latitude_rad, g.longitude_rad, h[0]}).z;
  }

  std::optional<std::vector<glm::dvec2>> enu_line(const std::vector<LonLat>& pts) {
    std::vector<glm::dvec2> out;
    for (const LonLat& p : pts) {
      const auto e = enu(p);
      if (!e || !terrain_.height(*e))
        return std::nullopt;
      if (out.empty() || glm::length(*e - out.back()) > 1e-3)
        out.push_back(*e);
    }
    return out;
  }

  void strip(const std::string& name, const std::vector<glm::dvec2>& line, double width_m,
             std::uint16_t material) {
    const double step = 0.5 * spec_.central_cell_m;
    std::vector<glm::dvec2> p;
    for (std::size_t k = 0; k + 1 < line.size(); ++k) {
      const double len = glm::length(line[k + 1] - line[k]);
      const int n = std::max(1, static_cast<int>(std::ceil(len / step)));
      for (int s = 0; s < n; ++s)
        p.push_back(line[k] + (line[k + 1] - line[k]) * (static_cast<double>(s) / n));
    }
    p.push_back(line.back());
    ObjectDesc o;
    o.name = name;
    o.area = "central";
    Mesh& m = o.mesh;
    const double hw = 0.5 * width_m;
    for (std::size_t k = 0; k < p.size(); ++k) {
      const glm::dvec2 dir =
          glm::normalize(p[std::min(k + 1, p.size() - 1)] - p[k == 0 ? 0 : k - 1]);
      const glm::dvec2 left(-dir.y, dir.x);
      for (const glm::dvec2 q : {p[k] + hw * left, p[k] - hw * left}) {
        // On the DEM, lifted to the level-0 mesh where that lies higher (valleys, where the
        // mesh's straight facets cut above the bilinear surface): never under the ground.
        const double mesh = terrain_.height(q).value_or(terrain_.height(p[k]).value_or(0.0));
        const double z = std::max(mesh, dem_z(q, mesh));
        m.positions_m.emplace_back(q.x, q.y, z + spec_.draped_offset_m);
      }
      if (k > 0) {
        const auto l0 = static_cast<std::uint32_t>(2 * (k - 1)), r0 = l0 + 1, l1 = l0 + 2,
                   r1 = l0 + 3;
        m.triangles.push_back({r0, r1, l1});
        m.triangles.push_back({r0, l1, l0});
        m.triangle_material.push_back(material);
        m.triangle_material.push_back(material);
      }
    }
    if (!m.triangles.empty())
      d_.objects.push_back(std::move(o));
  }

  void way(const OsmWay& w) {
    const std::string highway = tag(w.tags, "highway"), aeroway = tag(w.tags, "aeroway"),
                      power = tag(w.tags, "power"), surface = tag(w.tags, "surface");
    if (!tag(w.tags, "building").empty()) {
      ++report_.osm_broken_ways;  // a building way that is not closed
      return;
    }
    const bool is_road = !highway.empty() && highway != "proposed" && highway != "construction";
    const bool is_runway = aeroway == "runway", is_taxiway = aeroway == "taxiway";
    const bool is_power = power == "line" || power == "minor_line";
    if (!is_road && !is_runway && !is_taxiway && !is_power) {
      ++report_.osm_ignored;
      return;
    }
    const auto line = enu_line(w.points);
    if (!line || line->size() < 2) {
      ++report_.osm_outside;
      return;
    }
    if (is_power) {
      power_line(*line, w.tags);
      return;
    }
    double width = parse_metres(tag(w.tags, "width"));
    std::string material = "asphalt";
    if (surface.rfind("concrete", 0) == 0 || surface == "paving_stones")
      material = "concrete";
    else if (surface == "gravel" || surface == "unpaved" || surface == "dirt" ||
             surface == "ground" || surface == "compacted" || surface == "fine_gravel")
      material = "gravel";
    if (is_runway || is_taxiway) {
      if (!std::isfinite(width))
        width = is_runway ? 45.0 : 23.0;
      const std::size_t k = is_runway ? report_.osm_runways++ : report_.osm_taxiways++;
      strip((is_runway ? "runway_" : "taxiway_") + std::to_string(k), *line, width, mat_(material));
      return;
    }
    static const std::map<std::string, double, std::less<>> kWidth{
        {"motorway", 14.0}, {"trunk", 12.0},      {"primary", 10.0},     {"secondary", 8.0},
        {"tertiary", 7.0},  {"residential", 5.0}, {"unclassified", 5.0}, {"service", 4.0},
        {"track", 3.0},     {"path", 1.5},        {"footway", 1.5},      {"cycleway", 2.0}};
    if (!std::isfinite(width)) {
      const auto it = kWidth.find(highway.substr(0, highway.find("_link")));
      width = it == kWidth.end() ? 5.0 : it->second;
    }
    if (surface.empty() && (highway == "track" || highway == "path"))
      material = "gravel";
    strip("road_" + std::to_string(report_.osm_roads++), *line, width, mat_(material));
  }

  void power_line(const std::vector<glm::dvec2>& line, const Tags& tags) {
    ++report_.osm_power_lines;
    double h = parse_metres(tag(tags, "height"));
    if (!std::isfinite(h))
      h = spec_.pylon_height_m;
    const std::uint16_t metal = mat_("metal");
    const double arm_half = 0.25 * h, conductor_drop = 0.1 * h;
    std::vector<glm::dvec3> base(line.size());
    std::vector<glm::dvec2> across(line.size());
    for (std::size_t k = 0; k < line.size(); ++k) {
      const glm::dvec2 dir =
          glm::normalize(line[std::min(k + 1, line.size() - 1)] - line[k == 0 ? 0 : k - 1]);
      across[k] = {-dir.y, dir.x};
      base[k] = {line[k].x, line[k].y, terrain_.height(line[k]).value_or(0.0)};
      // Pylon: a tapered open 4-sided frustum and a cross arm across the line.
      ObjectDesc o;
      o.name = "pylon_" + std::to_string(report_.osm_pylons++);
      o.area = "central";
      const glm::dvec3 x(dir, 0.0), y(across[k], 0.0), z(0, 0, 1);
      o.world_from_body =
          glm::dmat4(glm::dvec4(x, 0), glm::dvec4(y, 0), glm::dvec4(z, 0), glm::dvec4(base[k], 1));
      Mesh& m = o.mesh;
      const float b = static_cast<float>(0.05 * h), t = static_cast<float>(0.0125 * h),
                  hf = static_cast<float>(h);
      const glm::vec3 lo[4] = {{-b, -b, 0}, {b, -b, 0}, {b, b, 0}, {-b, b, 0}};
      const glm::vec3 hi[4] = {{-t, -t, hf}, {t, -t, hf}, {t, t, hf}, {-t, t, hf}};
      for (int s = 0; s < 4; ++s)
        scene::detail::add_quad(m, lo[s], lo[(s + 1) % 4], hi[(s + 1) % 4], hi[s], metal);
      const float arm_z = static_cast<float>(h - conductor_drop);
      scene::detail::add_box(m, {-0.4f, static_cast<float>(-arm_half), arm_z - 0.8f},
                             {0.4f, static_cast<float>(arm_half), arm_z}, metal);
      d_.objects.push_back(std::move(o));
    }
    // Conductors: arm ends and the top, sagging 2 % of the span mid-span, 3-sided tubes.
    for (std::size_t k = 0; k + 1 < line.size(); ++k) {
      const double span = glm::length(line[k + 1] - line[k]);
      for (int c = 0; c < 3; ++c) {
        const double off = c == 2 ? 0.0 : (c == 0 ? arm_half : -arm_half);
        const double dz = c == 2 ? h : h - conductor_drop - 0.8;
        const glm::dvec3 a = base[k] + glm::dvec3(off * across[k], dz);
        const glm::dvec3 b = base[k + 1] + glm::dvec3(off * across[k + 1], dz);
        const glm::dvec3 mid = 0.5 * (a + b);
        ObjectDesc o;
        o.name = "wire_" + std::to_string(wire_span_) + "_" + std::to_string(c);
        o.area = "central";
        o.world_from_body = scene::detail::translation(mid);
        constexpr int kSeg = 16;
        constexpr double kRadius = 0.015;
        const glm::dvec3 along = glm::normalize(b - a);
        const glm::dvec3 side = glm::normalize(glm::cross(along, glm::dvec3(0, 0, 1)));
        const glm::dvec3 up = glm::cross(side, along);
        Mesh& m = o.mesh;
        for (int s = 0; s <= kSeg; ++s) {
          const double t = static_cast<double>(s) / kSeg;
          const glm::dvec3 p = a + t * (b - a) - glm::dvec3(0, 0, 4.0 * 0.02 * span * t * (1 - t));
          for (int r = 0; r < 3; ++r) {
            const double ang = 2.0 * common::kPi * r / 3.0;
            const glm::dvec3 q = p + kRadius * (std::cos(ang) * side + std::sin(ang) * up) - mid;
            m.positions_m.emplace_back(q);
          }
          if (s > 0) {
            const auto r0 = static_cast<std::uint32_t>(3 * (s - 1)), r1 = r0 + 3;
            for (std::uint32_t r = 0; r < 3; ++r) {
              const std::uint32_t rn = (r + 1) % 3;
              m.triangles.push_back({r0 + r, r1 + r, r1 + rn});
              m.triangles.push_back({r0 + r, r1 + rn, r0 + rn});
              m.triangle_material.push_back(metal);
              m.triangle_material.push_back(metal);
            }
          }
        }
        d_.objects.push_back(std::move(o));
      }
      ++wire_span_;
    }
  }

  void building(const OsmArea& a) {
    double height = parse_metres(tag(a.tags, "height"));
    const double levels = parse_metres(tag(a.tags, "building:levels"));
    if (std::isfinite(height)) {
      ++report_.osm_buildings_height;
    } else if (std::isfinite(levels)) {
      height = levels * spec_.level_height_m;
      ++report_.osm_buildings_levels;
    } else {
      height = spec_.default_levels * spec_.level_height_m;
      ++report_.osm_buildings_default;
    }
    const std::string kind = tag(a.tags, "building");
    const std::uint16_t walls = mat_("concrete");
    const std::uint16_t roof =
        (kind == "hangar" || kind == "industrial" || kind == "warehouse") ? mat_("metal") : walls;
    for (const auto& poly : a.polygons) {
      if (poly.size() > 1)
        ++report_.osm_courtyards_roofed;
      auto ring = enu_line(poly[0]);
      if (!ring) {
        ++report_.osm_outside;
        continue;
      }
      if (ring->size() > 1 && glm::length(ring->front() - ring->back()) < 1e-3)
        ring->pop_back();
      if (ring->size() < 3) {
        ++report_.osm_broken_ways;
        continue;
      }
      if (detail::signed_area2(*ring) < 0.0)
        std::reverse(ring->begin(), ring->end());
      double ground = std::numeric_limits<double>::infinity();
      glm::dvec2 centre(0.0);
      for (const glm::dvec2 p : *ring) {
        ground = std::min(ground, *terrain_.height(p));
        centre += p / static_cast<double>(ring->size());
      }
      ObjectDesc o;
      o.name = "building_" + std::to_string(report_.osm_buildings++);
      o.area = "central";
      o.world_from_body = scene::detail::translation({centre, ground});
      Mesh& m = o.mesh;
      const auto top = static_cast<float>(height);
      std::vector<glm::dvec2> local;
      for (const glm::dvec2 p : *ring)
        local.push_back(p - centre);
      for (std::size_t k = 0; k < local.size(); ++k) {
        const glm::dvec2 p = local[k], q = local[(k + 1) % local.size()];
        scene::detail::add_quad(m, {p.x, p.y, 0.0f}, {q.x, q.y, 0.0f}, {q.x, q.y, top},
                                {p.x, p.y, top}, walls);
      }
      const auto base = static_cast<std::uint32_t>(m.positions_m.size());
      for (const glm::dvec2 p : local)
        m.positions_m.emplace_back(p.x, p.y, top);
      for (const glm::uvec3 t : detail::triangulate(local)) {
        m.triangles.push_back(t + base);
        m.triangle_material.push_back(roof);
      }
      d_.objects.push_back(std::move(o));
    }
  }

  void mast(const OsmNode& n) {
    const auto p = enu(n.at);
    const auto ground = p ? terrain_.height(*p) : std::nullopt;
    if (!ground) {
      ++report_.osm_outside;
      return;
    }
    double h = parse_metres(tag(n.tags, "height"));
    if (!std::isfinite(h))
      h = spec_.mast_height_m;
    ObjectDesc o;
    o.name = "mast_" + std::to_string(report_.osm_masts++);
    o.area = "central";
    o.world_from_body = scene::detail::translation({*p, *ground});
    scene::detail::add_box(o.mesh, {-0.75f, -0.75f, 0.0f}, {0.75f, 0.75f, static_cast<float>(h)},
                           mat_("metal"));
    d_.objects.push_back(std::move(o));
  }

 private:
  const ImportSpec& spec_;
  const wgs84::EnuFrame& frame_;
  const Heights& central_;
  const Heights* surround_;
  const Terrain& terrain_;
  Materials& mat_;
  SceneDescription& d_;
  ImportReport& report_;
  std::vector<double> col_, row_;
  std::size_t wire_span_ = 0;
};

// Material an OSM area paints on the cells under it, and its priority (higher wins); none: not
// a land area the import models.
std::optional<std::pair<std::string, int>> area_material(const Tags& t) {
  const std::string landuse = tag(t, "landuse"), natural = tag(t, "natural"),
                    aeroway = tag(t, "aeroway"), surface = tag(t, "surface");
  if (natural == "water" || !tag(t, "water").empty() || landuse == "reservoir" ||
      landuse == "basin" || tag(t, "waterway") == "riverbank")
    return std::pair<std::string, int>{"water", 4};
  if (aeroway == "apron" || aeroway == "runway" || aeroway == "taxiway")
    return std::pair<std::string, int>{surface == "asphalt" ? "asphalt" : "concrete", 5};
  if (landuse == "forest" || natural == "wood")
    return std::pair<std::string, int>{"forest", 3};
  if (landuse == "farmland" || landuse == "orchard" || landuse == "vineyard")
    return std::pair<std::string, int>{"crops", 1};
  if (landuse == "meadow" || landuse == "grass" || natural == "grassland" || natural == "heath" ||
      natural == "scrub")
    return std::pair<std::string, int>{"grass", 1};
  if (landuse == "residential" || landuse == "industrial" || landuse == "commercial" ||
      landuse == "retail")
    return std::pair<std::string, int>{"urban", 2};
  if (natural == "bare_rock" || natural == "sand" || landuse == "construction" ||
      landuse == "quarry")
    return std::pair<std::string, int>{"soil_dry", 1};
  if (natural == "wetland")
    return std::pair<std::string, int>{"soil_wet", 1};
  return std::nullopt;
}

void paint(Grid& g, const std::vector<std::vector<glm::dvec2>>& rings, std::uint16_t material) {
  glm::dvec2 lo(std::numeric_limits<double>::infinity()), hi(-lo);
  for (const auto& r : rings) {
    for (const glm::dvec2 p : r) {
      lo = glm::min(lo, p);
      hi = glm::max(hi, p);
    }
  }
  const int i0 = std::max(0, static_cast<int>(std::floor((lo.x - g.x0_m) / g.cell_m)));
  const int i1 = std::min(g.nx - 1, static_cast<int>(std::floor((hi.x - g.x0_m) / g.cell_m)));
  const int j0 = std::max(0, static_cast<int>(std::floor((lo.y - g.y0_m) / g.cell_m)));
  const int j1 = std::min(g.ny - 1, static_cast<int>(std::floor((hi.y - g.y0_m) / g.cell_m)));
  for (int j = j0; j <= j1; ++j) {
    for (int i = i0; i <= i1; ++i) {
      const glm::dvec2 c(g.x(i) + 0.5 * g.cell_m, g.y(j) + 0.5 * g.cell_m);
      if (detail::inside(rings, c))
        g.material[g.cell(i, j)] = material;
    }
  }
}

}  // namespace

ImportEstimate estimate_import(const ImportSpec& spec) {
  check_spec(spec);
  ImportEstimate e;
  const Grid c = central_grid(spec);
  e.central_nodes = static_cast<std::uint64_t>(c.nx + 1) * static_cast<std::uint64_t>(c.ny + 1);
  count_grid(c, spec.tile_cells, spec.lod_levels, e.triangles, e.vertices);
  std::uint64_t cells = static_cast<std::uint64_t>(c.nx) * static_cast<std::uint64_t>(c.ny);
  if (spec.surround_side_m > 0.0) {
    const Grid s = surround_grid(spec, c);
    e.surround_nodes = static_cast<std::uint64_t>(s.nx + 1) * static_cast<std::uint64_t>(s.ny + 1);
    count_grid(s, spec.tile_cells, spec.lod_levels, e.triangles, e.vertices);
    cells += static_cast<std::uint64_t>(s.nx) * static_cast<std::uint64_t>(s.ny);
  }
  // Heights (float), materials (u16) and classes (i64) per cell, the meshes (vertex 12 B,
  // triangle 12 + 2 B), and the same meshes again while a writer serialises them.
  e.import_bytes = (e.central_nodes + e.surround_nodes) * 4 + cells * 10 +
                   2 * (e.vertices * 12 + e.triangles * 14);
  e.load_bytes = e.vertices * 12 + e.triangles * (14 + kBytesPerLoadedTriangle);
  const std::uint64_t peak = std::max(e.import_bytes, e.load_bytes);
  if (peak > spec.max_memory_bytes) {
    std::ostringstream os;
    os << "geodata import: estimated " << e.triangles << " triangles, " << e.vertices
       << " vertices: " << (e.import_bytes >> 20) << " MiB to import, " << (e.load_bytes >> 20)
       << " MiB to load, over the limit of " << (spec.max_memory_bytes >> 20)
       << " MiB (coarser cells, smaller areas or a higher limit)";
    throw std::runtime_error(os.str());
  }
  return e;
}

SceneDescription import_geodata(const ImportSpec& spec, ImportReport& report) {
  const auto t0 = std::chrono::steady_clock::now();
  report = ImportReport{};
  report.estimate = estimate_import(spec);
  progress(spec, "import: estimated " + std::to_string(report.estimate.triangles) +
                     " terrain triangles, " + std::to_string(report.estimate.load_bytes >> 20) +
                     " MiB loaded");

  GeoRaster dem(spec.dem, "dem", true);
  report.dem_holes_filled = dem.fill_holes();
  report.dem_spacing_m = dem.spacing_m();
  std::optional<GeoRaster> surround_dem;
  if (!spec.surround_dem.empty()) {
    surround_dem.emplace(spec.surround_dem, "surround dem", true);
    report.dem_holes_filled += surround_dem->fill_holes();
  }

  // Vertical datum.
  auto resolve = [&](const GeoRaster& r) {
    const VerticalDatum stated = r.stated_vertical_datum();
    if (spec.datum == DatumChoice::kEgm96)
      return std::pair<bool, std::string>{true, "EGM96 geoid (as told) -> WGS84 ellipsoid"};
    if (spec.datum == DatumChoice::kEllipsoid)
      return std::pair<bool, std::string>{false, "WGS84 ellipsoid (as told): unchanged"};
    if (stated == VerticalDatum::kEllipsoid)
      return std::pair<bool, std::string>{false, "WGS84 ellipsoid (stated by the file): unchanged"};
    if (stated == VerticalDatum::kEgm96)
      return std::pair<bool, std::string>{true, "EGM96 geoid (stated by the file: " +
                                                    r.vertical_crs_name() + ") -> WGS84 ellipsoid"};
    return std::pair<bool, std::string>{
        true,
        "EGM96 geoid (the file states no vertical datum: assumed, as SRTM and DTED) -> "
        "WGS84 ellipsoid"};
  };
  const auto [geoid_central, text_central] = resolve(dem);
  report.vertical = text_central;
  bool geoid_surround = geoid_central;
  if (surround_dem) {
    const auto r = resolve(*surround_dem);
    geoid_surround = r.first;
    report.vertical += "; surround: " + r.second;
  }
  std::optional<Egm96> egm96;
  if (geoid_central || geoid_surround)
    egm96.emplace();
  const Heights central_heights(dem, geoid_central ? &*egm96 : nullptr);
  std::optional<Heights> surround_heights;
  if (surround_dem)
    surround_heights.emplace(*surround_dem, geoid_surround ? &*egm96 : nullptr);

  // Anchor.
  {
    const double lat[1] = {spec.anchor_latitude_rad}, lon[1] = {spec.anchor_longitude_rad};
    double h[1];
    std::vector<double> col, row;
    central_heights.sample(lat, lon, h, col, row);
    if (!std::isfinite(h[0])) {
      double la0, lo0, la1, lo1;
      dem.geodetic_from_pixel(0, dem.height(), la0, lo0);
      dem.geodetic_from_pixel(dem.width(), 0, la1, lo1);
      throw std::runtime_error(
          spec.dem.string() + ": dem: the anchor (latitude " + deg_text(spec.anchor_latitude_rad) +
          " deg, longitude " + deg_text(spec.anchor_longitude_rad) +
          " deg) is outside the raster (about latitude " + deg_text(la0) + " .. " + deg_text(la1) +
          " deg, longitude " + deg_text(lo0) + " .. " + deg_text(lo1) + " deg)");
    }
    report.anchor_height_m = h[0];
    report.anchor_undulation_m = egm96 && geoid_central ? egm96->undulation_m(lat[0], lon[0]) : 0.0;
  }
  SceneDescription d;
  d.anchor = {spec.anchor_latitude_rad, spec.anchor_longitude_rad, report.anchor_height_m};
  const wgs84::EnuFrame frame(d.anchor);

  // Grids: heights.
  Grid central = central_grid(spec);
  std::optional<Grid> surround;
  if (spec.surround_side_m > 0.0)
    surround = surround_grid(spec, central);
  Steps steps{spec.control};
  for (const Grid* g : {&central, surround ? &*surround : nullptr}) {
    if (g != nullptr)
      steps.total += static_cast<std::size_t>(g->ny + 1 + tile_rows(*g, spec));
  }
  steps.control.report(0, steps.total);
  sample_grid(central, central_heights, frame, spec, "central", steps);
  if (surround) {
    sample_grid(*surround, surround_heights ? *surround_heights : central_heights, frame, spec,
                "surround", steps);
  }

  // Grids: land cover, then OSM areas over it.
  Materials materials(d);
  const std::uint16_t default_material = materials(spec.default_material);
  std::optional<GeoRaster> landcover;
  if (!spec.landcover.empty())
    landcover.emplace(spec.landcover, "landcover", false);
  progress(spec, "import: land cover");
  classify_grid(central, landcover ? &*landcover : nullptr, spec.classes, default_material,
                materials, frame, report);
  if (surround)
    classify_grid(*surround, landcover ? &*landcover : nullptr, spec.classes, default_material,
                  materials, frame, report);

  const Terrain terrain{central, surround ? &*surround : nullptr};
  Features features(spec, frame, central_heights, surround_heights ? &*surround_heights : nullptr,
                    terrain, materials, d, report);
  std::optional<OsmData> osm;
  if (!spec.osm.empty() && !steps.stop()) {
    progress(spec, "import: OpenStreetMap features");
    osm = read_osm(spec.osm);
    report.osm_broken_ways = osm->broken_ways;
    struct Painted {
      std::vector<std::vector<glm::dvec2>> rings;
      std::uint16_t material;
      int priority;
    };
    std::vector<Painted> painted;
    for (const OsmArea& a : osm->areas) {
      if (!tag(a.tags, "building").empty() && tag(a.tags, "building") != "no")
        continue;
      const auto m = area_material(a.tags);
      if (!m) {
        ++report.osm_ignored;
        continue;
      }
      bool any = false;
      for (const auto& poly : a.polygons) {
        Painted p{{}, materials(m->first), m->second};
        bool ok = true;
        for (const auto& ring : poly) {
          std::vector<glm::dvec2> r;
          for (const LonLat& q : ring) {
            const auto e = features.enu(q);
            if (!e) {
              ok = false;
              break;
            }
            r.push_back(*e);
          }
          if (!ok)
            break;
          p.rings.push_back(std::move(r));
        }
        if (ok) {
          painted.push_back(std::move(p));
          any = true;
        }
      }
      if (any)
        ++report.osm_areas;
      else
        ++report.osm_outside;
    }
    std::stable_sort(painted.begin(), painted.end(),
                     [](const Painted& a, const Painted& b) { return a.priority < b.priority; });
    for (const Painted& p : painted) {
      paint(central, p.rings, p.material);
      if (surround)
        paint(*surround, p.rings, p.material);
    }
  }

  // Level-0 cell counts per class and material.
  auto count = [&](const Grid& g) {
    for (int j = 0; j < g.ny; ++j) {
      for (int i = 0; i < g.nx; ++i) {
        if (g.in_hole(g.x(i), g.y(j), g.x(i + 1), g.y(j + 1)))
          continue;
        const std::size_t k = g.cell(i, j);
        if (landcover && g.cell_class[k] != kNoClass)
          ++report.cells_by_class[g.cell_class[k]];
        ++report.cells_by_material[d.materials[g.material[k]].name];
      }
    }
  };
  count(central);
  if (surround)
    count(*surround);

  progress(spec, "import: tiles");
  std::int32_t group = 0;
  const int central_rows = build_tiles(central, spec, "terrain", "central", group, d, steps);
  const int surround_rows =
      surround ? build_tiles(*surround, spec, "surround", "surround", group, d, steps) : 0;

  if (steps.stop()) {
    // What is whole is kept; the scene says what is missing (the glTF carries it).
    std::ostringstream os;
    os << "import stopped by " << signal_text(steps.stopped) << ": central " << central_rows
       << " of " << tile_rows(central, spec) << " rows of tiles (heights of "
       << central.rows_sampled << " of " << central.ny + 1 << " node rows)";
    if (surround) {
      os << ", surround " << surround_rows << " of " << tile_rows(*surround, spec)
         << " rows of tiles (heights of " << surround->rows_sampled << " of " << surround->ny + 1
         << " node rows)";
    }
    os << ", no OpenStreetMap features";
    d.incomplete = os.str();
    if (d.objects.empty()) {
      // glTF needs a mesh: the anchor's ground cell stands for the empty terrain.
      ObjectDesc o;
      o.name = "terrain_stopped_before_any_tile";
      o.area = "central";
      const auto c = static_cast<float>(central.cell_m / 2.0);
      o.mesh.positions_m = {{-c, -c, 0.0f}, {c, -c, 0.0f}, {c, c, 0.0f}, {-c, c, 0.0f}};
      o.mesh.triangles = {{0, 1, 2}, {0, 2, 3}};
      o.mesh.triangle_material = {default_material, default_material};
      d.objects.push_back(std::move(o));
    }
    report.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    return d;
  }

  if (osm) {
    for (const OsmWay& w : osm->ways)
      features.way(w);
    for (const OsmArea& a : osm->areas) {
      const std::string b = tag(a.tags, "building");
      if (!b.empty() && b != "no")
        features.building(a);
    }
    for (const OsmNode& n : osm->nodes) {
      const std::string mm = tag(n.tags, "man_made");
      if (mm == "mast" || mm == "tower" || mm == "communications_tower")
        features.mast(n);
      else if (tag(n.tags, "power") != "tower" && tag(n.tags, "power") != "pole")
        ++report.osm_ignored;  // pylons come from their power=line ways
    }
  }
  report.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return d;
}

std::string report_text(const ImportReport& r) {
  std::ostringstream os;
  os << "heights: " << r.vertical << "\n";
  os << "anchor ground: " << r.anchor_height_m << " m above the ellipsoid";
  if (r.anchor_undulation_m != 0.0)
    os << " (EGM96 N = " << r.anchor_undulation_m << " m)";
  os << "\nDEM spacing: " << r.dem_spacing_m << " m; no-data pixels filled: " << r.dem_holes_filled
     << "\n";
  os << "terrain: " << r.estimate.triangles << " triangles (all LOD levels), "
     << r.estimate.vertices << " vertices\n";
  if (!r.cells_by_class.empty()) {
    os << "land-cover cells by class:";
    for (const auto& [c, n] : r.cells_by_class)
      os << " " << c << ":" << n;
    os << "; given the fallback: " << r.unknown_class_cells << "\n";
  }
  os << "level-0 cells by material:";
  for (const auto& [m, n] : r.cells_by_material)
    os << " " << m << ":" << n;
  os << "\nOSM: " << r.osm_roads << " roads, " << r.osm_runways << " runways, " << r.osm_taxiways
     << " taxiways, " << r.osm_areas << " areas, " << r.osm_buildings << " buildings ("
     << r.osm_buildings_height << " by height, " << r.osm_buildings_levels << " by levels, "
     << r.osm_buildings_default << " default, " << r.osm_courtyards_roofed
     << " courtyards roofed), " << r.osm_power_lines << " power lines (" << r.osm_pylons
     << " pylons), " << r.osm_masts << " masts; dropped: " << r.osm_broken_ways << " broken ways, "
     << r.osm_outside << " off the terrain; not modelled: " << r.osm_ignored << "\n";
  os << "import time: " << r.seconds << " s\n";
  return os.str();
}

}  // namespace radar_emu::scene::geodata
