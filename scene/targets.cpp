#include "scene/targets.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <numbers>
#include <stdexcept>
#include <string>
#include <vector>

#include "common/path.hpp"
#include "common/units.hpp"
#include "scene/gltf.hpp"
#include "scene/mesh_io.hpp"

namespace radar_emu::scene {

namespace {

constexpr std::array<std::pair<TargetKind, std::string_view>, 12> kNames{{
    {TargetKind::kPlate, "plate"},
    {TargetKind::kDihedral, "dihedral"},
    {TargetKind::kTrihedralSquare, "trihedral-square"},
    {TargetKind::kTrihedralTriangular, "trihedral-tri"},
    {TargetKind::kSphere, "sphere"},
    {TargetKind::kCylinder, "cylinder"},
    {TargetKind::kBox, "box"},
    {TargetKind::kVehicle, "vehicle"},
    {TargetKind::kTruck, "truck"},
    {TargetKind::kJeep, "jeep"},
    {TargetKind::kHelicopter, "helicopter"},
    {TargetKind::kTransportAircraft, "transport_aircraft"},
}};

int divisions(double length_m, double facet_m) {
  if (facet_m <= 0.0)
    return 1;
  return std::max(1, static_cast<int>(std::ceil(length_m / facet_m - 1e-9)));
}

// Parallelogram origin + s u + t v (s, t in [0, 1]) split into nu x nv cells, 2 triangles each,
// wound so the normal is u x v.
void add_patch(Mesh& m, glm::dvec3 origin, glm::dvec3 u, glm::dvec3 v, int nu, int nv) {
  const auto base = static_cast<unsigned>(m.positions_m.size());
  for (int j = 0; j <= nv; ++j) {
    for (int i = 0; i <= nu; ++i) {
      m.positions_m.emplace_back(origin + u * (static_cast<double>(i) / nu) +
                                 v * (static_cast<double>(j) / nv));
    }
  }
  const auto row = static_cast<unsigned>(nu + 1);
  for (int j = 0; j < nv; ++j) {
    for (int i = 0; i < nu; ++i) {
      const unsigned a = base + static_cast<unsigned>(j) * row + static_cast<unsigned>(i);
      m.triangles.push_back({a, a + 1, a + row + 1});
      m.triangles.push_back({a, a + row + 1, a + row});
    }
  }
  m.triangle_material.resize(m.triangles.size(), 0);
}

// Triangle (p0, p1, p2) split into n^2 similar triangles, normal along (p1-p0) x (p2-p0).
void add_tri(Mesh& m, glm::dvec3 p0, glm::dvec3 p1, glm::dvec3 p2, int n) {
  auto p = [&](int i, int j) {
    return glm::vec3(p0 + (p1 - p0) * (static_cast<double>(i) / n) +
                     (p2 - p0) * (static_cast<double>(j) / n));
  };
  for (int j = 0; j < n; ++j) {
    for (int i = 0; i + j < n; ++i) {
      auto base = static_cast<unsigned>(m.positions_m.size());
      m.positions_m.insert(m.positions_m.end(), {p(i, j), p(i + 1, j), p(i, j + 1)});
      m.triangles.push_back({base, base + 1, base + 2});
      if (i + j + 1 < n) {
        base = static_cast<unsigned>(m.positions_m.size());
        m.positions_m.insert(m.positions_m.end(), {p(i + 1, j), p(i + 1, j + 1), p(i, j + 1)});
        m.triangles.push_back({base, base + 1, base + 2});
      }
    }
  }
  m.triangle_material.resize(m.triangles.size(), 0);
}

// Parts of the vehicle are convex: wind every face so its normal points away from the part's
// centre.
void add_face(Mesh& m, glm::dvec3 origin, glm::dvec3 u, glm::dvec3 v, glm::dvec3 centre, double f) {
  const glm::dvec3 mid = origin + 0.5 * (u + v);
  if (glm::dot(glm::cross(u, v), mid - centre) < 0.0)
    std::swap(u, v);
  add_patch(m, origin, u, v, divisions(glm::length(u), f), divisions(glm::length(v), f));
}
void add_tri_out(Mesh& m, glm::dvec3 p0, glm::dvec3 p1, glm::dvec3 p2, glm::dvec3 centre,
                 double f) {
  if (glm::dot(glm::cross(p1 - p0, p2 - p0), (p0 + p1 + p2) / 3.0 - centre) < 0.0)
    std::swap(p1, p2);
  const double longest =
      std::max({glm::length(p1 - p0), glm::length(p2 - p1), glm::length(p0 - p2)});
  add_tri(m, p0, p1, p2, divisions(longest, f));
}

// Axis-aligned box [lo, hi].
void add_box(Mesh& m, glm::dvec3 lo, glm::dvec3 hi, double f) {
  const glm::dvec3 c = 0.5 * (lo + hi), d = hi - lo;
  const glm::dvec3 ex(d.x, 0, 0), ey(0, d.y, 0), ez(0, 0, d.z);
  add_face(m, lo, ex, ey, c, f);
  add_face(m, lo + ez, ex, ey, c, f);
  add_face(m, lo, ex, ez, c, f);
  add_face(m, lo + ey, ex, ez, c, f);
  add_face(m, lo, ey, ez, c, f);
  add_face(m, lo + ex, ey, ez, c, f);
}

// Closed prism: convex polygon `outline` (in the plane through the origin normal to `axis`)
// extruded from `base` along axis * length; caps fanned from the centroid.
void add_prism(Mesh& m, const std::vector<glm::dvec3>& outline, glm::dvec3 base, glm::dvec3 axis,
               double length, double f) {
  glm::dvec3 cen(0.0);
  for (const glm::dvec3& p : outline)
    cen += p;
  cen /= static_cast<double>(outline.size());
  const glm::dvec3 centre = base + cen + 0.5 * length * axis;
  const std::size_t n = outline.size();
  for (std::size_t i = 0; i < n; ++i) {
    const glm::dvec3 a = base + outline[i], b = base + outline[(i + 1) % n];
    add_face(m, a, b - a, axis * length, centre, f);
    add_tri_out(m, base + cen, a, b, centre, f);
    add_tri_out(m, base + cen + axis * length, a + axis * length, b + axis * length, centre, f);
  }
}

// Closed frustum between two similar convex outlines (z = z0 and z = z1) around (cx, cy).
void add_frustum(Mesh& m, const std::vector<glm::dvec2>& lower,
                 const std::vector<glm::dvec2>& upper, double z0, double z1, double f) {
  const std::size_t n = lower.size();
  glm::dvec3 centre(0.0);
  for (std::size_t i = 0; i < n; ++i)
    centre += glm::dvec3(lower[i], z0) + glm::dvec3(upper[i], z1);
  centre /= 2.0 * static_cast<double>(n);
  glm::dvec2 cl(0.0), cu(0.0);
  for (std::size_t i = 0; i < n; ++i) {
    cl += lower[i] / static_cast<double>(n);
    cu += upper[i] / static_cast<double>(n);
  }
  for (std::size_t i = 0; i < n; ++i) {
    const glm::dvec3 a0(lower[i], z0), b0(lower[(i + 1) % n], z0);
    const glm::dvec3 a1(upper[i], z1), b1(upper[(i + 1) % n], z1);
    add_tri_out(m, a0, b0, b1, centre, f);
    add_tri_out(m, a0, b1, a1, centre, f);
    add_tri_out(m, glm::dvec3(cl, z0), a0, b0, centre, f);
    add_tri_out(m, glm::dvec3(cu, z1), a1, b1, centre, f);
  }
}

// Closed circular cylinder: centre of the first cap, unit axis, radius, length. The caps are
// tessellated in concentric rings (a fan would make slivers as long as the radius).
void add_cylinder(Mesh& m, glm::dvec3 base, glm::dvec3 axis, double radius, double length,
                  double f) {
  const double pi = std::numbers::pi;
  const glm::dvec3 helper = std::abs(axis.z) < 0.9 ? glm::dvec3(0, 0, 1) : glm::dvec3(1, 0, 0);
  const glm::dvec3 e1 = glm::normalize(glm::cross(axis, helper)), e2 = glm::cross(axis, e1);
  const int around = std::max(12, divisions(2 * pi * radius, f));
  const int rings = divisions(radius, f);
  auto at = [&](int i, double r) {
    const double ph = 2 * pi * i / around;
    return r * (std::cos(ph) * e1 + std::sin(ph) * e2);
  };
  const glm::dvec3 centre = base + 0.5 * length * axis;
  for (int i = 0; i < around; ++i) {
    add_face(m, base + at(i, radius), at(i + 1, radius) - at(i, radius), axis * length, centre, f);
    for (double h : {0.0, length}) {
      const glm::dvec3 c0 = base + h * axis;
      for (int j = 0; j < rings; ++j) {
        const double r0 = radius * j / rings, r1 = radius * (j + 1) / rings;
        if (j == 0) {
          add_tri_out(m, c0, c0 + at(i, r1), c0 + at(i + 1, r1), centre, 0.0);
        } else {
          add_tri_out(m, c0 + at(i, r0), c0 + at(i, r1), c0 + at(i + 1, r1), centre, 0.0);
          add_tri_out(m, c0 + at(i, r0), c0 + at(i + 1, r1), c0 + at(i + 1, r0), centre, 0.0);
        }
      }
    }
  }
}

void make_vehicle(Mesh& m, double a, double b, double c, double f) {
  // Proportions of a main battle tank (overall 7 x 3.5 x 2.5 m: gun forward of the hull).
  const double hull_rear = -0.50 * a, hull_front = 0.25 * a;
  const double belly = 0.065 * c, deck = 0.58 * c;
  const double hull_half = 0.31 * b;
  // Hull: a side profile (x, z) with a sloped glacis and a sloped rear, extruded across y.
  const std::vector<glm::dvec3> profile{{hull_rear + 0.03 * a, 0, belly},
                                        {hull_front - 0.09 * a, 0, belly},
                                        {hull_front, 0, 0.38 * c},
                                        {hull_front - 0.17 * a, 0, deck},
                                        {hull_rear, 0, deck},
                                        {hull_rear, 0, 0.30 * c}};
  add_prism(m, profile, {0, -hull_half, 0}, {0, 1, 0}, 2 * hull_half, f);
  // Track skirts (thick side plates over the wheels) and road wheels, both sides.
  for (double side : {-1.0, 1.0}) {
    const double outer = side * 0.5 * b, inner = side * 0.32 * b;
    add_box(m, {hull_rear + 0.01 * a, std::min(outer, inner), 0.22 * c},
            {hull_front - 0.03 * a, std::max(outer, inner), 0.40 * c}, f);
    for (int w = 0; w < 6; ++w) {
      const double x = hull_rear + 0.08 * a + w * (0.57 * a / 5.0);
      add_cylinder(m, {x, side * 0.33 * b, 0.13 * c}, {0, side, 0}, 0.13 * c, 0.15 * b, f);
    }
  }
  // Turret: an octagonal frustum with sloped faces, behind the hull's centre.
  const double tx = -0.14 * a, tz0 = deck, tz1 = 0.86 * c;
  std::vector<glm::dvec2> lower, upper;
  const double pi = std::numbers::pi;
  for (int i = 0; i < 8; ++i) {
    const double ph = 2 * pi * (i + 0.5) / 8;
    lower.push_back({tx + 0.16 * a * std::cos(ph), 0.29 * b * std::sin(ph)});
    upper.push_back({tx + 0.13 * a * std::cos(ph), 0.24 * b * std::sin(ph)});
  }
  add_frustum(m, lower, upper, tz0, tz1, f);
  // Gun: mantlet box and barrel to the overall front (x = a / 2).
  const double gun_z = 0.72 * c;
  add_box(m, {tx + 0.14 * a, -0.06 * b, gun_z - 0.06 * c},
          {tx + 0.19 * a, 0.06 * b, gun_z + 0.06 * c}, f);
  add_cylinder(m, {tx + 0.19 * a, 0, gun_z}, {1, 0, 0}, 0.022 * c, 0.5 * a - (tx + 0.19 * a), f);
  // Cupola on the turret roof, up to the overall height.
  add_cylinder(m, {tx - 0.04 * a, 0.09 * b, tz1}, {0, 0, 1}, 0.11 * b, c - tz1, f);
  // Stowage boxes on the turret's rear and the hull's rear deck.
  add_box(m, {tx - 0.21 * a, -0.22 * b, 0.64 * c}, {tx - 0.14 * a, 0.22 * b, 0.80 * c}, f);
  add_box(m, {hull_rear + 0.01 * a, -0.25 * b, deck}, {hull_rear + 0.09 * a, 0.25 * b, 0.66 * c},
          f);
}

// ---- Lofted parts of the vehicles and aircraft (truck, jeep, helicopter, transport_aircraft) ----

using Ring = std::vector<glm::dvec3>;

// Points of a convex 2-D profile placed in a plane: origin + p.x ex + p.y ey.
Ring place(const std::vector<glm::dvec2>& profile, glm::dvec3 origin, glm::dvec3 ex,
           glm::dvec3 ey) {
  Ring r;
  for (const glm::dvec2& p : profile)
    r.push_back(origin + p.x * ex + p.y * ey);
  return r;
}

// Regular n-gon inscribed in the ellipse of semi-axes (ru, rv), first vertex at angle `phase`.
std::vector<glm::dvec2> ngon(int n, double ru, double rv, double phase) {
  std::vector<glm::dvec2> p;
  for (int i = 0; i < n; ++i) {
    const double ph = phase + 2.0 * std::numbers::pi * i / n;
    p.emplace_back(ru * std::cos(ph), rv * std::sin(ph));
  }
  return p;
}

// Sides of a round part: n0 at facet_m = 0, more when the facet size asks for it (a multiple of
// 4, so that vertices stay at the top, bottom and sides).
int around(double radius, int n0, double f) {
  if (f <= 0.0)
    return n0;
  return std::max(n0, 4 * divisions(2.0 * std::numbers::pi * radius, 4.0 * f));
}

// A closed part lofted through `rings` (each a planar convex polygon, all with the same number
// of corresponding points; consecutive rings similar with parallel sides, so that every band is
// made of planar trapezoids) and closed at both ends by a fan to an apex (nullopt: the ring's
// centroid, a flat cap; elsewhere a pyramid). Vertices are shared, so the part is closed by
// construction; it is wound outward (its signed volume is made positive). With f > 0 bands are
// split along and around and caps into concentric rings, so that no edge exceeds f (quad
// diagonals sqrt(2) f); the surface, hence the volume, is the same at every f.
void add_loft(Mesh& m, const std::vector<Ring>& rings, std::optional<glm::dvec3> apex_first,
              std::optional<glm::dvec3> apex_last, double f) {
  const std::size_t n = rings.front().size();
  // Points along each polygon side (the same count on every ring).
  std::vector<int> side(n, 1);
  for (const Ring& r : rings) {
    for (std::size_t i = 0; i < n; ++i)
      side[i] = std::max(side[i], divisions(glm::length(r[(i + 1) % n] - r[i]), f));
  }
  auto expand = [&](const Ring& r) {
    Ring e;
    for (std::size_t i = 0; i < n; ++i) {
      for (int s = 0; s < side[i]; ++s)
        e.push_back(r[i] + (r[(i + 1) % n] - r[i]) * (static_cast<double>(s) / side[i]));
    }
    return e;
  };
  std::vector<Ring> all{expand(rings.front())};
  for (std::size_t k = 1; k < rings.size(); ++k) {
    const Ring a = expand(rings[k - 1]), b = expand(rings[k]);
    int steps = 1;
    for (std::size_t i = 0; i < a.size(); ++i)
      steps = std::max(steps, divisions(glm::length(b[i] - a[i]), f));
    for (int s = 1; s <= steps; ++s) {
      Ring r;
      for (std::size_t i = 0; i < a.size(); ++i)
        r.push_back(a[i] + (b[i] - a[i]) * (static_cast<double>(s) / steps));
      all.push_back(std::move(r));
    }
  }
  const std::size_t first_triangle = m.triangles.size();
  auto add_ring = [&](const Ring& r) {
    const auto base = static_cast<unsigned>(m.positions_m.size());
    for (const glm::dvec3& p : r)
      m.positions_m.emplace_back(p);
    return base;
  };
  const auto count = static_cast<unsigned>(all.front().size());
  // Band between rings x and y: x's edges run forward (k -> k+1), y's backward. Each quad is
  // split along its shorter diagonal (at most sqrt(2) f when its sides are at most f).
  auto band = [&](unsigned x, unsigned y) {
    const auto& p = m.positions_m;
    for (unsigned k = 0; k < count; ++k) {
      const unsigned k1 = (k + 1) % count;
      if (glm::length(p[x + k] - p[y + k1]) <= glm::length(p[x + k1] - p[y + k])) {
        m.triangles.push_back({x + k, x + k1, y + k1});
        m.triangles.push_back({x + k, y + k1, y + k});
      } else {
        m.triangles.push_back({x + k, x + k1, y + k});
        m.triangles.push_back({x + k1, y + k1, y + k});
      }
    }
  };
  auto centroid = [](const Ring& r) {
    glm::dvec3 c(0.0);
    for (const glm::dvec3& p : r)
      c += p;
    return c / static_cast<double>(r.size());
  };
  std::vector<unsigned> ids;
  for (const Ring& r : all)
    ids.push_back(add_ring(r));
  for (std::size_t k = 1; k < all.size(); ++k)
    band(ids[k - 1], ids[k]);
  // Caps: concentric rings from the apex out to the end ring; the first cap runs the end ring
  // backward, the last one forward, so that every edge pairs with its reverse.
  auto cap = [&](const Ring& end, unsigned end_id, glm::dvec3 apex, bool first) {
    int steps = 1;
    for (const glm::dvec3& p : end)
      steps = std::max(steps, divisions(glm::length(p - apex), f));
    std::vector<unsigned> inner;  // rings 1 .. steps-1 from the apex, then the end ring
    for (int s = 1; s < steps; ++s) {
      Ring r;
      for (const glm::dvec3& p : end)
        r.push_back(apex + (p - apex) * (static_cast<double>(s) / steps));
      inner.push_back(add_ring(r));
    }
    inner.push_back(end_id);
    const auto tip = static_cast<unsigned>(m.positions_m.size());
    m.positions_m.emplace_back(apex);
    for (unsigned k = 0; k < count; ++k) {
      const unsigned k1 = (k + 1) % count;
      if (first)
        m.triangles.push_back({tip, inner[0] + k1, inner[0] + k});
      else
        m.triangles.push_back({tip, inner[0] + k, inner[0] + k1});
    }
    for (std::size_t s = 1; s < inner.size(); ++s) {
      if (first)
        band(inner[s - 1], inner[s]);
      else
        band(inner[s], inner[s - 1]);
    }
  };
  cap(all.front(), ids.front(), apex_first.value_or(centroid(rings.front())), true);
  cap(all.back(), ids.back(), apex_last.value_or(centroid(rings.back())), false);
  // Outward: positive signed volume (divergence theorem about the part's first vertex).
  const glm::dvec3 o(m.positions_m[m.triangles[first_triangle].x]);
  double volume = 0.0;
  for (std::size_t t = first_triangle; t < m.triangles.size(); ++t) {
    const glm::uvec3 tri = m.triangles[t];
    volume += glm::dot(
        glm::dvec3(m.positions_m[tri.x]) - o,
        glm::cross(glm::dvec3(m.positions_m[tri.y]) - o, glm::dvec3(m.positions_m[tri.z]) - o));
  }
  if (volume < 0.0) {
    for (std::size_t t = first_triangle; t < m.triangles.size(); ++t)
      std::swap(m.triangles[t].y, m.triangles[t].z);
  }
  m.triangle_material.resize(m.triangles.size(), 0);
}

const glm::dvec3 kX(1, 0, 0), kY(0, 1, 0), kZ(0, 0, 1);

// Box [lo, hi] as a loft along x (flat caps fanned from their centres).
void add_block(Mesh& m, glm::dvec3 lo, glm::dvec3 hi, double f) {
  const std::vector<glm::dvec2> rect{{lo.y, lo.z}, {hi.y, lo.z}, {hi.y, hi.z}, {lo.y, hi.z}};
  add_loft(m, {place(rect, {lo.x, 0, 0}, kY, kZ), place(rect, {hi.x, 0, 0}, kY, kZ)}, std::nullopt,
           std::nullopt, f);
}

// Prism of a convex side profile (x, z) between y0 and y1.
void add_side_prism(Mesh& m, const std::vector<glm::dvec2>& xz, double y0, double y1, double f) {
  add_loft(m, {place(xz, {0, y0, 0}, kX, kZ), place(xz, {0, y1, 0}, kX, kZ)}, std::nullopt,
           std::nullopt, f);
}

// Wheel: an n-gon prism along y (axle) of radius r, centre (x, z = r) so that a vertex touches
// the ground (z = 0), faces at y0 and y1.
void add_wheel(Mesh& m, double x, double r, double y0, double y1, int n, double f) {
  const auto rim = ngon(around(r, n, f), r, r, -std::numbers::pi / 2);
  add_loft(m, {place(rim, {x, y0, r}, kX, kZ), place(rim, {x, y1, r}, kX, kZ)}, std::nullopt,
           std::nullopt, f);
}

// Symmetric hexagonal aerofoil of chord 1 and thickness ratio tau, leading edge at the origin,
// chord along -u (aft), thickness along v. Area 0.675 tau (chord^2).
std::vector<glm::dvec2> aerofoil(double tau) {
  const double h = 0.5 * tau;
  return {{0, 0}, {-0.25, h}, {-0.6, h}, {-1, 0}, {-0.6, -h}, {-0.25, -h}};
}

// Tapered, swept lifting surface: aerofoil sections (thickness ratio tau) in planes normal to
// `span_axis`, root chord `chord` with its leading edge at `root_le`, sections scaled by `taper`
// at the tip(s) a distance `half_span` away, leading edge moved aft by tan(sweep) and along
// `rise` by tan(dihedral) per metre of span. Both tips (a wing through the fuselage) or one
// (a fin). Sections are scaled about their leading edge: similar, parallel sides.
void add_surface(Mesh& m, glm::dvec3 root_le, glm::dvec3 span_axis, glm::dvec3 thick_axis,
                 glm::dvec3 rise, double half_span, double chord, double tau, double taper,
                 double sweep_rad, double dihedral_rad, bool both_sides, double f) {
  std::vector<glm::dvec2> root = aerofoil(tau);
  auto section = [&](double s) {  // s: signed span position
    const double scale = s == 0.0 ? 1.0 : taper;
    std::vector<glm::dvec2> p = root;
    for (glm::dvec2& q : p)
      q *= chord * scale;
    const glm::dvec3 le = root_le + s * span_axis - std::abs(s) * std::tan(sweep_rad) * kX +
                          std::abs(s) * std::tan(dihedral_rad) * rise;
    return place(p, le, kX, thick_axis);
  };
  std::vector<Ring> rings;
  if (both_sides)
    rings.push_back(section(half_span));
  rings.push_back(section(0.0));
  rings.push_back(section(both_sides ? -half_span : half_span));
  add_loft(m, rings, std::nullopt, std::nullopt, f);
}

// Truck (a x b x c overall, x forward): three axles of twin-tyre-width wheels, a ladder chassis,
// a cab with a sloped upper front and a cargo box. Proportions (fractions of a, b, c):
//   wheels    6, 16-gon r 0.15c, y from +-0.34b to +-0.48b, axles at x 0.33a, -0.17a, -0.33a
//   chassis   x [-0.48a, 0.45a], y +-0.33b, z [0.17c, 0.27c]
//   cab       side profile (0.24a,0.22c) (0.5a,0.22c) (0.5a,0.55c) (0.44a,0.78c) (0.24a,0.78c),
//             y +-0.5b
//   cargo box x [-0.5a, 0.21a], y +-0.5b, z [0.29c, c]
void make_truck(Mesh& m, double a, double b, double c, double f) {
  const double r = 0.15 * c;
  for (double x : {0.33 * a, -0.17 * a, -0.33 * a}) {
    for (double s : {-1.0, 1.0})
      add_wheel(m, x, r, s * 0.34 * b, s * 0.48 * b, 16, f);
  }
  add_block(m, {-0.48 * a, -0.33 * b, 0.17 * c}, {0.45 * a, 0.33 * b, 0.27 * c}, f);
  add_side_prism(m,
                 {{0.24 * a, 0.22 * c},
                  {0.5 * a, 0.22 * c},
                  {0.5 * a, 0.55 * c},
                  {0.44 * a, 0.78 * c},
                  {0.24 * a, 0.78 * c}},
                 -0.5 * b, 0.5 * b, f);
  add_block(m, {-0.5 * a, -0.5 * b, 0.29 * c}, {0.21 * a, 0.5 * b, c}, f);
}

// Jeep (a x b x c overall): four wheels, a hull with a sloped nose and a cabin with a raked
// windscreen.
//   wheels 4, 16-gon r 0.19c, y from +-0.36b to +-0.5b, axles at x +-0.31a
//   hull   side profile (-0.5a,0.2c) (0.44a,0.2c) (0.5a,0.3c) (0.5a,0.52c) (-0.5a,0.55c),
//          y +-0.43b
//   cabin  side profile (-0.45a,0.5c) (0.12a,0.5c) (0.02a,c) (-0.45a,c), y +-0.42b
void make_jeep(Mesh& m, double a, double b, double c, double f) {
  const double r = 0.19 * c;
  for (double x : {0.31 * a, -0.31 * a}) {
    for (double s : {-1.0, 1.0})
      add_wheel(m, x, r, s * 0.36 * b, s * 0.5 * b, 16, f);
  }
  add_side_prism(m,
                 {{-0.5 * a, 0.2 * c},
                  {0.44 * a, 0.2 * c},
                  {0.5 * a, 0.3 * c},
                  {0.5 * a, 0.52 * c},
                  {-0.5 * a, 0.55 * c}},
                 -0.43 * b, 0.43 * b, f);
  add_side_prism(m, {{-0.45 * a, 0.5 * c}, {0.12 * a, 0.5 * c}, {0.02 * a, c}, {-0.45 * a, c}},
                 -0.42 * b, 0.42 * b, f);
}

// Helicopter: a = fuselage length (nose to tail), b = main rotor diameter, c = overall height.
//   fuselage  16-gon elliptic sections, semi-axes 0.08a (y) x 0.22c (z), centre z_f = 0.38c:
//             nose apex (0.5a, 0, z_f - 0.06c); ring x 0.42a scale 0.6 centre z_f - 0.04c; full
//             rings x 0.3a and -0.12a; ring x -0.22a scale 0.4 centre z_f + 0.12c; rear apex
//             (-0.25a, 0, z_f + 0.13c)
//   boom      12-gon frustum along x from x -0.18a (r 0.045c) to -0.47a (r 0.025c), z_f + 0.12c
//   fin       side profile (-0.5a,0.45c) (-0.43a,0.45c) (-0.46a,0.85c) (-0.5a,0.85c), y +-0.008a
//   stabiliser x [-0.45a, -0.40a], y +-0.1a, z [z_f + 0.1c, z_f + 0.13c]
//   tail rotor 16-gon disc r 0.08a, centre (-0.42a, z 0.65c), y [0.009a, 0.013a]
//   mast      12-gon r 0.025a along z at x 0.05a, z [z_f + 0.15c, 0.93c]
//   hub       x 0.05a +- 0.04a, y +-0.04a, z [0.88c, c]
//   blades    a two-bladed rotor parked across the fuselage: y [-b/2, b/2], chord 0.035b
//             centred on x 0.05a, z [0.9c, 0.912c]
//   skids     12-gon tubes r 0.008a along x from -0.2a to 0.25a at y +-0.075a, touching z = 0;
//             struts x {0.15a, -0.1a} +- 0.005a, y +-0.075a +- 0.005a, z [0.004a, 0.33c]
void make_helicopter(Mesh& m, double a, double b, double c, double f) {
  const double pi = std::numbers::pi;
  const double zf = 0.38 * c, w = 0.08 * a, h = 0.22 * c;
  const int nf = around(std::max(w, h), 16, f);
  const auto section = ngon(nf, w, h, -pi / 2);
  auto scaled = [&](double s) {
    std::vector<glm::dvec2> p = section;
    for (glm::dvec2& q : p)
      q *= s;
    return p;
  };
  add_loft(
      m,
      {place(scaled(0.6), {0.42 * a, 0, zf - 0.04 * c}, kY, kZ),
       place(scaled(1.0), {0.3 * a, 0, zf}, kY, kZ), place(scaled(1.0), {-0.12 * a, 0, zf}, kY, kZ),
       place(scaled(0.4), {-0.22 * a, 0, zf + 0.12 * c}, kY, kZ)},
      glm::dvec3(0.5 * a, 0, zf - 0.06 * c), glm::dvec3(-0.25 * a, 0, zf + 0.13 * c), f);
  const int nb = around(0.045 * c, 12, f);
  add_loft(m,
           {place(ngon(nb, 0.045 * c, 0.045 * c, -pi / 2), {-0.18 * a, 0, zf + 0.12 * c}, kY, kZ),
            place(ngon(nb, 0.025 * c, 0.025 * c, -pi / 2), {-0.47 * a, 0, zf + 0.12 * c}, kY, kZ)},
           std::nullopt, std::nullopt, f);
  add_side_prism(
      m, {{-0.5 * a, 0.45 * c}, {-0.43 * a, 0.45 * c}, {-0.46 * a, 0.85 * c}, {-0.5 * a, 0.85 * c}},
      -0.008 * a, 0.008 * a, f);
  add_block(m, {-0.45 * a, -0.1 * a, zf + 0.1 * c}, {-0.40 * a, 0.1 * a, zf + 0.13 * c}, f);
  const auto disc = ngon(around(0.08 * a, 16, f), 0.08 * a, 0.08 * a, 0.0);
  add_loft(m,
           {place(disc, {-0.42 * a, 0.009 * a, 0.65 * c}, kX, kZ),
            place(disc, {-0.42 * a, 0.013 * a, 0.65 * c}, kX, kZ)},
           std::nullopt, std::nullopt, f);
  const auto mast = ngon(around(0.025 * a, 12, f), 0.025 * a, 0.025 * a, 0.0);
  add_loft(m,
           {place(mast, {0.05 * a, 0, zf + 0.15 * c}, kX, kY),
            place(mast, {0.05 * a, 0, 0.93 * c}, kX, kY)},
           std::nullopt, std::nullopt, f);
  add_block(m, {0.01 * a, -0.04 * a, 0.88 * c}, {0.09 * a, 0.04 * a, c}, f);
  // Two-bladed rotor parked across the fuselage: one blade pair from y = -b/2 to b/2.
  const double chord = 0.035 * b;
  const std::vector<glm::dvec2> blade{{0.05 * a - 0.5 * chord, 0.9 * c},
                                      {0.05 * a + 0.5 * chord, 0.9 * c},
                                      {0.05 * a + 0.5 * chord, 0.912 * c},
                                      {0.05 * a - 0.5 * chord, 0.912 * c}};
  add_side_prism(m, blade, -0.5 * b, 0.5 * b, f);
  const double rs = 0.008 * a;
  const auto tube = ngon(around(rs, 12, f), rs, rs, -pi / 2);
  for (double s : {-1.0, 1.0}) {
    const double y = s * 0.075 * a;
    add_loft(m, {place(tube, {0.25 * a, y, rs}, kY, kZ), place(tube, {-0.2 * a, y, rs}, kY, kZ)},
             std::nullopt, std::nullopt, f);
    for (double x : {0.15 * a, -0.1 * a})
      add_block(m, {x - 0.005 * a, y - 0.005 * a, 0.5 * rs},
                {x + 0.005 * a, y + 0.005 * a, 0.33 * c}, f);
  }
}

// Transport aircraft (A320 / C-130 class): a = overall length, b = wing span, c = overall
// height (ground to fin tip). R = 0.053a, fuselage axis z_f = 0.3c.
//   fuselage  32-gon: nose apex (0.5a, 0, z_f - 0.3R); ring x 0.43a scale 0.55 centre
//             z_f - 0.25R; full rings x 0.33a and -0.2a; ring x -0.43a scale 0.35 centre
//             z_f + 0.5R; tail apex (-0.5a, 0, z_f + 0.55R)
//   wing      hexagonal aerofoil (tau 0.12), root chord 0.19a, leading edge (0.12a, 0,
//             z_f - 0.55R), tips at y +-b/2 with taper 0.24, sweep 27 deg, dihedral 5 deg
//   tailplane tau 0.10, root chord 0.1a at (-0.355a, 0, z_f + 0.35R), span 0.34b, taper 0.33,
//             dihedral 6 deg, swept so that the tips' leading edges are at x = -0.44a
//   fin       tau 0.10, sections horizontal, root chord 0.17a at (-0.3a, 0, z_f + 0.4R), tip at
//             z = c, taper 0.35, swept so that the tip's trailing edge is at x = -0.49a
//   engines   2 nacelles at y +-0.17b, 24-gon r_e 0.031a: rings scale 0.9 / 1 / 0.7 at x_f,
//             x_f - 0.04a, x_f - 0.11a, with x_f 0.06a ahead of the wing's leading edge there,
//             axis 1.15 r_e under it; pylons x [x_f - 0.09a, x_f - 0.01a], y +-0.004a, z from
//             the axis + 0.8 r_e up to the leading edge's height
//   gear      nose: 12-gon wheel r 0.035c at x 0.4a, y +-0.008a; strut x 0.4a +- 0.004a,
//             y +-0.003a, z [0.035c, z_f]; main: 16-gon wheels r 0.05c at x -0.04a,
//             y +-(0.1b +- 0.01b); struts x -0.04a +- 0.006a, y +-0.1b +- 0.004a,
//             z [0.05c, z_f - 0.55R]
void make_transport_aircraft(Mesh& m, double a, double b, double c, double f) {
  const double pi = std::numbers::pi;
  const double radius = 0.053 * a, zf = 0.3 * c;
  const int nf = around(radius, 32, f);
  auto circle = [&](double s) { return ngon(nf, s * radius, s * radius, -pi / 2); };
  add_loft(
      m,
      {place(circle(0.55), {0.43 * a, 0, zf - 0.25 * radius}, kY, kZ),
       place(circle(1.0), {0.33 * a, 0, zf}, kY, kZ), place(circle(1.0), {-0.2 * a, 0, zf}, kY, kZ),
       place(circle(0.35), {-0.43 * a, 0, zf + 0.5 * radius}, kY, kZ)},
      glm::dvec3(0.5 * a, 0, zf - 0.3 * radius), glm::dvec3(-0.5 * a, 0, zf + 0.55 * radius), f);
  const glm::dvec3 wing_le(0.12 * a, 0, zf - 0.55 * radius);
  const double sweep = common::radians(27), dihedral = common::radians(5);
  add_surface(m, wing_le, kY, kZ, kZ, 0.5 * b, 0.19 * a, 0.12, 0.24, sweep, dihedral, true, f);
  add_surface(m, {-0.355 * a, 0, zf + 0.35 * radius}, kY, kZ, kZ, 0.17 * b, 0.1 * a, 0.10, 0.33,
              std::atan2(0.085 * a, 0.17 * b), common::radians(6), true, f);
  const double fin_z = zf + 0.4 * radius;
  const double fin_sweep = std::atan2(0.49 * a - 0.3 * a - 0.35 * 0.17 * a, c - fin_z);
  add_surface(m, {-0.3 * a, 0, fin_z}, kZ, kY, kZ, c - fin_z, 0.17 * a, 0.10, 0.35, fin_sweep, 0.0,
              false, f);
  const double re = 0.031 * a;
  const int ne = around(re, 24, f);
  for (double s : {-1.0, 1.0}) {
    const double y = s * 0.17 * b;
    const double le_x = wing_le.x - 0.17 * b * std::tan(sweep);
    const double le_z = wing_le.z + 0.17 * b * std::tan(dihedral);
    const double xf = le_x + 0.06 * a, ze = le_z - 1.15 * re;
    auto ring = [&](double x, double scale) {
      return place(ngon(ne, scale * re, scale * re, -pi / 2), {x, y, ze}, kY, kZ);
    };
    add_loft(m, {ring(xf, 0.9), ring(xf - 0.04 * a, 1.0), ring(xf - 0.11 * a, 0.7)}, std::nullopt,
             std::nullopt, f);
    add_block(m, {xf - 0.09 * a, y - 0.004 * a, ze + 0.8 * re},
              {xf - 0.01 * a, y + 0.004 * a, le_z}, f);
  }
  add_wheel(m, 0.4 * a, 0.035 * c, -0.008 * a, 0.008 * a, 12, f);
  add_block(m, {0.396 * a, -0.003 * a, 0.035 * c}, {0.404 * a, 0.003 * a, zf}, f);
  for (double s : {-1.0, 1.0}) {
    add_wheel(m, -0.04 * a, 0.05 * c, s * 0.09 * b, s * 0.11 * b, 16, f);
    add_block(m, {-0.046 * a, s * 0.1 * b - 0.004 * a, 0.05 * c},
              {-0.034 * a, s * 0.1 * b + 0.004 * a, zf - 0.55 * radius}, f);
  }
}

void require(double x, const char* name, bool allow_zero = false) {
  if (!std::isfinite(x) || x < 0.0 || (!allow_zero && x == 0.0)) {
    throw std::invalid_argument(std::string("target: ") + name + " must be a positive number");
  }
}

}  // namespace

std::optional<TargetKind> target_kind_from_name(std::string_view name) noexcept {
  for (const auto& [k, n] : kNames) {
    if (n == name)
      return k;
  }
  return std::nullopt;
}

std::string_view target_name(TargetKind kind) noexcept {
  for (const auto& [k, n] : kNames) {
    if (k == kind)
      return n;
  }
  return "unknown";
}

std::string target_names() {
  std::string s;
  for (const auto& [k, n] : kNames)
    s += (s.empty() ? "" : "|") + std::string(n);
  return s;
}

TargetKindSize target_kind_size(TargetKind k) noexcept {
  using K = TargetKind;
  using Size = std::array<double, 3>;
  switch (k) {
    case K::kSphere:
      return {1, "[radius]", std::nullopt};
    case K::kTrihedralSquare:
    case K::kTrihedralTriangular:
      return {1, "[edge]", std::nullopt};
    case K::kPlate:
      return {2, "[length x, width y]", std::nullopt};
    case K::kDihedral:
      return {2, "[fold length, face width]", std::nullopt};
    case K::kCylinder:
      return {2, "[radius, length]", std::nullopt};
    case K::kBox:
      return {3, "[length, width, height]", std::nullopt};
    case K::kVehicle:
      return {3, "[length, width, height]", Size{7.0, 3.5, 2.5}};
    case K::kTruck:
      return {3, "[length, width, height]", Size{8.0, 2.5, 3.4}};
    case K::kJeep:
      return {3, "[length, width, height]", Size{4.0, 1.8, 1.9}};
    case K::kHelicopter:
      return {3, "[length, rotor diameter, height]", Size{12.7, 14.6, 4.4}};
    case K::kTransportAircraft:
      return {3, "[length, wing span, height]", Size{37.6, 35.8, 11.8}};
  }
  return {3, "[a, b, c]", std::nullopt};
}

std::string target_size_text(const TargetSpec& spec) {
  const TargetKindSize s = target_kind_size(spec.kind);
  std::string text(target_name(spec.kind));
  const double d[3] = {spec.a_m, spec.b_m, spec.c_m};
  for (int i = 0; i < s.dims; ++i) {
    char buf[32];
    std::snprintf(buf, sizeof buf, "%s%g", i == 0 ? " " : " x ", d[i]);
    text += buf;
  }
  return text + " m " + std::string(s.meaning);
}

SceneDescription make_target(const TargetSpec& t) {
  require(t.a_m, "a_m");
  require(t.b_m, "b_m");
  require(t.c_m, "c_m");
  require(t.facet_m, "facet_m", true);
  const double a = t.a_m, b = t.b_m, c = t.c_m, f = t.facet_m;
  Mesh m;
  const double pi = std::numbers::pi;
  switch (t.kind) {
    case TargetKind::kPlate:
      add_patch(m, {-a / 2, -b / 2, 0}, {a, 0, 0}, {0, b, 0}, divisions(a, f), divisions(b, f));
      break;
    case TargetKind::kDihedral: {
      const double s = b / std::sqrt(2.0);
      // Faces from the fold up and out to x = -+s, z = s; interior normals toward +z.
      add_patch(m, {0, -a / 2, 0}, {0, a, 0}, {-s, 0, s}, divisions(a, f), divisions(b, f));
      add_patch(m, {0, -a / 2, 0}, {s, 0, s}, {0, a, 0}, divisions(b, f), divisions(a, f));
      break;
    }
    case TargetKind::kTrihedralSquare: {
      const int n = divisions(a, f);
      add_patch(m, {0, 0, 0}, {a, 0, 0}, {0, a, 0}, n, n);  // z = 0, normal +z
      add_patch(m, {0, 0, 0}, {0, a, 0}, {0, 0, a}, n, n);  // x = 0, normal +x
      add_patch(m, {0, 0, 0}, {0, 0, a}, {a, 0, 0}, n, n);  // y = 0, normal +y
      break;
    }
    case TargetKind::kTrihedralTriangular: {
      const int n = divisions(a, f);
      add_tri(m, {0, 0, 0}, {a, 0, 0}, {0, a, 0}, n);
      add_tri(m, {0, 0, 0}, {0, a, 0}, {0, 0, a}, n);
      add_tri(m, {0, 0, 0}, {0, 0, a}, {a, 0, 0}, n);
      break;
    }
    case TargetKind::kSphere: {
      const int around = f > 0.0 ? std::max(8, divisions(2 * pi * a, f)) : 32;
      const int rings = std::max(4, around / 2);
      auto p = [&](int i, int j) {  // i around (phi), j from the north pole (theta)
        const double th = pi * j / rings, ph = 2 * pi * i / around;
        return glm::vec3(glm::dvec3(a * std::sin(th) * std::cos(ph),
                                    a * std::sin(th) * std::sin(ph), a * std::cos(th)));
      };
      for (int j = 0; j < rings; ++j) {
        for (int i = 0; i < around; ++i) {
          const glm::vec3 p00 = p(i, j), p10 = p(i + 1, j), p01 = p(i, j + 1),
                          p11 = p(i + 1, j + 1);
          auto tri = [&](glm::vec3 x, glm::vec3 y, glm::vec3 z) {
            const auto base = static_cast<unsigned>(m.positions_m.size());
            m.positions_m.insert(m.positions_m.end(), {x, y, z});
            m.triangles.push_back({base, base + 1, base + 2});
          };
          if (j > 0)
            tri(p00, p01, p10);  // outward: (p01-p00) x (p10-p00) points out
          if (j + 1 < rings)
            tri(p10, p01, p11);
        }
      }
      m.triangle_material.assign(m.triangles.size(), 0);
      break;
    }
    case TargetKind::kCylinder: {
      const int around = f > 0.0 ? std::max(8, divisions(2 * pi * a, f)) : 32;
      const int along = divisions(b, f);
      auto ring = [&](int i, double z) {
        const double ph = 2 * pi * i / around;
        return glm::dvec3(a * std::cos(ph), a * std::sin(ph), z);
      };
      for (int i = 0; i < around; ++i) {
        const glm::dvec3 p0 = ring(i, -b / 2), p1 = ring(i + 1, -b / 2);
        add_patch(m, p0, p1 - p0, {0, 0, b}, 1, along);  // (p1-p0) x z points outward
        // End caps as fans from the axis: bottom normal -z, top normal +z.
        const auto base = static_cast<unsigned>(m.positions_m.size());
        m.positions_m.insert(
            m.positions_m.end(),
            {glm::vec3(0, 0, -b / 2), glm::vec3(ring(i + 1, -b / 2)), glm::vec3(ring(i, -b / 2)),
             glm::vec3(0, 0, b / 2), glm::vec3(ring(i, b / 2)), glm::vec3(ring(i + 1, b / 2))});
        m.triangles.push_back({base, base + 1, base + 2});
        m.triangles.push_back({base + 3, base + 4, base + 5});
      }
      m.triangle_material.assign(m.triangles.size(), 0);
      break;
    }
    case TargetKind::kVehicle:
      make_vehicle(m, a, b, c, f > 0.0 ? f : a / 58.0);
      break;
    case TargetKind::kTruck:
      make_truck(m, a, b, c, f);
      break;
    case TargetKind::kJeep:
      make_jeep(m, a, b, c, f);
      break;
    case TargetKind::kHelicopter:
      make_helicopter(m, a, b, c, f);
      break;
    case TargetKind::kTransportAircraft:
      make_transport_aircraft(m, a, b, c, f);
      break;
    case TargetKind::kBox: {
      const glm::dvec3 lo(-a / 2, -b / 2, -c / 2);
      const int na = divisions(a, f), nb = divisions(b, f), nc = divisions(c, f);
      add_patch(m, lo, {0, b, 0}, {a, 0, 0}, nb, na);                        // -z
      add_patch(m, lo + glm::dvec3(0, 0, c), {a, 0, 0}, {0, b, 0}, na, nb);  // +z
      add_patch(m, lo, {a, 0, 0}, {0, 0, c}, na, nc);                        // -y
      add_patch(m, lo + glm::dvec3(0, b, 0), {0, 0, c}, {a, 0, 0}, nc, na);  // +y
      add_patch(m, lo, {0, 0, c}, {0, b, 0}, nc, nb);                        // -x
      add_patch(m, lo + glm::dvec3(a, 0, 0), {0, b, 0}, {0, 0, c}, nb, nc);  // +x
      break;
    }
  }
  SceneDescription d;
  d.materials = {{"metal", {0.75f, 0.75f, 0.8f}}};
  d.objects.push_back(
      {std::string(target_name(t.kind)), std::move(m), glm::dmat4(1.0), std::nullopt});
  return d;
}

double target_triangle_estimate(const TargetSpec& t) {
  require(t.a_m, "a_m");
  require(t.b_m, "b_m");
  require(t.c_m, "c_m");
  require(t.facet_m, "facet_m", true);
  const double a = t.a_m, b = t.b_m, c = t.c_m, f = t.facet_m;
  const double pi = std::numbers::pi;
  // divisions() in doubles: no overflow whatever the facet size.
  auto div = [f](double length_m) {
    return f <= 0.0 ? 1.0 : std::max(1.0, std::ceil(length_m / f - 1e-9));
  };
  // The lofted kinds: coarse count + k S / f^2 (S = 2 (ab + bc + ca)), k fitted per kind on the
  // counts at facet_m = 0.05 m for the example sizes in targets.hpp.
  auto lofted = [&](double coarse, double k, double facet_m) {
    const double s = 2.0 * (a * b + b * c + c * a);
    return facet_m > 0.0 ? coarse + k * s / (facet_m * facet_m) : coarse;
  };
  switch (t.kind) {
    case TargetKind::kPlate:
      return 2.0 * div(a) * div(b);
    case TargetKind::kDihedral:
      return 4.0 * div(a) * div(b);
    case TargetKind::kTrihedralSquare:
      return 6.0 * div(a) * div(a);
    case TargetKind::kTrihedralTriangular:
      return 3.0 * div(a) * div(a);
    case TargetKind::kSphere: {
      const double around = f > 0.0 ? std::max(8.0, div(2 * pi * a)) : 32.0;
      const double rings = std::max(4.0, std::floor(around / 2.0));
      return around * (2.0 * rings - 2.0);
    }
    case TargetKind::kCylinder: {
      const double around = f > 0.0 ? std::max(8.0, div(2 * pi * a)) : 32.0;
      return around * (2.0 * div(b) + 2.0);
    }
    case TargetKind::kBox:
      return 4.0 * (div(a) * div(b) + div(a) * div(c) + div(b) * div(c));
    case TargetKind::kVehicle:
      return lofted(1000.0, 3.44, f > 0.0 ? f : a / 58.0);
    case TargetKind::kTruck:
      return lofted(436.0, 3.56, f);
    case TargetKind::kJeep:
      return lofted(292.0, 5.2, f);
    case TargetKind::kHelicopter:
      return lofted(512.0, 0.58, f);
    case TargetKind::kTransportAircraft:
      return lofted(896.0, 0.71, f);
  }
  return 0.0;
}

std::size_t write_target_file(const TargetSpec& spec, const std::filesystem::path& path) {
  const SceneDescription desc = make_target(spec);
  const std::string ext = common::lower_extension(path);
  if (ext == ".glb" || ext == ".gltf")
    write_gltf(desc, path);
  else
    write_mesh_file(desc.objects[0].mesh, desc.materials, path);
  return desc.objects[0].mesh.triangles.size();
}

}  // namespace radar_emu::scene
