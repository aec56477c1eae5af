#include "scene/targets.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <numbers>
#include <stdexcept>

namespace radar_emu::scene {

namespace {

constexpr std::array<std::pair<TargetKind, std::string_view>, 7> kNames{{
    {TargetKind::kPlate, "plate"},
    {TargetKind::kDihedral, "dihedral"},
    {TargetKind::kTrihedralSquare, "trihedral-square"},
    {TargetKind::kTrihedralTriangular, "trihedral-tri"},
    {TargetKind::kSphere, "sphere"},
    {TargetKind::kCylinder, "cylinder"},
    {TargetKind::kBox, "box"},
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

// Right isosceles triangle (0, u, v) subdivided into n^2 similar triangles, normal u x v.
void add_triangle(Mesh& m, glm::dvec3 u, glm::dvec3 v, int n) {
  auto p = [&](int i, int j) {
    return glm::vec3(u * (static_cast<double>(i) / n) + v * (static_cast<double>(j) / n));
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
      add_triangle(m, {a, 0, 0}, {0, a, 0}, n);
      add_triangle(m, {0, a, 0}, {0, 0, a}, n);
      add_triangle(m, {0, 0, a}, {a, 0, 0}, n);
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
