#include "scene/terrain_gen.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <limits>
#include <numeric>
#include <optional>
#include <random>
#include <stdexcept>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "common/units.hpp"

namespace radar_emu::scene {
namespace {

using Layout = TerrainLayout;
using common::kPi;
constexpr double kInf = std::numeric_limits<double>::infinity();
constexpr double kHalfEast_m = Layout::kCentralEast_m / 2.0;
constexpr double kHalfNorth_m = Layout::kCentralNorth_m / 2.0;
constexpr double kHalfSurround_m = Layout::kSurroundSide_m / 2.0;
constexpr int kCellsX = Layout::kTileColumns * Layout::kTileCells;  // level-0 cells west-east
constexpr int kCellsY = Layout::kTileRows * Layout::kTileCells;     // level-0 cells south-north
static_assert(Layout::kTileColumns * Layout::kTile_m == Layout::kCentralEast_m);
static_assert(Layout::kTileRows * Layout::kTile_m == Layout::kCentralNorth_m);
static_assert(Layout::kTileCells % (1 << (Layout::kLodLevels - 1)) == 0);

// Surround grid: n1 / m1 cells from the outer edge to the central area, and the central span cut
// into cells of kRingFine level-0 cells (their inner edges take the central boundary nodes).
constexpr int kRingFine = 16;
constexpr int kSurroundOuterX = 20;                   // 7.5 km / 20 = 375 m
constexpr int kSurroundOuterY = 17;                   // 6.5 km / 17 = 382 m
constexpr int kSurroundInnerX = kCellsX / kRingFine;  // 15 cells of 333 m
constexpr int kSurroundInnerY = kCellsY / kRingFine;  // 21 cells of 333 m
static_assert(kCellsX % kRingFine == 0 && kCellsY % kRingFine == 0);

// Feature dimensions [m].
constexpr double kRiverStep_m = 10.0;           // river centreline sampling (y step)
constexpr double kRiverBedHalf_m = 40.0;        // bed half-width (water half-width + a cell)
constexpr double kRiverWetHalf_m = 16.0;        // wet soil: under the water and its edges
constexpr double kRiverDepth_m = 2.0;           // bed below the water
constexpr double kRiverTaperMax_m = 400.0;      // bank taper outer radius, at most
constexpr double kSurroundRiverWidth_m = 25.0;  // drawn wider on the coarse grid
constexpr double kValleyDepth_m = 6.0;          // valley along the river
constexpr double kValleyWidth_m = 350.0;        // Gaussian width of the valley
constexpr double kLakeDepth_m = 2.0;            // bed below the lake surface
constexpr double kRoadStep_m = 10.0;            // road sampling along its length
constexpr double kRampSlope = 0.05;             // bridge approach ramps
constexpr double kDeckThickness_m = 1.2;        // bridge deck
constexpr double kDeckClearance_m = 4.3;        // deck underside above the water, at least
constexpr double kPylonSpacing_m = 300.0;       // power line
constexpr double kPylonHeight_m = 30.0;
constexpr double kArmHeight_m = 25.0;  // cross-arm underside
constexpr double kArmHalfSpan_m = 7.0;
constexpr double kConductorOffset_m = 6.5;  // conductors below the arm ends
constexpr double kWireRadius_m = 0.015;
constexpr double kWireSag_m = 4.0;  // mid-span sag of a 300 m span
constexpr int kWireSegments = 16;
constexpr int kTreeTriangles = 24;
constexpr std::size_t kMinTrees = 50;

// Materials (indices into SceneDescription::materials), radar/clutter/terrain.hpp names; colours
// are linear RGB for previews.
namespace mat {
constexpr std::uint16_t kAsphalt = 0, kConcrete = 1, kGrass = 2, kCrops = 3, kForest = 4,
                        kSoilDry = 5, kSoilWet = 6, kWater = 7, kGravel = 8, kUrban = 9,
                        kMetal = 10, kCount = 11;
struct Def {
  const char* name;
  float r, g, b;
};
constexpr std::array<Def, kCount> kDefs{{{"asphalt", 0.09f, 0.09f, 0.10f},
                                         {"concrete", 0.55f, 0.55f, 0.52f},
                                         {"grass", 0.16f, 0.36f, 0.09f},
                                         {"crops", 0.45f, 0.42f, 0.12f},
                                         {"forest", 0.05f, 0.16f, 0.05f},
                                         {"soil_dry", 0.42f, 0.30f, 0.18f},
                                         {"soil_wet", 0.20f, 0.14f, 0.08f},
                                         {"water", 0.05f, 0.14f, 0.30f},
                                         {"gravel", 0.40f, 0.38f, 0.35f},
                                         {"urban", 0.36f, 0.29f, 0.25f},
                                         {"metal", 0.70f, 0.72f, 0.75f}}};
}  // namespace mat

// Materials no generator places but an imported scene may carry (GIS land cover): preview only.
constexpr std::array<mat::Def, 1> kPreviewOnly{{{"snow", 0.90f, 0.90f, 0.95f}}};

// Level-0 node coordinates: one formula everywhere, so shared vertices are bit-identical.
double node_x(int i) {
  return -kHalfEast_m + Layout::kCentralEast_m * i / kCellsX;
}
double node_y(int j) {
  return -kHalfNorth_m + Layout::kCentralNorth_m * j / kCellsY;
}

bool in_central(glm::dvec2 p, double margin_m = 0.0) {
  return std::abs(p.x) <= kHalfEast_m - margin_m && std::abs(p.y) <= kHalfNorth_m - margin_m;
}

double smoothstep(double e0, double e1, double x) {
  const double t = std::clamp((x - e0) / (e1 - e0), 0.0, 1.0);
  return t * t * (3.0 - 2.0 * t);
}

glm::dvec2 perp(glm::dvec2 d) {
  return {-d.y, d.x};
}  // left of d

// Deterministic random numbers: std::mt19937_64 is fully specified by the standard; the
// distributions are ours (std:: distributions are implementation-defined).
class Rng {
 public:
  explicit Rng(std::uint64_t seed) : engine_(seed) {}
  double uniform() { return static_cast<double>(engine_() >> 11) * 0x1.0p-53; }  // [0, 1)
  double uniform(double lo, double hi) { return lo + (hi - lo) * uniform(); }
  int integer(int lo, int hi) {  // [lo, hi]
    return std::min(hi, lo + static_cast<int>(uniform() * (hi - lo + 1)));
  }
  double sign() { return uniform() < 0.5 ? -1.0 : 1.0; }

 private:
  std::mt19937_64 engine_;
};

struct SegmentHit {
  double d_m = kInf;  // distance to the segment
  double t = 0.0;     // parameter of the nearest point, 0..1
};
SegmentHit segment_distance(glm::dvec2 p, glm::dvec2 a, glm::dvec2 b) {
  const glm::dvec2 ab = b - a;
  const double len2 = glm::dot(ab, ab);
  const double t = len2 > 0.0 ? std::clamp(glm::dot(p - a, ab) / len2, 0.0, 1.0) : 0.0;
  return {glm::length(p - (a + t * ab)), t};
}

// A polyline with its cumulative length.
struct Polyline {
  std::vector<glm::dvec2> p;
  std::vector<double> s;
  void finish() {
    s.assign(p.size(), 0.0);
    for (std::size_t i = 1; i < p.size(); ++i)
      s[i] = s[i - 1] + glm::length(p[i] - p[i - 1]);
  }
  [[nodiscard]] double length() const { return s.empty() ? 0.0 : s.back(); }
  // Point at arc length `at` (clamped) and the unit direction there.
  glm::dvec2 at(double at_m, glm::dvec2& dir) const {
    at_m = std::clamp(at_m, 0.0, length());
    std::size_t i =
        static_cast<std::size_t>(std::upper_bound(s.begin(), s.end(), at_m) - s.begin());
    i = std::clamp<std::size_t>(i, 1, p.size() - 1);
    const double seg = s[i] - s[i - 1];
    dir = glm::normalize(p[i] - p[i - 1]);
    return p[i - 1] + (seg > 0.0 ? (at_m - s[i - 1]) / seg : 0.0) * (p[i] - p[i - 1]);
  }
  [[nodiscard]] glm::dvec2 direction(std::size_t i) const {  // at sample i (central difference)
    const std::size_t a = i == 0 ? 0 : i - 1, b = std::min(i + 1, p.size() - 1);
    return glm::normalize(p[b] - p[a]);
  }
};

struct Road {
  std::string name;
  Polyline line;
  double half_width_m = 3.5;
  double offset_m = 0.2;  // above the level-0 ground
  std::uint16_t material = mat::kAsphalt;
};

// Uniform grid of road segments: clearance = distance from the nearest road edge.
class RoadIndex {
 public:
  static constexpr double kCell_m = 100.0;
  void build(const std::vector<Road>& roads) {
    segs_.clear();
    for (const Road& r : roads) {
      for (std::size_t i = 1; i < r.line.p.size(); ++i)
        segs_.push_back({r.line.p[i - 1], r.line.p[i], r.half_width_m});
    }
    lo_ = glm::dvec2(-kHalfSurround_m);
    n_ = static_cast<int>(std::ceil(Layout::kSurroundSide_m / kCell_m));
    cells_.assign(static_cast<std::size_t>(n_ * n_), {});
    for (std::size_t k = 0; k < segs_.size(); ++k) {
      const Seg& s = segs_[k];
      const glm::dvec2 a = glm::min(s.a, s.b) - s.hw, b = glm::max(s.a, s.b) + s.hw;
      for (int cy = cell(a.y); cy <= cell(b.y); ++cy) {
        for (int cx = cell(a.x); cx <= cell(b.x); ++cx)
          cells_[index(cx, cy)].push_back(static_cast<std::uint32_t>(k));
      }
    }
  }
  // Distance from p to the nearest road edge (negative on a road); +inf beyond `radius_m`.
  [[nodiscard]] double clearance(glm::dvec2 p, double radius_m) const {
    double best = kInf;
    for (int cy = cell(p.y - radius_m); cy <= cell(p.y + radius_m); ++cy) {
      for (int cx = cell(p.x - radius_m); cx <= cell(p.x + radius_m); ++cx) {
        for (std::uint32_t k : cells_[index(cx, cy)]) {
          const Seg& s = segs_[k];
          best = std::min(best, segment_distance(p, s.a, s.b).d_m - s.hw);
        }
      }
    }
    return best;
  }

 private:
  struct Seg {
    glm::dvec2 a, b;
    double hw;
  };
  [[nodiscard]] int cell(double v) const {
    return std::clamp(static_cast<int>(std::floor((v - lo_.x) / kCell_m)), 0, n_ - 1);
  }
  [[nodiscard]] std::size_t index(int cx, int cy) const {
    return static_cast<std::size_t>(cy * n_ + cx);
  }
  std::vector<Seg> segs_;
  std::vector<std::vector<std::uint32_t>> cells_;
  glm::dvec2 lo_{0.0};
  int n_ = 1;
};

// The river: x = f(y) over the whole domain, flowing south to north.
struct River {
  double x0 = 0, a1 = 0, k1 = 0, p1 = 0, a2 = 0, k2 = 0, p2 = 0;
  std::vector<glm::dvec2> c;    // centreline samples, y = -10 km + k kRiverStep_m
  std::vector<double> level_m;  // water level at each sample (non-increasing downstream)
  std::vector<double> taper_m;  // outer radius of the carved banks at each sample
  [[nodiscard]] double x_at(double y) const {
    return x0 + a1 * std::sin(k1 * y + p1) + a2 * std::sin(k2 * y + p2);
  }
  [[nodiscard]] double slope(double y) const {  // dx/dy
    return a1 * k1 * std::cos(k1 * y + p1) + a2 * k2 * std::cos(k2 * y + p2);
  }
  // Smooth distance for the valley (first order in the curvature; exact on straight reaches).
  [[nodiscard]] double valley_distance(glm::dvec2 p) const {
    const double s = slope(p.y);
    return std::abs(p.x - x_at(p.y)) / std::sqrt(1.0 + s * s);
  }
  struct Near {
    double d_m = kInf;
    double level_m = 0.0;
    double taper_m = 0.0;
  };
  // Exact distance to the centreline polyline when within `radius_m`.
  [[nodiscard]] Near nearest(glm::dvec2 p, double radius_m) const {
    Near best;
    const double k_lo = std::floor((p.y - radius_m + kHalfSurround_m) / kRiverStep_m);
    const double k_hi = std::ceil((p.y + radius_m + kHalfSurround_m) / kRiverStep_m);
    const auto last = static_cast<double>(c.size() - 2);
    const auto lo = static_cast<std::size_t>(std::clamp(k_lo, 0.0, last));
    const auto hi = static_cast<std::size_t>(std::clamp(k_hi, 0.0, last));
    std::size_t seg = c.size();
    SegmentHit hit;
    for (std::size_t k = lo; k <= hi; ++k) {
      if (std::abs(p.x - c[k].x) > radius_m + 2.0 * kRiverStep_m)
        continue;
      const SegmentHit h = segment_distance(p, c[k], c[k + 1]);
      if (h.d_m < hit.d_m) {
        hit = h;
        seg = k;
      }
    }
    if (seg == c.size() || hit.d_m > radius_m)
      return best;
    best.d_m = hit.d_m;
    best.level_m = level_m[seg] + hit.t * (level_m[seg + 1] - level_m[seg]);
    best.taper_m = taper_m[seg] + hit.t * (taper_m[seg + 1] - taper_m[seg]);
    return best;
  }
};

struct Lake {
  glm::dvec2 c{0.0};
  double a_m = 1, b_m = 1, rot = 0;
  double level_m = 0.0;
  double bank_in_m = -40, bank_out_m = 10;  // the bed rises to the shore over [in, out]
  [[nodiscard]] glm::dvec2 point(double theta) const {
    const glm::dvec2 u(a_m * std::cos(theta), b_m * std::sin(theta));
    return c + glm::dvec2(std::cos(rot) * u.x - std::sin(rot) * u.y,
                          std::sin(rot) * u.x + std::cos(rot) * u.y);
  }
  // Signed distance to the shore ellipse, first order ((r - 1) / |grad r|): exact on the axes,
  // negative inside.
  [[nodiscard]] double sdist(glm::dvec2 p) const {
    const glm::dvec2 d = p - c;
    const double u = std::cos(rot) * d.x + std::sin(rot) * d.y;
    const double v = -std::sin(rot) * d.x + std::cos(rot) * d.y;
    const double r = std::sqrt(u * u / (a_m * a_m) + v * v / (b_m * b_m));
    const double g = std::sqrt(u * u / std::pow(a_m, 4) + v * v / std::pow(b_m, 4));
    if (r < 1e-9 || g <= 0.0)
      return -std::min(a_m, b_m);
    return (r - 1.0) * r / g;
  }
  // Basin: bed kLakeDepth_m under the surface, rising to at least 0.5 m above it at the shore.
  [[nodiscard]] double shape(double g, glm::dvec2 p) const {
    const double d = sdist(p);
    if (d >= bank_out_m + 50.0)
      return g;
    const double bed = level_m - kLakeDepth_m;
    const double top =
        g + std::max(0.0, level_m + 0.5 - g) * (1.0 - smoothstep(bank_out_m, bank_out_m + 50.0, d));
    return bed + (top - bed) * smoothstep(bank_in_m, bank_out_m, d);
  }
};

// Voronoi parcels on a jittered grid, each with a material class.
struct Parcels {
  glm::dvec2 lo{0.0};
  double cell_m = 1;
  int nx = 0, ny = 0;
  std::vector<glm::dvec2> seed;
  std::vector<std::uint16_t> cls;
  void build(Rng& rng, glm::dvec2 area_lo, glm::dvec2 area_hi, double cell,
             const std::vector<std::pair<std::uint16_t, double>>& classes) {
    cell_m = cell;
    lo = area_lo - cell;
    nx = static_cast<int>(std::ceil((area_hi.x - area_lo.x) / cell)) + 2;
    ny = static_cast<int>(std::ceil((area_hi.y - area_lo.y) / cell)) + 2;
    for (int j = 0; j < ny; ++j) {
      for (int i = 0; i < nx; ++i) {
        seed.push_back(lo + cell * glm::dvec2(i + 0.5 + rng.uniform(-0.4, 0.4),
                                              j + 0.5 + rng.uniform(-0.4, 0.4)));
        double u = rng.uniform();
        std::uint16_t c = classes.back().first;
        for (const auto& [id, prob] : classes) {
          if (u < prob) {
            c = id;
            break;
          }
          u -= prob;
        }
        cls.push_back(c);
      }
    }
  }
  [[nodiscard]] std::uint16_t at(glm::dvec2 p) const {
    const int ci = static_cast<int>(std::floor((p.x - lo.x) / cell_m));
    const int cj = static_cast<int>(std::floor((p.y - lo.y) / cell_m));
    double best = kInf;
    std::uint16_t c = cls.front();
    for (int j = std::max(0, cj - 1); j <= std::min(ny - 1, cj + 1); ++j) {
      for (int i = std::max(0, ci - 1); i <= std::min(nx - 1, ci + 1); ++i) {
        const auto k = static_cast<std::size_t>(j * nx + i);
        const glm::dvec2 d = p - seed[k];
        if (glm::dot(d, d) < best) {
          best = glm::dot(d, d);
          c = cls[k];
        }
      }
    }
    return c;
  }
};

struct Building {
  glm::dvec2 c{0.0};
  double heading = 0, length_m = 10, width_m = 8, wall_m = 4, roof_m = 2;
  bool shed = false;
  [[nodiscard]] double radius() const { return 0.5 * std::hypot(length_m, width_m); }
};

// --- mesh helpers (body-frame coordinates in double, stored as float) ---

std::uint32_t add_vertex(Mesh& m, glm::dvec3 p) {
  m.positions_m.push_back(glm::vec3(p));
  return static_cast<std::uint32_t>(m.positions_m.size() - 1);
}

void add_triangle(Mesh& m, std::uint32_t a, std::uint32_t b, std::uint32_t c, std::uint16_t mat) {
  m.triangles.push_back({a, b, c});
  m.triangle_material.push_back(mat);
}

// Triangle with its normal on the side of `outward`.
void add_tri_facing(Mesh& m, glm::dvec3 a, glm::dvec3 b, glm::dvec3 c, glm::dvec3 outward,
                    std::uint16_t mat) {
  if (glm::dot(glm::cross(b - a, c - a), outward) < 0.0)
    std::swap(b, c);
  const std::uint32_t ia = add_vertex(m, a), ib = add_vertex(m, b), ic = add_vertex(m, c);
  add_triangle(m, ia, ib, ic, mat);
}

// Planar quad a b c d (in order around it, either way) facing `outward`.
void add_quad_facing(Mesh& m, glm::dvec3 a, glm::dvec3 b, glm::dvec3 c, glm::dvec3 d,
                     glm::dvec3 outward, std::uint16_t mat) {
  if (glm::dot(glm::cross(b - a, c - a) + glm::cross(c - a, d - a), outward) < 0.0)
    std::swap(b, d);
  const std::uint32_t ia = add_vertex(m, a), ib = add_vertex(m, b), ic = add_vertex(m, c),
                      id = add_vertex(m, d);
  add_triangle(m, ia, ib, ic, mat);
  add_triangle(m, ia, ic, id, mat);
}

// Hexahedron from its bottom (b0..b3) and top (t0..t3) quads, listed in the same order around;
// faces outward from its centroid (12 triangles).
void add_hexahedron(Mesh& m, const std::array<glm::dvec3, 4>& b, const std::array<glm::dvec3, 4>& t,
                    std::uint16_t mat) {
  glm::dvec3 centre(0.0);
  for (int k = 0; k < 4; ++k)
    centre += 0.125 * (b[static_cast<std::size_t>(k)] + t[static_cast<std::size_t>(k)]);
  auto face = [&](glm::dvec3 p, glm::dvec3 q, glm::dvec3 r, glm::dvec3 s) {
    add_quad_facing(m, p, q, r, s, 0.25 * (p + q + r + s) - centre, mat);
  };
  face(b[0], b[1], b[2], b[3]);
  face(t[0], t[1], t[2], t[3]);
  for (std::size_t k = 0; k < 4; ++k) {
    const std::size_t n = (k + 1) % 4;
    face(b[k], b[n], t[n], t[k]);
  }
}

// Box swept along the plan polyline c (its cross-sections perpendicular to the local direction):
// centred `offset` to the left of c, `half_w` either side of that, top at z_top, `depth` thick;
// closed with end caps, faces outward (8 triangles a segment, 4 for the caps).
void add_swept_box(Mesh& m, const std::vector<glm::dvec2>& c, const std::vector<double>& z_top,
                   double offset, double half_w, double depth, std::uint16_t mat) {
  const std::size_t n = c.size();
  std::vector<std::array<glm::dvec3, 4>> sec(n);  // left top, right top, right bottom, left bottom
  std::vector<glm::dvec2> dir(n);
  for (std::size_t i = 0; i < n; ++i) {
    dir[i] = glm::normalize(c[std::min(i + 1, n - 1)] - c[i > 0 ? i - 1 : 0]);
    const glm::dvec2 nrm = perp(dir[i]), mid = c[i] + offset * nrm;
    const glm::dvec2 l = mid + half_w * nrm, r = mid - half_w * nrm;
    sec[i] = {glm::dvec3(l, z_top[i]), glm::dvec3(r, z_top[i]), glm::dvec3(r, z_top[i] - depth),
              glm::dvec3(l, z_top[i] - depth)};
  }
  auto centre = [&](std::size_t i) {
    return 0.25 * (sec[i][0] + sec[i][1] + sec[i][2] + sec[i][3]);
  };
  for (std::size_t i = 0; i + 1 < n; ++i) {
    const glm::dvec3 mid = 0.5 * (centre(i) + centre(i + 1));
    for (std::size_t k = 0; k < 4; ++k) {
      const std::size_t k1 = (k + 1) % 4;
      const glm::dvec3 face = 0.25 * (sec[i][k] + sec[i][k1] + sec[i + 1][k1] + sec[i + 1][k]);
      add_quad_facing(m, sec[i][k], sec[i][k1], sec[i + 1][k1], sec[i + 1][k], face - mid, mat);
    }
  }
  add_quad_facing(m, sec[0][0], sec[0][1], sec[0][2], sec[0][3], -glm::dvec3(dir[0], 0.0), mat);
  add_quad_facing(m, sec[n - 1][0], sec[n - 1][1], sec[n - 1][2], sec[n - 1][3],
                  glm::dvec3(dir[n - 1], 0.0), mat);
}

void sort_by_material(Mesh& m) {
  std::vector<std::uint32_t> order(m.triangles.size());
  std::iota(order.begin(), order.end(), 0u);
  std::stable_sort(order.begin(), order.end(), [&](std::uint32_t x, std::uint32_t y) {
    return m.triangle_material[x] < m.triangle_material[y];
  });
  std::vector<glm::uvec3> tris;
  std::vector<std::uint16_t> mats;
  tris.reserve(order.size());
  mats.reserve(order.size());
  for (std::uint32_t k : order) {
    tris.push_back(m.triangles[k]);
    mats.push_back(m.triangle_material[k]);
  }
  m.triangles = std::move(tris);
  m.triangle_material = std::move(mats);
}

double longest_edge_m(const Mesh& m) {
  double best = 0.0;
  for (const glm::uvec3& t : m.triangles) {
    for (glm::length_t k = 0; k < 3; ++k) {
      const glm::dvec3 a(m.positions_m[t[k]]), b(m.positions_m[t[(k + 1) % 3]]);
      best = std::max(best, glm::length(b - a));
    }
  }
  return best;
}

glm::dmat4 placement(glm::dvec3 origin, double heading = 0.0) {
  glm::dmat4 x(1.0);
  x[0] = glm::dvec4(std::cos(heading), std::sin(heading), 0.0, 0.0);
  x[1] = glm::dvec4(-std::sin(heading), std::cos(heading), 0.0, 0.0);
  x[3] = glm::dvec4(origin, 1.0);
  return x;
}

// ------------------------------------------------------------------------------------------------

class Builder {
 public:
  explicit Builder(const TerrainSpec& spec) : spec_(spec), rng_(spec.seed) {}

  SceneDescription build() {
    for (std::uint16_t k = 0; k < mat::kCount; ++k) {
      const mat::Def& d = mat::kDefs[k];
      out_.materials.push_back({d.name, glm::vec3(d.r, d.g, d.b)});
    }
    out_.anchor = {common::radians(Layout::kAnchorLatitude_deg),
                   common::radians(Layout::kAnchorLongitude_deg), Layout::kAnchorHeight_m};
    make_relief();
    make_river();
    make_roads();
    find_bridge();
    make_lakes();
    make_power_line();
    make_buildings();
    central_parcels_.build(
        rng_, {-kHalfEast_m, -kHalfNorth_m}, {kHalfEast_m, kHalfNorth_m}, 320.0,
        {{mat::kCrops, 0.40}, {mat::kGrass, 0.28}, {mat::kForest, 0.22}, {mat::kSoilDry, 0.10}});
    surround_parcels_.build(rng_, glm::dvec2(-kHalfSurround_m), glm::dvec2(kHalfSurround_m), 1400.0,
                            {{mat::kCrops, 0.50}, {mat::kGrass, 0.33}, {mat::kSoilDry, 0.17}});
    make_heights();
    emit_tiles();
    emit_roads_and_bridge();
    emit_river_and_lake();
    emit_buildings();
    emit_power_line();
    emit_trees();
    emit_surround();
    return std::move(out_);
  }

 private:
  // --- height field ---------------------------------------------------------------------------

  struct Wave {
    glm::dvec2 k{0.0};
    double amp_m = 0.0, phase = 0.0;
  };

  void make_relief() {
    // Wavelengths and relative weights: broad swells down to 400 m ripples (a "relatively
    // undulating" terrain, slopes under about 5 % at relief_m = 18 m).
    constexpr std::array<double, 6> kWavelength_m{6000, 3500, 2000, 1200, 700, 400};
    constexpr std::array<double, 6> kWeight{8.0, 5.0, 3.0, 1.5, 0.8, 0.4};
    const double total = std::accumulate(kWeight.begin(), kWeight.end(), 0.0);
    for (std::size_t i = 0; i < waves_.size(); ++i) {
      const double dir = rng_.uniform(0.0, 2.0 * kPi);
      const double k = 2.0 * kPi / kWavelength_m[i];
      waves_[i] = {k * glm::dvec2(std::cos(dir), std::sin(dir)),
                   spec_.relief_m * kWeight[i] / total, rng_.uniform(0.0, 2.0 * kPi)};
    }
  }

  [[nodiscard]] double relief(glm::dvec2 p) const {
    double h = 0.0;
    for (const Wave& w : waves_)
      h += w.amp_m * std::sin(glm::dot(w.k, p) + w.phase);
    return h;
  }

  // Undulation and river valley (no river bed, lakes or canopy).
  [[nodiscard]] double base_ground(glm::dvec2 p) const {
    const double d = river_.valley_distance(p) / kValleyWidth_m;
    return relief(p) - kValleyDepth_m * std::exp(-d * d);
  }

  // Bare ground: base, river bed and banks, lake basins.
  [[nodiscard]] double ground(glm::dvec2 p) const {
    double g = base_ground(p);
    const River::Near r = river_.nearest(p, kRiverTaperMax_m);
    if (r.d_m < r.taper_m) {
      const double bed = r.level_m - kRiverDepth_m;
      g = std::min(g, bed + (g - bed) * smoothstep(kRiverBedHalf_m, r.taper_m, r.d_m));
    }
    g = lake_.shape(g, p);
    return outer_lake_.shape(g, p);
  }

  void make_river() {
    river_.x0 = rng_.uniform(-900.0, 900.0);
    river_.a1 = rng_.uniform(350.0, 500.0);
    river_.k1 = 2.0 * kPi / rng_.uniform(5000.0, 7000.0);
    river_.p1 = rng_.uniform(0.0, 2.0 * kPi);
    river_.a2 = rng_.uniform(40.0, 80.0);
    river_.k2 = 2.0 * kPi / rng_.uniform(1600.0, 2200.0);
    river_.p2 = rng_.uniform(0.0, 2.0 * kPi);
    const int n = static_cast<int>(Layout::kSurroundSide_m / kRiverStep_m) + 1;
    double level = kInf;
    for (int k = 0; k < n; ++k) {
      const double y = -kHalfSurround_m + kRiverStep_m * k;
      const glm::dvec2 c(river_.x_at(y), y);
      const double g = base_ground(c);
      level = std::min(level, g - 1.0);  // the water never flows uphill
      river_.c.push_back(c);
      river_.level_m.push_back(level);
      // Banks about 10 % steep where the river has cut into higher ground.
      river_.taper_m.push_back(std::clamp(kRiverBedHalf_m + 10.0 * (g - (level - kRiverDepth_m)),
                                          100.0, kRiverTaperMax_m));
    }
  }

  // --- roads ------------------------------------------------------------------------------------

  [[nodiscard]] std::pair<double, double> river_x_range(double y0, double y1) const {
    double lo = kInf, hi = -kInf;
    for (const glm::dvec2& c : river_.c) {
      if (c.y >= y0 && c.y <= y1) {
        lo = std::min(lo, c.x);
        hi = std::max(hi, c.x);
      }
    }
    return {lo, hi};
  }

  void make_roads() {
    // road_0: west-east across the area, over the river.
    {
      Road r{"road_0", {}, 3.5, 0.20, mat::kAsphalt};
      const double y0 = rng_.uniform(-2200.0, 2200.0), amp = rng_.uniform(40.0, 100.0);
      const double k = 2.0 * kPi / rng_.uniform(2000.0, 3000.0), ph = rng_.uniform(0.0, 2 * kPi);
      for (int i = 0; i <= static_cast<int>(Layout::kCentralEast_m / kRoadStep_m); ++i) {
        const double x = -kHalfEast_m + kRoadStep_m * i;
        r.line.p.push_back({x, y0 + amp * std::sin(k * x + ph)});
      }
      r.line.finish();
      roads_.push_back(std::move(r));
    }
    // road_1: south-north, on the side of the river with more room.
    const auto [rx_lo, rx_hi] = river_x_range(-kHalfNorth_m, kHalfNorth_m);
    const bool west = (rx_lo + kHalfEast_m) > (kHalfEast_m - rx_hi);
    {
      Road r{"road_1", {}, 3.5, 0.25, mat::kAsphalt};
      const double x1 = west ? 0.5 * (-kHalfEast_m + rx_lo) : 0.5 * (kHalfEast_m + rx_hi);
      const double amp = rng_.uniform(30.0, 80.0);
      const double k = 2.0 * kPi / rng_.uniform(1800.0, 2600.0), ph = rng_.uniform(0.0, 2 * kPi);
      for (int j = 0; j <= static_cast<int>(Layout::kCentralNorth_m / kRoadStep_m); ++j) {
        const double y = -kHalfNorth_m + kRoadStep_m * j;
        r.line.p.push_back({x1 + amp * std::sin(k * y + ph), y});
      }
      r.line.finish();
      roads_.push_back(std::move(r));
    }
    // road_2: a branch of road_1 toward the outer edge, away from road_0.
    {
      const Polyline& r1 = roads_[1].line;
      const double y_cross = road0_y_near(r1.p[r1.p.size() / 2].x);
      const double dir_y = y_cross < 0.0 ? 1.0 : -1.0;
      const double yb = std::clamp(y_cross + dir_y * rng_.uniform(900.0, 1800.0), -3000.0, 3000.0);
      glm::dvec2 start(0.0);
      double best = kInf;
      for (const glm::dvec2& q : r1.p) {
        if (std::abs(q.y - yb) < best) {
          best = std::abs(q.y - yb);
          start = q;
        }
      }
      junction_ = start;
      const glm::dvec2 end(west ? -kHalfEast_m : kHalfEast_m,
                           std::clamp(yb + dir_y * rng_.uniform(300.0, 900.0), -3400.0, 3400.0));
      const glm::dvec2 mid =
          0.5 * (start + end) + perp(glm::normalize(end - start)) * rng_.uniform(-100.0, 100.0);
      Road r{"road_2", {}, 2.75, 0.30, mat::kAsphalt};
      const double len = glm::length(end - start) + glm::length(mid - start);
      const int n = std::max(2, static_cast<int>(len / kRoadStep_m));
      for (int i = 0; i <= n; ++i) {  // quadratic Bezier
        const double t = static_cast<double>(i) / n;
        r.line.p.push_back((1 - t) * (1 - t) * start + 2 * t * (1 - t) * mid + t * t * end);
      }
      r.line.finish();
      roads_.push_back(std::move(r));
    }
    // track_0: a gravel farm track from road_0 to the north or south edge, clear of the river
    // and of road_1 (skipped when no attempt finds room).
    road_index_.build(roads_);
    for (int attempt = 0; attempt < 60; ++attempt) {
      const double xt = rng_.uniform(-2300.0, 2300.0), dir = rng_.sign();
      const double amp = rng_.uniform(10.0, 40.0), k = 2.0 * kPi / rng_.uniform(600.0, 1200.0);
      const double ph = rng_.uniform(0.0, 2 * kPi);
      const double y_start = road0_y_near(xt), y_end = dir * kHalfNorth_m;
      if (std::abs(y_end - y_start) < 800.0)
        continue;
      Road r{"track_0", {}, 2.0, 0.15, mat::kGravel};
      const int n = static_cast<int>(std::abs(y_end - y_start) / kRoadStep_m);
      bool ok = true;
      for (int i = 0; i <= n && ok; ++i) {
        const double y = y_start + (y_end - y_start) * i / n;
        const glm::dvec2 q(xt + amp * std::sin(k * (y - y_start) + ph) - amp * std::sin(ph), y);
        ok = river_.nearest(q, 150.0).d_m > 150.0 && std::abs(q.x) < kHalfEast_m - 50.0 &&
             road_clearance_of(1, q) > 150.0 && road_clearance_of(2, q) > 60.0;
        r.line.p.push_back(q);
      }
      if (!ok)
        continue;
      r.line.finish();
      roads_.push_back(std::move(r));
      break;
    }
    road_index_.build(roads_);
  }

  [[nodiscard]] double road0_y_near(double x) const {
    const Polyline& l = roads_[0].line;
    const auto i = static_cast<std::size_t>(std::clamp(std::round((x + kHalfEast_m) / kRoadStep_m),
                                                       0.0, static_cast<double>(l.p.size() - 1)));
    return l.p[i].y;
  }

  [[nodiscard]] double road_clearance_of(std::size_t road, glm::dvec2 q) const {
    double best = kInf;
    const Road& r = roads_[road];
    for (std::size_t i = 1; i < r.line.p.size(); ++i)
      best = std::min(best, segment_distance(q, r.line.p[i - 1], r.line.p[i]).d_m);
    return best - r.half_width_m;
  }

  // --- lakes ------------------------------------------------------------------------------------

  // A lake's water level: half a metre under the lowest ground on its shore (64 points).
  [[nodiscard]] double water_level_m(const Lake& l) const {
    double level = kInf;
    for (int k = 0; k < 64; ++k)
      level = std::min(level, base_ground(l.point(2.0 * kPi * k / 64)));
    return level - 0.5;
  }

  void make_lakes() {
    // Central lake: clear of roads, the river's banks and the edges.
    for (int attempt = 0;; ++attempt) {
      const double shrink = attempt < 300 ? 1.0 : 0.6;
      Lake l;
      l.c = {rng_.uniform(-kHalfEast_m + 500.0, kHalfEast_m - 500.0),
             rng_.uniform(-kHalfNorth_m + 500.0, kHalfNorth_m - 500.0)};
      l.a_m = shrink * rng_.uniform(300.0, 420.0);
      l.b_m = shrink * rng_.uniform(180.0, 260.0);
      l.rot = rng_.uniform(0.0, kPi);
      bool ok = true;
      for (int k = 0; k < 32 && ok; ++k) {
        const glm::dvec2 q = l.point(2.0 * kPi * k / 32);
        ok = in_central(q, 150.0) && road_index_.clearance(q, 100.0) > 80.0 &&
             river_.nearest(q, 700.0).d_m > 600.0;
      }
      if (ok || attempt > 600) {
        l.level_m = water_level_m(l);
        lake_ = l;
        break;
      }
    }
    // Surround lake: clear of the central area, the outer edge and the river.
    for (int attempt = 0;; ++attempt) {
      Lake l;
      l.c = {rng_.uniform(-9000.0, 9000.0), rng_.uniform(-9000.0, 9000.0)};
      l.a_m = rng_.uniform(800.0, 1200.0);
      l.b_m = rng_.uniform(450.0, 700.0);
      l.rot = rng_.uniform(0.0, kPi);
      l.bank_in_m = -300.0;
      l.bank_out_m = 60.0;
      const double outside_x = std::max(0.0, std::abs(l.c.x) - kHalfEast_m);
      const double outside_y = std::max(0.0, std::abs(l.c.y) - kHalfNorth_m);
      const bool ok =
          std::hypot(outside_x, outside_y) > l.a_m + 500.0 &&
          std::max(std::abs(l.c.x), std::abs(l.c.y)) + l.a_m < kHalfSurround_m - 400.0 &&
          river_.valley_distance(l.c) > l.a_m + 700.0;
      if (ok || attempt > 2000) {
        l.level_m = water_level_m(l);
        outer_lake_ = l;
        break;
      }
    }
  }

  // --- power line -------------------------------------------------------------------------------

  [[nodiscard]] double power_line_distance(glm::dvec2 p) const {
    if (pylons_.empty())
      return kInf;
    return segment_distance(p, line_a_, line_b_).d_m;
  }

  [[nodiscard]] bool pylon_site_ok(glm::dvec2 q) const {
    // On the valley sides if need be, but out of the river bed.
    return in_central(q, 30.0) && river_.nearest(q, 100.0).d_m > kRiverBedHalf_m + 30.0 &&
           road_index_.clearance(q, 40.0) > 20.0 && lake_.sdist(q) > 40.0;
  }

  // Pylons every ~kPylonSpacing_m from a to b, each shifted up to 140 m along the line to a good
  // site; empty when a site cannot be found.
  [[nodiscard]] std::vector<glm::dvec2> pylon_sites(glm::dvec2 a, glm::dvec2 b) const {
    const double len = glm::length(b - a);
    const int spans = std::max(1, static_cast<int>(std::lround(len / kPylonSpacing_m)));
    const glm::dvec2 dir = (b - a) / len;
    std::vector<glm::dvec2> sites;
    for (int k = 0; k <= spans; ++k) {
      const double s0 = len * k / spans;
      bool found = false;
      for (int shift = 0; shift <= 14 && !found; ++shift) {  // 0, +20, -20, +40, ... m
        const double s =
            std::clamp(s0 + 20.0 * ((shift + 1) / 2) * (shift % 2 ? 1.0 : -1.0), 0.0, len);
        const glm::dvec2 q = a + s * dir;
        found = pylon_site_ok(q) && (sites.empty() || glm::length(q - sites.back()) > 150.0);
        if (found)
          sites.push_back(q);
      }
      if (!found)
        return {};
    }
    return sites;
  }

  void make_power_line() {
    // A straight line across the area, clear of the lake and of the bridge, with a pylon site
    // at every span.
    for (int attempt = 0; attempt < 400; ++attempt) {
      const double theta = rng_.uniform(0.0, kPi);
      const glm::dvec2 m(rng_.uniform(-1500.0, 1500.0), rng_.uniform(-2500.0, 2500.0));
      const glm::dvec2 d(std::cos(theta), std::sin(theta));
      // Clip the line through m along d to the central area less 100 m.
      double t0 = -kInf, t1 = kInf;
      for (int ax = 0; ax < 2; ++ax) {
        const double half = (ax == 0 ? kHalfEast_m : kHalfNorth_m) - 100.0;
        const double mc = ax == 0 ? m.x : m.y, dc = ax == 0 ? d.x : d.y;
        if (std::abs(dc) < 1e-9)
          continue;
        const double ta = (-half - mc) / dc, tb = (half - mc) / dc;
        t0 = std::max(t0, std::min(ta, tb));
        t1 = std::min(t1, std::max(ta, tb));
      }
      const glm::dvec2 a = m + t0 * d, b = m + t1 * d;
      if (t1 - t0 < 3000.0 || segment_distance(lake_.c, a, b).d_m < lake_.a_m + 150.0)
        continue;
      bool clear = true;
      for (std::size_t i = bridge_a_; i <= bridge_b_ && clear; ++i)
        clear = segment_distance(roads_[0].line.p[i], a, b).d_m > 100.0;
      if (!clear)
        continue;
      std::vector<glm::dvec2> sites = pylon_sites(a, b);
      if (sites.empty())
        continue;
      line_a_ = a;
      line_b_ = b;
      line_heading_ = std::atan2(d.y, d.x);
      pylons_ = std::move(sites);
      break;
    }
  }

  // --- buildings --------------------------------------------------------------------------------

  [[nodiscard]] double building_clearance(glm::dvec2 p) const {
    double best = kInf;
    for (const Building& b : buildings_) {
      const glm::dvec2 d = p - b.c;
      if (std::abs(d.x) - b.radius() > best || std::abs(d.y) - b.radius() > best)
        continue;
      best = std::min(best, glm::length(d) - b.radius());
    }
    return best;
  }

  [[nodiscard]] bool building_site_ok(const Building& b) const {
    const double r = b.radius();
    if (!in_central(b.c, r + 20.0) || road_index_.clearance(b.c, r + 40.0) < r + 3.0 ||
        lake_.sdist(b.c) < r + 25.0 || power_line_distance(b.c) < r + 30.0)
      return false;
    const River::Near rv = river_.nearest(b.c, kRiverTaperMax_m + r + 10.0);
    if (rv.d_m < rv.taper_m + r + 10.0)
      return false;
    for (const Building& o : buildings_) {
      if (glm::length(o.c - b.c) < r + o.radius() + 3.0)
        return false;
    }
    return true;
  }

  Building random_building(bool shed) {
    Building b;
    b.shed = shed;
    if (shed) {
      b.length_m = rng_.uniform(18.0, 32.0);
      b.width_m = rng_.uniform(10.0, 16.0);
      b.wall_m = rng_.uniform(5.0, 8.0);
      b.roof_m = rng_.uniform(1.5, 2.5);
    } else {
      b.length_m = rng_.uniform(9.0, 18.0);
      b.width_m = rng_.uniform(7.0, 11.0);
      b.wall_m = rng_.uniform(3.0, 6.5);
      b.roof_m = rng_.uniform(2.0, 3.5);
    }
    return b;
  }

  // Buildings facing road `road` around arc length s_m (+- window_m), both sides.
  void hamlet(std::size_t road, double s_m, double window_m, int count) {
    const Road& r = roads_[road];
    for (int n = 0; n < count; ++n) {
      for (int attempt = 0; attempt < 30; ++attempt) {
        Building b = random_building(rng_.uniform() < 0.2);
        glm::dvec2 dir;
        const glm::dvec2 q = r.line.at(s_m + rng_.uniform(-window_m, window_m), dir);
        const double side = rng_.sign();
        b.c = q +
              perp(dir) * side * (r.half_width_m + 4.0 + 0.5 * b.width_m + rng_.uniform(0.0, 40.0));
        b.heading = std::atan2(dir.y, dir.x) + rng_.uniform(-0.08, 0.08);
        if (building_site_ok(b)) {
          buildings_.push_back(b);
          break;
        }
      }
    }
  }

  void make_buildings() {
    // Hamlet at the road_1 / road_2 junction, one on road_0 away from the bridge, one more on
    // road_1; then farms (2-4 buildings, mostly sheds) a little off the roads.
    const Polyline& r1 = roads_[1].line;
    double s_junction = 0.0;
    for (std::size_t i = 0; i < r1.p.size(); ++i) {
      if (r1.p[i] == junction_)
        s_junction = r1.s[i];
    }
    hamlet(1, s_junction, 220.0, rng_.integer(14, 20));
    hamlet(2, 120.0, 120.0, rng_.integer(4, 7));
    const double x_river = river_.x_at(road0_y_near(0.0));
    double s0 = 0.0;
    for (int attempt = 0; attempt < 50; ++attempt) {
      s0 = rng_.uniform(300.0, roads_[0].line.length() - 300.0);
      glm::dvec2 dir;
      if (std::abs(roads_[0].line.at(s0, dir).x - x_river) > 700.0)
        break;
    }
    hamlet(0, s0, 200.0, rng_.integer(10, 16));
    const double s1 = std::fmod(s_junction + rng_.uniform(1500.0, 5500.0), r1.length());
    hamlet(1, s1, 180.0, rng_.integer(8, 14));
    const int farms = rng_.integer(5, 8);
    for (int f = 0; f < farms; ++f) {
      const std::size_t road =
          static_cast<std::size_t>(rng_.integer(0, static_cast<int>(roads_.size()) - 1));
      glm::dvec2 dir;
      const glm::dvec2 q = roads_[road].line.at(rng_.uniform(0.0, roads_[road].line.length()), dir);
      const glm::dvec2 centre = q + perp(dir) * rng_.sign() * rng_.uniform(60.0, 200.0);
      const double heading = rng_.uniform(0.0, kPi);
      const int count = rng_.integer(2, 4);
      for (int n = 0; n < count; ++n) {
        for (int attempt = 0; attempt < 20; ++attempt) {
          Building b = random_building(n > 0 || rng_.uniform() < 0.3);
          b.c = centre + glm::dvec2(rng_.uniform(-50.0, 50.0), rng_.uniform(-50.0, 50.0));
          b.heading = heading + (rng_.uniform() < 0.5 ? 0.0 : 0.5 * kPi);
          if (building_site_ok(b)) {
            buildings_.push_back(b);
            break;
          }
        }
      }
    }
  }

  // --- height field on the level-0 grid --------------------------------------------------------

  // Forest canopy: forest parcels, cleared along roads, the river banks, the lake shore, the
  // power line and around buildings; none in the surround.
  [[nodiscard]] bool canopy(glm::dvec2 p) const {
    if (!in_central(p) || central_parcels_.at(p) != mat::kForest)
      return false;
    if (road_index_.clearance(p, 40.0) < 30.0 || lake_.sdist(p) < 60.0 ||
        power_line_distance(p) < 30.0 || building_clearance(p) < 45.0)
      return false;
    const River::Near r = river_.nearest(p, kRiverTaperMax_m + 20.0);
    return !(r.d_m < r.taper_m + 20.0);
  }

  [[nodiscard]] std::uint16_t central_material(glm::dvec2 p) const {
    if (lake_.sdist(p) < 0.0)
      return mat::kSoilWet;  // lake bed, under the water sheet
    const River::Near r = river_.nearest(p, 70.0);
    if (r.d_m < kRiverWetHalf_m)
      return mat::kSoilWet;  // river bed under the water strip, and a strip of mud
    if (r.d_m < 70.0)
      return mat::kGrass;  // banks
    if (building_clearance(p) < 15.0)
      return mat::kUrban;  // yards
    if (canopy(p))
      return mat::kForest;
    const std::uint16_t c = central_parcels_.at(p);
    return c == mat::kForest ? mat::kGrass : c;  // clearings
  }

  [[nodiscard]] std::uint16_t surround_material(glm::dvec2 p) const {
    if (outer_lake_.sdist(p) < 0.0)
      return mat::kSoilWet;
    if (river_.valley_distance(p) < 150.0)
      return mat::kGrass;  // river meadows
    return surround_parcels_.at(p);
  }

  [[nodiscard]] double& h(int i, int j) {
    return heights_[static_cast<std::size_t>(j * (kCellsX + 1) + i)];
  }
  [[nodiscard]] double h(int i, int j) const {
    return heights_[static_cast<std::size_t>(j * (kCellsX + 1) + i)];
  }

  void make_heights() {
    heights_.assign(static_cast<std::size_t>((kCellsX + 1) * (kCellsY + 1)), 0.0);
    for (int j = 0; j <= kCellsY; ++j) {
      for (int i = 0; i <= kCellsX; ++i) {
        const glm::dvec2 p(node_x(i), node_y(j));
        h(i, j) = ground(p) + (canopy(p) ? Layout::kCanopy_m : 0.0);
      }
    }
  }

  // Height of the level-0 central surface at p (clamped to the area), as its triangles
  // interpolate it (diagonal from the south-west to the north-east node of each cell).
  [[nodiscard]] double central_height(glm::dvec2 p) const {
    const double fx = (p.x + kHalfEast_m) / Layout::kCentralEast_m * kCellsX;
    const double fy = (p.y + kHalfNorth_m) / Layout::kCentralNorth_m * kCellsY;
    const int i = std::clamp(static_cast<int>(std::floor(fx)), 0, kCellsX - 1);
    const int j = std::clamp(static_cast<int>(std::floor(fy)), 0, kCellsY - 1);
    const double u = std::clamp(fx - i, 0.0, 1.0), v = std::clamp(fy - j, 0.0, 1.0);
    const double h00 = h(i, j), h10 = h(i + 1, j), h01 = h(i, j + 1), h11 = h(i + 1, j + 1);
    if (u >= v)
      return h00 + u * (h10 - h00) + v * (h11 - h10);
    return h00 + v * (h01 - h00) + u * (h11 - h01);
  }

  // --- objects ----------------------------------------------------------------------------------

  void add_object(std::string name, Mesh mesh, const glm::dmat4& world_from_body, const char* area,
                  std::int32_t lod_group = -1, std::uint8_t lod_level = 0) {
    ObjectDesc o;
    o.name = std::move(name);
    o.lod_facet_m = longest_edge_m(mesh);
    o.mesh = std::move(mesh);
    o.world_from_body = world_from_body;
    o.area = area;
    o.lod_group = lod_group;
    o.lod_level = lod_level;
    if (std::string_view(area) == "central" && (lod_group < 0 || lod_level == 0))
      central_full_detail_ += o.mesh.triangles.size();
    out_.objects.push_back(std::move(o));
  }

  void emit_tiles() {
    for (int row = 0; row < Layout::kTileRows; ++row) {
      for (int col = 0; col < Layout::kTileColumns; ++col) {
        for (int level = 0; level < Layout::kLodLevels; ++level) {
          const int step = 1 << level, n = Layout::kTileCells / step;
          const int i0 = col * Layout::kTileCells, j0 = row * Layout::kTileCells;
          Mesh m;
          m.positions_m.reserve(static_cast<std::size_t>((n + 1) * (n + 1)));
          for (int jj = 0; jj <= n; ++jj) {
            for (int ii = 0; ii <= n; ++ii) {
              const int i = i0 + ii * step, j = j0 + jj * step;
              add_vertex(m, {node_x(i), node_y(j), h(i, j)});
            }
          }
          for (int jj = 0; jj < n; ++jj) {
            for (int ii = 0; ii < n; ++ii) {
              const auto v00 = static_cast<std::uint32_t>(jj * (n + 1) + ii);
              const std::uint32_t v10 = v00 + 1, v01 = v00 + static_cast<std::uint32_t>(n + 1),
                                  v11 = v01 + 1;
              for (const glm::uvec3 t : {glm::uvec3(v00, v10, v11), glm::uvec3(v00, v11, v01)}) {
                const glm::dvec2 c =
                    (glm::dvec2(m.positions_m[t.x]) + glm::dvec2(m.positions_m[t.y]) +
                     glm::dvec2(m.positions_m[t.z])) /
                    3.0;
                add_triangle(m, t.x, t.y, t.z, central_material(c));
              }
            }
          }
          sort_by_material(m);
          char name[48];
          std::snprintf(name, sizeof name, "terrain_r%02d_c%02d_lod%d", row, col, level);
          add_object(name, std::move(m), glm::dmat4(1.0), "central",
                     row * Layout::kTileColumns + col, static_cast<std::uint8_t>(level));
        }
      }
    }
  }

  // Bridge span on road_0: the samples within the river's banks (plus 10 m).
  void find_bridge() {
    const Road& r0 = roads_[0];
    std::size_t ic = 0;
    for (std::size_t i = 0; i < r0.line.p.size(); ++i) {
      const River::Near q = river_.nearest(r0.line.p[i], 600.0);
      if (q.d_m < bridge_cross_.d_m) {
        bridge_cross_ = q;
        ic = i;
      }
    }
    const double reach = bridge_cross_.taper_m + 10.0;
    bridge_a_ = bridge_b_ = ic;
    while (bridge_a_ > 0 && river_.nearest(r0.line.p[bridge_a_], reach).d_m < reach)
      --bridge_a_;
    while (bridge_b_ + 1 < r0.line.p.size() &&
           river_.nearest(r0.line.p[bridge_b_], reach).d_m < reach)
      ++bridge_b_;
  }

  void emit_roads_and_bridge() {
    const Road& r0 = roads_[0];
    const std::size_t ia = bridge_a_, ib = bridge_b_;
    const River::Near cross = bridge_cross_;
    const double deck_floor = cross.level_m + kDeckClearance_m + kDeckThickness_m;
    const double za = std::max(central_height(r0.line.p[ia]) + r0.offset_m, deck_floor);
    const double zb = std::max(central_height(r0.line.p[ib]) + r0.offset_m, deck_floor);

    for (std::size_t k = 0; k < roads_.size(); ++k) {
      const Road& r = roads_[k];
      Mesh m;
      const glm::dvec2 origin = r.line.p[r.line.p.size() / 2];
      const double z0 = std::round(central_height(origin));
      const glm::dvec3 o(origin, z0);
      struct Section {
        glm::dvec3 left, centre, right;
        double raise_m;
      };
      std::vector<Section> sec;
      for (std::size_t i = 0; i < r.line.p.size(); ++i) {
        const glm::dvec2 n = perp(r.line.direction(i)) * r.half_width_m;
        const glm::dvec2 q = r.line.p[i];
        double ramp = -kInf;
        if (k == 0 && i <= ia)
          ramp = za - kRampSlope * (r.line.s[ia] - r.line.s[i]);
        if (k == 0 && i >= ib)
          ramp = zb - kRampSlope * (r.line.s[i] - r.line.s[ib]);
        Section s{};
        double raise = 0.0;
        auto at = [&](glm::dvec2 x) {
          const double drape = central_height(x) + r.offset_m;
          raise = std::max(raise, ramp - drape);
          return glm::dvec3(x, std::max(drape, ramp)) - o;
        };
        s.left = at(q + n);
        s.centre = at(q);
        s.right = at(q - n);
        s.raise_m = raise;
        sec.push_back(s);
      }
      for (std::size_t i = 0; i + 1 < sec.size(); ++i) {
        if (k == 0 && i >= ia && i < ib)
          continue;  // the bridge deck
        const Section &a = sec[i], &b = sec[i + 1];
        const glm::dvec3 up(0, 0, 1);
        add_quad_facing(m, a.right, b.right, b.centre, a.centre, up, r.material);
        add_quad_facing(m, a.centre, b.centre, b.left, a.left, up, r.material);
        if (std::max(a.raise_m, b.raise_m) > 0.05) {  // embankment walls down into the ground
          const glm::dvec3 fwd = b.centre - a.centre;
          const glm::dvec3 left_dir = glm::dvec3(perp(glm::dvec2(fwd)), 0.0);
          auto foot = [&](glm::dvec3 top) {
            return glm::dvec3(top.x, top.y,
                              central_height(glm::dvec2(top) + glm::dvec2(o)) - 0.3 - z0);
          };
          add_quad_facing(m, a.left, b.left, foot(b.left), foot(a.left), left_dir, mat::kGravel);
          add_quad_facing(m, a.right, b.right, foot(b.right), foot(a.right), -left_dir,
                          mat::kGravel);
        }
      }
      add_object(r.name, std::move(m), placement(o), "central");
    }

    // Bridge: deck following road_0 from sample ia to ib (straight slope between its ends),
    // railings, piers down into the river bed.
    const glm::dvec3 o(r0.line.p[(ia + ib) / 2], std::round(0.5 * (za + zb)));
    std::vector<glm::dvec2> axis;
    std::vector<double> top;
    for (std::size_t i = ia; i <= ib; ++i) {
      axis.push_back(r0.line.p[i] - glm::dvec2(o));
      const double t = (r0.line.s[i] - r0.line.s[ia]) / (r0.line.s[ib] - r0.line.s[ia]);
      top.push_back(za + t * (zb - za) - o.z);
    }
    Mesh m;
    const double half_w = r0.half_width_m + 1.0;
    add_swept_box(m, axis, top, 0.0, half_w, kDeckThickness_m, mat::kConcrete);
    std::vector<double> rail_top(top);
    for (double& z : rail_top)
      z += 1.0;
    for (double side : {-1.0, 1.0})
      add_swept_box(m, axis, rail_top, side * (half_w - 0.1), 0.1, 1.0, mat::kMetal);
    const double span = r0.line.s[ib] - r0.line.s[ia];
    const int piers = std::max(1, static_cast<int>(span / 70.0));
    for (int k = 1; k <= piers; ++k) {
      const auto i = static_cast<std::size_t>(
          std::lround(static_cast<double>(k) / (piers + 1) * static_cast<double>(ib - ia)));
      const glm::dvec2 c = axis[i];
      const glm::dvec2 f = r0.line.direction(ia + i), n = perp(f);
      const double bottom = cross.level_m - kRiverDepth_m - 1.5 - o.z;
      const glm::dvec2 df = f * 1.0, dn = n * (half_w - 1.0);
      const std::array<glm::dvec2, 4> q{c - df - dn, c + df - dn, c + df + dn, c - df + dn};
      std::array<glm::dvec3, 4> lo, hi;
      for (std::size_t v = 0; v < 4; ++v) {
        lo[v] = glm::dvec3(q[v], bottom);
        hi[v] = glm::dvec3(q[v], top[i] - kDeckThickness_m);
      }
      add_hexahedron(m, lo, hi, mat::kConcrete);
    }
    add_object("bridge", std::move(m), placement(o), "central");
  }

  void emit_river_and_lake() {
    // River: flat across at its level, the central reach at full sampling.
    {
      Mesh m;
      const glm::dvec3 o(river_.x_at(0.0), 0.0, std::round(river_.level_m[river_.c.size() / 2]));
      const auto k0 = static_cast<std::size_t>((kHalfSurround_m - kHalfNorth_m) / kRiverStep_m);
      const auto k1 = static_cast<std::size_t>((kHalfSurround_m + kHalfNorth_m) / kRiverStep_m);
      for (std::size_t k = k0; k < k1; ++k) {
        auto edge = [&](std::size_t i, double side) {
          const double s = river_.slope(river_.c[i].y);
          const glm::dvec2 n = glm::dvec2(1.0, -s) / std::sqrt(1.0 + s * s);  // right of north
          return glm::dvec3(river_.c[i] + side * 0.5 * Layout::kRiverWidth_m * n,
                            river_.level_m[i]) -
                 o;
        };
        add_quad_facing(m, edge(k, -1), edge(k, 1), edge(k + 1, 1), edge(k + 1, -1), {0, 0, 1},
                        mat::kWater);
      }
      add_object("river", std::move(m), placement(o), "central");
    }
    emit_lake_sheet(lake_, 96, "lake", "central");
  }

  // Flat water sheet over a lake basin: a fan of `sides` triangles.
  void emit_lake_sheet(const Lake& l, int sides, const char* name, const char* area) {
    Mesh m;
    const glm::dvec3 o(l.c, l.level_m);
    const std::uint32_t centre = add_vertex(m, {0, 0, 0});
    for (int k = 0; k < sides; ++k)
      add_vertex(m, glm::dvec3(l.point(2.0 * kPi * k / sides) - l.c, 0.0));
    for (int k = 0; k < sides; ++k) {
      // point() runs counter-clockwise in the ellipse frame (a rotation keeps that).
      add_triangle(m, centre, centre + 1 + static_cast<std::uint32_t>(k),
                   centre + 1 + static_cast<std::uint32_t>((k + 1) % sides), mat::kWater);
    }
    add_object(name, std::move(m), placement(o), area);
  }

  void emit_buildings() {
    int index = 0;
    for (const Building& b : buildings_) {
      const double hl = 0.5 * b.length_m, hw = 0.5 * b.width_m;
      const glm::dvec2 fx(std::cos(b.heading), std::sin(b.heading)), fy = perp(fx);
      double base = kInf;
      for (double sx : {-1.0, 1.0}) {
        for (double sy : {-1.0, 1.0})
          base = std::min(base, central_height(b.c + sx * hl * fx + sy * hw * fy));
      }
      base -= 0.3;  // foundations
      const double wall = central_height(b.c) - base + b.wall_m;
      const double ridge = wall + b.roof_m;
      Mesh m;
      const std::uint16_t roof = b.shed ? mat::kMetal : mat::kConcrete;  // tiles: as concrete
      const glm::dvec3 c0(-hl, -hw, 0), c1(hl, -hw, 0), c2(hl, hw, 0), c3(-hl, hw, 0);
      const glm::dvec3 up(0, 0, wall);
      const std::array<glm::dvec3, 4> corner{c0, c1, c2, c3};
      for (std::size_t k = 0; k < 4; ++k) {
        const glm::dvec3 p = corner[k], q = corner[(k + 1) % 4];
        add_quad_facing(m, p, q, q + up, p + up, 0.5 * (p + q), mat::kConcrete);
      }
      const glm::dvec3 r0(-hl, 0, ridge), r1(hl, 0, ridge);
      add_tri_facing(m, c0 + up, c3 + up, r0, {-1, 0, 0}, mat::kConcrete);  // gables
      add_tri_facing(m, c1 + up, c2 + up, r1, {1, 0, 0}, mat::kConcrete);
      add_quad_facing(m, c0 + up, c1 + up, r1, r0, {0, -1, 1}, roof);
      add_quad_facing(m, c3 + up, c2 + up, r1, r0, {0, 1, 1}, roof);
      add_object("building_" + std::to_string(index++), std::move(m),
                 placement(glm::dvec3(b.c, base), b.heading), "central");
    }
  }

  void emit_power_line() {
    // Pylon: open tapered frustum (6 m square at the foot, 1.5 m at the top, 30 m) and a cross
    // arm box; x along the line.
    std::vector<glm::dmat4> pylon_world;
    for (std::size_t k = 0; k < pylons_.size(); ++k) {
      const glm::dvec2 q = pylons_[k];
      const glm::dvec2 fx(std::cos(line_heading_), std::sin(line_heading_)), fy = perp(fx);
      double base = kInf;
      for (double sx : {-1.0, 1.0}) {
        for (double sy : {-1.0, 1.0})
          base = std::min(base, central_height(q + 3.0 * sx * fx + 3.0 * sy * fy));
      }
      base -= 0.2;
      Mesh m;
      const std::array<glm::dvec2, 4> sq{{{-1, -1}, {1, -1}, {1, 1}, {-1, 1}}};
      for (std::size_t s = 0; s < 4; ++s) {
        const glm::dvec2 p = sq[s], n = sq[(s + 1) % 4];
        add_quad_facing(m, glm::dvec3(3.0 * p, 0), glm::dvec3(3.0 * n, 0),
                        glm::dvec3(0.75 * n, kPylonHeight_m), glm::dvec3(0.75 * p, kPylonHeight_m),
                        glm::dvec3(p + n, 0.0), mat::kMetal);
      }
      std::array<glm::dvec3, 4> lo, hi;
      const std::array<glm::dvec2, 4> arm{{{-0.5, -kArmHalfSpan_m},
                                           {0.5, -kArmHalfSpan_m},
                                           {0.5, kArmHalfSpan_m},
                                           {-0.5, kArmHalfSpan_m}}};
      for (std::size_t v = 0; v < 4; ++v) {
        lo[v] = glm::dvec3(arm[v], kArmHeight_m);
        hi[v] = glm::dvec3(arm[v], kArmHeight_m + 1.0);
      }
      add_hexahedron(m, lo, hi, mat::kMetal);
      const glm::dmat4 w = placement(glm::dvec3(q, base), line_heading_);
      pylon_world.push_back(w);
      add_object("pylon_" + std::to_string(k), std::move(m), w, "central");
    }
    // Wires: parabolic sag (a catenary to within a few cm at this sag-to-span ratio), 3-sided
    // tubes; conductors 0 and 1 under the arm ends, 2 (earth wire) on the top.
    const std::array<glm::dvec3, 3> attach{glm::dvec3(0, -kConductorOffset_m, kArmHeight_m),
                                           glm::dvec3(0, kConductorOffset_m, kArmHeight_m),
                                           glm::dvec3(0, 0, kPylonHeight_m)};
    for (std::size_t k = 0; k + 1 < pylon_world.size(); ++k) {
      for (std::size_t c = 0; c < attach.size(); ++c) {
        const glm::dvec3 a(pylon_world[k] * glm::dvec4(attach[c], 1.0));
        const glm::dvec3 b(pylon_world[k + 1] * glm::dvec4(attach[c], 1.0));
        const double span = glm::length(glm::dvec2(b - a));
        const double sag = kWireSag_m * (span / kPylonSpacing_m) * (span / kPylonSpacing_m);
        auto at = [&](double t) { return (b - a) * t - glm::dvec3(0, 0, 4.0 * sag * t * (1 - t)); };
        Mesh m;
        std::vector<std::array<glm::dvec3, 3>> rings;
        for (int i = 0; i <= kWireSegments; ++i) {
          const double t = static_cast<double>(i) / kWireSegments;
          const glm::dvec3 tangent =
              glm::normalize(at(std::min(1.0, t + 1e-3)) - at(std::max(0.0, t - 1e-3)));
          const glm::dvec3 n1 = glm::normalize(glm::cross(tangent, glm::dvec3(0, 0, 1)));
          const glm::dvec3 n2 = glm::cross(tangent, n1);
          std::array<glm::dvec3, 3> ring;
          for (std::size_t s = 0; s < 3; ++s) {
            const double phi = 2.0 * kPi * static_cast<double>(s) / 3.0;
            ring[s] = at(t) + kWireRadius_m * (std::cos(phi) * n1 + std::sin(phi) * n2);
          }
          rings.push_back(ring);
        }
        for (std::size_t i = 0; i + 1 < rings.size(); ++i) {
          const glm::dvec3 mid = 0.5 * (at(static_cast<double>(i) / kWireSegments) +
                                        at(static_cast<double>(i + 1) / kWireSegments));
          for (std::size_t s = 0; s < 3; ++s) {
            const std::size_t n = (s + 1) % 3;
            const glm::dvec3 face =
                0.25 * (rings[i][s] + rings[i][n] + rings[i + 1][s] + rings[i + 1][n]);
            add_quad_facing(m, rings[i][s], rings[i][n], rings[i + 1][n], rings[i + 1][s],
                            face - mid, mat::kMetal);
          }
        }
        add_object("wire_" + std::to_string(k) + "_" + std::to_string(c), std::move(m),
                   placement(a), "central");
      }
    }
  }

  [[nodiscard]] bool tree_site_ok(glm::dvec2 p, double crown_m) const {
    if (!in_central(p, 10.0) || lake_.sdist(p) < 15.0 || power_line_distance(p) < 20.0 ||
        road_index_.clearance(p, 20.0) < crown_m + 2.0 || building_clearance(p) < crown_m + 3.0 ||
        river_.nearest(p, 45.0).d_m < 45.0)
      return false;
    // Crowns 1 m apart at least.
    const auto [ci, cj] = tree_cell(p);
    for (int j = std::max(0, cj - 1); j <= std::min(kTreeCellsY - 1, cj + 1); ++j) {
      for (int i = std::max(0, ci - 1); i <= std::min(kTreeCellsX - 1, ci + 1); ++i) {
        for (const auto& [q, crown] : tree_cells_[static_cast<std::size_t>(j * kTreeCellsX + i)]) {
          if (glm::length(q - p) < crown + crown_m + 1.0)
            return false;
        }
      }
    }
    for (const glm::dvec2 d : {glm::dvec2(0, 0), glm::dvec2(25, 0), glm::dvec2(-25, 0),
                               glm::dvec2(0, 25), glm::dvec2(0, -25)}) {
      if (canopy(p + d))
        return false;
    }
    return true;
  }

  static constexpr double kTreeCell_m = 20.0;  // > twice the largest crown + 1 m
  static constexpr int kTreeCellsX = static_cast<int>(Layout::kCentralEast_m / kTreeCell_m);
  static constexpr int kTreeCellsY = static_cast<int>(Layout::kCentralNorth_m / kTreeCell_m);
  [[nodiscard]] static std::pair<int, int> tree_cell(glm::dvec2 p) {
    return {std::clamp(static_cast<int>((p.x + kHalfEast_m) / kTreeCell_m), 0, kTreeCellsX - 1),
            std::clamp(static_cast<int>((p.y + kHalfNorth_m) / kTreeCell_m), 0, kTreeCellsY - 1)};
  }

  void emit_tree(std::size_t index, glm::dvec2 p, double height, double crown) {
    const auto [ci, cj] = tree_cell(p);
    tree_cells_[static_cast<std::size_t>(cj * kTreeCellsX + ci)].emplace_back(p, crown);
    Mesh m;
    const double trunk = 0.3 * height, low = trunk - 0.25 * (height - trunk);
    // Trunk: 4-sided prism 0.5 m wide, from below ground into the crown.
    const std::array<glm::dvec2, 4> sq{
        {{-0.25, -0.25}, {0.25, -0.25}, {0.25, 0.25}, {-0.25, 0.25}}};
    for (std::size_t s = 0; s < 4; ++s) {
      const glm::dvec2 a = sq[s], b = sq[(s + 1) % 4];
      add_quad_facing(m, glm::dvec3(a, -0.5), glm::dvec3(b, -0.5), glm::dvec3(b, trunk),
                      glm::dvec3(a, trunk), glm::dvec3(a + b, 0.0), mat::kForest);
    }
    // Crown: 8-sided double cone, widest at the top of the trunk.
    const glm::dvec3 top(0, 0, height), bottom(0, 0, low);
    for (int s = 0; s < 8; ++s) {
      const double t0 = 2.0 * kPi * s / 8, t1 = 2.0 * kPi * (s + 1) / 8;
      const glm::dvec3 a(crown * std::cos(t0), crown * std::sin(t0), trunk);
      const glm::dvec3 b(crown * std::cos(t1), crown * std::sin(t1), trunk);
      const glm::dvec3 out(0.5 * (glm::dvec2(a) + glm::dvec2(b)), 0.0);
      add_tri_facing(m, a, b, top, out + glm::dvec3(0, 0, 0.1), mat::kForest);
      add_tri_facing(m, a, b, bottom, out - glm::dvec3(0, 0, 0.1), mat::kForest);
    }
    add_object("tree_" + std::to_string(index), std::move(m),
               placement(glm::dvec3(p, central_height(p))), "central");
  }

  void emit_trees() {
    const std::size_t used = central_full_detail_;
    const std::size_t min_total = used + kMinTrees * kTreeTriangles;
    if (spec_.central_triangles < min_total) {
      throw std::invalid_argument(
          "TerrainSpec::central_triangles: " + std::to_string(spec_.central_triangles) +
          " leaves no room for trees with this seed (at least " + std::to_string(min_total) + ")");
    }
    const std::size_t want = (spec_.central_triangles - used) / kTreeTriangles;
    tree_cells_.assign(static_cast<std::size_t>(kTreeCellsX * kTreeCellsY), {});
    std::size_t placed = 0;
    // Half in rows along the roads (12 m apart), half scattered over the fields and meadows.
    for (std::size_t attempt = 0; placed < want / 2 && attempt < 20 * want; ++attempt) {
      const Road& r =
          roads_[static_cast<std::size_t>(rng_.integer(0, static_cast<int>(roads_.size()) - 1))];
      double s = rng_.uniform(0.0, r.line.length());
      const double side = rng_.sign();
      const int count = rng_.integer(6, 16);
      for (int k = 0; k < count && placed < want / 2; ++k, s += 12.0) {
        const double height = rng_.uniform(8.0, 16.0), crown = rng_.uniform(2.0, 3.5);
        if (s > r.line.length())
          break;
        glm::dvec2 dir;
        const glm::dvec2 p = r.line.at(s, dir) + perp(dir) * side * (r.half_width_m + crown + 3.0);
        if (tree_site_ok(p, crown))
          emit_tree(placed++, p, height, crown);
      }
    }
    for (std::size_t attempt = 0; placed < want && attempt < 40 * want; ++attempt) {
      const glm::dvec2 p(rng_.uniform(-kHalfEast_m, kHalfEast_m),
                         rng_.uniform(-kHalfNorth_m, kHalfNorth_m));
      const double height = rng_.uniform(8.0, 16.0), crown = rng_.uniform(2.0, 3.5);
      if (tree_site_ok(p, crown))
        emit_tree(placed++, p, height, crown);
    }
  }

  // --- surround ---------------------------------------------------------------------------------

  void emit_surround() {
    // Node coordinates: outer cells, then the central span in kRingFine level-0 cells (the same
    // formula as the tiles), then outer cells again.
    std::vector<double> xs, ys;
    for (int a = 0; a < kSurroundOuterX; ++a)
      xs.push_back(-kHalfSurround_m + (kHalfSurround_m - kHalfEast_m) * a / kSurroundOuterX);
    for (int a = 0; a <= kSurroundInnerX; ++a)
      xs.push_back(node_x(a * kRingFine));
    for (int a = 1; a <= kSurroundOuterX; ++a)
      xs.push_back(kHalfEast_m + (kHalfSurround_m - kHalfEast_m) * a / kSurroundOuterX);
    for (int b = 0; b < kSurroundOuterY; ++b)
      ys.push_back(-kHalfSurround_m + (kHalfSurround_m - kHalfNorth_m) * b / kSurroundOuterY);
    for (int b = 0; b <= kSurroundInnerY; ++b)
      ys.push_back(node_y(b * kRingFine));
    for (int b = 1; b <= kSurroundOuterY; ++b)
      ys.push_back(kHalfNorth_m + (kHalfSurround_m - kHalfNorth_m) * b / kSurroundOuterY);
    const int nx = static_cast<int>(xs.size()), ny = static_cast<int>(ys.size());
    const int a_lo = kSurroundOuterX, a_hi = kSurroundOuterX + kSurroundInnerX;  // hole columns
    const int b_lo = kSurroundOuterY, b_hi = kSurroundOuterY + kSurroundInnerY;  // hole rows
    // A node is inside the hole (no vertex) strictly between its edges; on the edge it takes the
    // central level-0 height (bit-identical to the tile's vertex).
    auto in_hole = [&](int a, int b) { return a > a_lo && a < a_hi && b > b_lo && b < b_hi; };
    auto node_height = [&](int a, int b) {
      if (a >= a_lo && a <= a_hi && b >= b_lo && b <= b_hi)
        return h((a - a_lo) * kRingFine, (b - b_lo) * kRingFine);
      return ground({xs[static_cast<std::size_t>(a)], ys[static_cast<std::size_t>(b)]});
    };
    Mesh m;
    std::vector<std::uint32_t> id(static_cast<std::size_t>(nx * ny), 0);
    for (int b = 0; b < ny; ++b) {
      for (int a = 0; a < nx; ++a) {
        if (!in_hole(a, b)) {
          id[static_cast<std::size_t>(b * nx + a)] =
              add_vertex(m, {xs[static_cast<std::size_t>(a)], ys[static_cast<std::size_t>(b)],
                             node_height(a, b)});
        }
      }
    }
    auto vid = [&](int a, int b) { return id[static_cast<std::size_t>(b * nx + a)]; };
    auto fine = [&](int i, int j) { return add_vertex(m, {node_x(i), node_y(j), h(i, j)}); };
    auto tri = [&](std::uint32_t p, std::uint32_t q, std::uint32_t r) {
      const glm::dvec2 c = (glm::dvec2(m.positions_m[p]) + glm::dvec2(m.positions_m[q]) +
                            glm::dvec2(m.positions_m[r])) /
                           3.0;
      add_triangle(m, p, q, r, surround_material(c));
    };
    for (int b = 0; b + 1 < ny; ++b) {
      for (int a = 0; a + 1 < nx; ++a) {
        if (a >= a_lo && a < a_hi && b >= b_lo && b < b_hi)
          continue;  // the central area
        // Corners counter-clockwise from the south-west.
        const std::array<std::uint32_t, 4> c{vid(a, b), vid(a + 1, b), vid(a + 1, b + 1),
                                             vid(a, b + 1)};
        // Which edge (0 south, 1 east, 2 north, 3 west) lies on the central area, if any, and
        // its level-0 nodes in counter-clockwise order.
        int edge = -1;
        std::array<std::uint32_t, kRingFine + 1> f{};
        if (b == b_lo - 1 && a >= a_lo && a < a_hi) {
          edge = 2;  // north edge, east to west
          for (int k = 1; k < kRingFine; ++k)
            f[static_cast<std::size_t>(k)] = fine((a - a_lo + 1) * kRingFine - k, 0);
        } else if (b == b_hi && a >= a_lo && a < a_hi) {
          edge = 0;  // south edge, west to east
          for (int k = 1; k < kRingFine; ++k)
            f[static_cast<std::size_t>(k)] = fine((a - a_lo) * kRingFine + k, kCellsY);
        } else if (a == a_lo - 1 && b >= b_lo && b < b_hi) {
          edge = 1;  // east edge, south to north
          for (int k = 1; k < kRingFine; ++k)
            f[static_cast<std::size_t>(k)] = fine(0, (b - b_lo) * kRingFine + k);
        } else if (a == a_hi && b >= b_lo && b < b_hi) {
          edge = 3;  // west edge, north to south
          for (int k = 1; k < kRingFine; ++k)
            f[static_cast<std::size_t>(k)] = fine(kCellsX, (b - b_lo + 1) * kRingFine - k);
        }
        if (edge < 0) {
          tri(c[0], c[1], c[2]);
          tri(c[0], c[2], c[3]);
          continue;
        }
        const auto e = static_cast<std::size_t>(edge);
        f.front() = c[e];
        f.back() = c[(e + 1) % 4];
        const std::uint32_t r = c[(e + 2) % 4], s = c[(e + 3) % 4];
        // Fans from the two far corners, and the triangle between them.
        constexpr int kMid = kRingFine / 2;
        for (int k = 0; k < kRingFine; ++k) {
          const auto ks = static_cast<std::size_t>(k);
          tri(f[ks], f[ks + 1], k < kMid ? s : r);
        }
        tri(f[kMid], r, s);
      }
    }
    const Mesh located = m;  // before sorting: the locator below walks cells in this order
    sort_by_material(m);
    add_object("surround_terrain", std::move(m), glm::dmat4(1.0), "surround");
    emit_lake_sheet(outer_lake_, 64, "surround_lake", "surround");

    // River outside the central area: flat across, on its level or just above the coarse ground.
    auto surround_height = [&](glm::dvec2 p) {
      if (in_central(p))
        return central_height(p);
      double best = -kInf;
      for (std::size_t t = 0; t < located.triangles.size(); ++t) {
        const glm::uvec3 tr = located.triangles[t];
        const glm::dvec3 p0(located.positions_m[tr.x]), p1(located.positions_m[tr.y]),
            p2(located.positions_m[tr.z]);
        const glm::dvec2 lo = glm::min(glm::min(glm::dvec2(p0), glm::dvec2(p1)), glm::dvec2(p2));
        const glm::dvec2 hi = glm::max(glm::max(glm::dvec2(p0), glm::dvec2(p1)), glm::dvec2(p2));
        if (p.x < lo.x - 1e-6 || p.x > hi.x + 1e-6 || p.y < lo.y - 1e-6 || p.y > hi.y + 1e-6)
          continue;
        const glm::dvec2 e1 = glm::dvec2(p1 - p0), e2 = glm::dvec2(p2 - p0), d = p - glm::dvec2(p0);
        const double det = e1.x * e2.y - e1.y * e2.x;
        const double u = (d.x * e2.y - d.y * e2.x) / det, v = (e1.x * d.y - e1.y * d.x) / det;
        if (u < -1e-9 || v < -1e-9 || u + v > 1.0 + 1e-9)
          continue;
        best = std::max(best, p0.z + u * (p1.z - p0.z) + v * (p2.z - p0.z));
      }
      return best;
    };
    Mesh r;
    const glm::dvec3 o(river_.x_at(0.0), 0.0, std::round(river_.level_m[river_.c.size() / 2]));
    const auto k_south = static_cast<std::size_t>((kHalfSurround_m - kHalfNorth_m) / kRiverStep_m);
    const auto k_north = static_cast<std::size_t>((kHalfSurround_m + kHalfNorth_m) / kRiverStep_m);
    constexpr std::size_t kStride = 10;  // 100 m
    auto edge = [&](std::size_t i, double side) {
      const double s = river_.slope(river_.c[i].y);
      const glm::dvec2 n = glm::dvec2(1.0, -s) / std::sqrt(1.0 + s * s);
      const glm::dvec2 q = river_.c[i] + side * 0.5 * kSurroundRiverWidth_m * n;
      return glm::dvec3(q, std::max(river_.level_m[i], surround_height(q) + 0.3)) - o;
    };
    for (const auto& [k0, k1] :
         {std::pair<std::size_t, std::size_t>{0, k_south},
          std::pair<std::size_t, std::size_t>{k_north, river_.c.size() - 1}}) {
      for (std::size_t k = k0; k < k1; k += kStride) {
        const std::size_t kn = std::min(k + kStride, k1);
        add_quad_facing(r, edge(k, -1), edge(k, 1), edge(kn, 1), edge(kn, -1), {0, 0, 1},
                        mat::kWater);
      }
    }
    add_object("surround_river", std::move(r), placement(o), "surround");
  }

  const TerrainSpec spec_;
  Rng rng_;
  SceneDescription out_;
  std::array<Wave, 6> waves_{};
  River river_;
  std::vector<Road> roads_;
  RoadIndex road_index_;
  glm::dvec2 junction_{0.0};
  Lake lake_, outer_lake_;
  glm::dvec2 line_a_{0.0}, line_b_{0.0};
  double line_heading_ = 0.0;
  std::size_t bridge_a_ = 0, bridge_b_ = 0;  // road_0 samples at the ends of the bridge
  River::Near bridge_cross_;                 // the river where road_0 crosses it
  std::vector<glm::dvec2> pylons_;
  std::vector<Building> buildings_;
  Parcels central_parcels_, surround_parcels_;
  std::vector<double> heights_;  // level-0 central nodes, (kCellsX + 1) per row, south first
  std::size_t central_full_detail_ = 0;
  std::vector<std::vector<std::pair<glm::dvec2, double>>> tree_cells_;  // position, crown [m]
};

}  // namespace

SceneDescription generate_terrain(const TerrainSpec& spec) {
  if (spec.central_triangles > 2'000'000) {
    throw std::invalid_argument(
        "TerrainSpec::central_triangles: " + std::to_string(spec.central_triangles) +
        " is over the limit of 2,000,000");
  }
  if (!(spec.relief_m >= 0.0 && spec.relief_m <= 100.0)) {
    throw std::invalid_argument("TerrainSpec::relief_m must be in [0, 100] m");
  }
  return Builder(spec).build();
}

glm::vec3 terrain_preview_colour(std::string_view material) noexcept {
  for (const mat::Def& d : mat::kDefs) {
    if (material == d.name)
      return {d.r, d.g, d.b};
  }
  for (const mat::Def& d : kPreviewOnly) {
    if (material == d.name)
      return {d.r, d.g, d.b};
  }
  return {0.5f, 0.5f, 0.5f};
}

}  // namespace radar_emu::scene
