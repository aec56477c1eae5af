#include "scene/targets.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <numbers>
#include <stdexcept>
#include <vector>

namespace radar_emu::scene {

namespace {

constexpr std::array<std::pair<TargetKind, std::string_view>, 8> kNames{{
    {TargetKind::kPlate, "plate"},
    {TargetKind::kDihedral, "dihedral"},
    {TargetKind::kTrihedralSquare, "trihedral-square"},
    {TargetKind::kTrihedralTriangular, "trihedral-tri"},
    {TargetKind::kSphere, "sphere"},
    {TargetKind::kCylinder, "cylinder"},
    {TargetKind::kBox, "box"},
    {TargetKind::kVehicle, "vehicle"},
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

}  // namespace radar_emu::scene
