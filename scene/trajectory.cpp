#include "scene/trajectory.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <stdexcept>
#include <string>

namespace radar_emu::scene {

namespace {

const glm::dvec3 kUp(0.0, 0.0, 1.0);

[[noreturn]] void fail(const std::string& what) {
  throw std::invalid_argument("trajectory: " + what);
}

bool finite(const glm::dvec3& v) noexcept {
  return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z);
}

// Horizontal unit vector to the left of `forward` (up x forward), or `fallback` when forward is
// (nearly) vertical.
glm::dvec3 left_of(const glm::dvec3& forward, const glm::dvec3& fallback) noexcept {
  const glm::dvec3 l = glm::cross(kUp, forward);
  const double n = glm::length(l);
  return n > 1e-9 ? l / n : fallback;
}

// Rotation world from body for a body x along `forward` (unit), rolled by `roll_rad` about x.
glm::dmat3 orientation(const glm::dvec3& forward, double roll_rad,
                       const glm::dvec3& fallback_left) noexcept {
  const glm::dvec3 y0 = left_of(forward, fallback_left);
  const glm::dvec3 z0 = glm::cross(forward, y0);
  if (roll_rad == 0.0)
    return {forward, y0, z0};
  const double c = std::cos(roll_rad), s = std::sin(roll_rad);
  return {forward, c * y0 + s * z0, -s * y0 + c * z0};
}

}  // namespace

TrajectoryPath::TrajectoryPath(const Trajectory& t) : speed_mps_(t.speed_mps), loop_(t.loop) {
  const std::size_t n = t.waypoints_m.size();
  if (n < 2)
    fail("needs at least 2 waypoints, got " + std::to_string(n));
  for (std::size_t i = 0; i < n; ++i) {
    if (!finite(t.waypoints_m[i]))
      fail("waypoint " + std::to_string(i) + " is not finite");
  }
  if (!std::isfinite(t.speed_mps) || !(t.speed_mps > 0.0))
    fail("speed_mps must be a finite number > 0");
  if (!std::isfinite(t.turn_radius_m) || t.turn_radius_m < 0.0)
    fail("turn_radius_m must be a finite number >= 0");
  if (!std::isfinite(t.turn_rate_rad_s) || t.turn_rate_rad_s < 0.0)
    fail("turn_rate_rad_s must be a finite number >= 0");
  if (t.turn_radius_m > 0.0 && t.turn_rate_rad_s > 0.0)
    fail("give turn_radius_m or turn_rate_rad_s, not both");
  // Constant turn rate at constant speed: r = v / omega.
  radius_m_ = t.turn_rate_rad_s > 0.0 ? t.speed_mps / t.turn_rate_rad_s : t.turn_radius_m;
  const double r = radius_m_;

  // Legs: waypoint i to i + 1 (and the last back to the first for loops).
  const std::size_t legs = loop_ ? n : n - 1;
  std::vector<glm::dvec3> dir(legs);
  std::vector<double> len(legs);
  for (std::size_t i = 0; i < legs; ++i) {
    const glm::dvec3 d = t.waypoints_m[(i + 1) % n] - t.waypoints_m[i];
    len[i] = glm::length(d);
    if (!(len[i] > 1e-9 * (1.0 + glm::length(t.waypoints_m[i]))))
      fail("waypoints " + std::to_string(i) + " and " + std::to_string((i + 1) % n) + " coincide");
    dir[i] = d / len[i];
    if (std::hypot(dir[i].x, dir[i].y) < 1e-9)
      fail("leg " + std::to_string(i) + " is vertical (no heading)");
  }
  // Turn at waypoint j joins leg j - 1 (incoming) and leg j (outgoing); none at the ends of an
  // open path.
  struct Turn {
    double angle_rad = 0.0;
    double tangent_m = 0.0;
  };
  std::vector<Turn> turn(n);
  for (std::size_t j = 0; j < n; ++j) {
    if (!loop_ && (j == 0 || j == n - 1))
      continue;
    const glm::dvec3 din = dir[(j + legs - 1) % legs], dout = dir[j % legs];
    const double c = std::clamp(glm::dot(din, dout), -1.0, 1.0);
    turn[j].angle_rad = std::acos(c);
    if (r > 0.0 && turn[j].angle_rad > 1e-12) {
      if (c < -1.0 + 1e-12)
        fail("the path reverses at waypoint " + std::to_string(j) +
             " (a U-turn with a turn radius needs an intermediate waypoint)");
      turn[j].tangent_m = r * std::tan(0.5 * turn[j].angle_rad);
    }
  }
  for (std::size_t i = 0; i < legs; ++i) {
    const double need = turn[i].tangent_m + turn[(i + 1) % n].tangent_m;
    if (need > len[i] * (1.0 + 1e-12)) {
      fail("leg " + std::to_string(i) + " (" + std::to_string(len[i]) +
           " m) is shorter than the tangent lengths of its turns (" + std::to_string(need) +
           " m): reduce the turn radius");
    }
  }

  auto add_leg = [&](std::size_t i) {
    const std::size_t j_end = (i + 1) % n;
    TrajectorySegment s;
    s.arc = false;
    s.start_direction = dir[i];
    s.start_position_m = t.waypoints_m[i] + dir[i] * turn[i].tangent_m;
    s.length_m = std::max(0.0, len[i] - turn[i].tangent_m - turn[j_end].tangent_m);
    s.fallback_left = left_of(dir[i], {0.0, 1.0, 0.0});
    if (s.length_m > 0.0)
      segments_.push_back(s);
  };
  auto add_arc = [&](std::size_t j) {
    if (turn[j].tangent_m <= 0.0)
      return;  // straight on, or a sharp corner
    const glm::dvec3 din = dir[(j + legs - 1) % legs], dout = dir[j % legs];
    TrajectorySegment s;
    s.arc = true;
    s.radius_m = r;
    s.turn_rad = turn[j].angle_rad;
    s.length_m = r * s.turn_rad;
    s.start_direction = din;
    s.start_position_m = t.waypoints_m[j] - din * turn[j].tangent_m;
    // Inward normal: the part of d_out perpendicular to d_in.
    const glm::dvec3 inward = glm::normalize(dout - glm::dot(dout, din) * din);
    s.centre_m = s.start_position_m + r * inward;
    s.centre_to_start = -inward;
    s.fallback_left = left_of(din, {0.0, 1.0, 0.0});
    if (t.bank) {
      // Coordinated turn: tan(bank) = v^2 / (g r) (lift balances weight and centripetal force).
      // A left turn (counter-clockwise seen from above) rolls body z toward the left: negative
      // roll about body x (x forward, y left, z up).
      const double bank = std::atan(t.speed_mps * t.speed_mps / (kStandardGravity_mps2 * r));
      const bool left_turn = glm::dot(glm::cross(din, dout), kUp) > 0.0;
      s.roll_rad = left_turn ? -bank : bank;
    }
    segments_.push_back(s);
  };
  for (std::size_t i = 0; i < legs; ++i) {
    add_leg(i);
    if (loop_ || i + 1 < legs)
      add_arc((i + 1) % n);
  }
  if (segments_.empty())
    fail("has zero length");
  double s0 = 0.0;
  starts_m_.reserve(segments_.size());
  for (TrajectorySegment& s : segments_) {
    s.start_m = s0;
    starts_m_.push_back(s0);
    s0 += s.length_m;
  }
  length_m_ = s0;
}

TrajectorySample TrajectoryPath::at(double t_s) const noexcept {
  if (!std::isfinite(t_s))
    t_s = 0.0;
  double s = speed_mps_ * t_s;
  bool resting = false;
  if (loop_) {
    s = std::fmod(s, length_m_);
    if (s < 0.0)
      s += length_m_;
    if (!(s < length_m_))
      s = 0.0;
  } else if (s < 0.0) {
    s = 0.0;
    resting = true;
  } else if (s > length_m_) {
    s = length_m_;
    resting = true;
  }
  // Last piece starting at or before s.
  const auto it = std::upper_bound(starts_m_.begin(), starts_m_.end(), s);
  const std::size_t k =
      it == starts_m_.begin() ? 0 : static_cast<std::size_t>(it - starts_m_.begin()) - 1;
  const TrajectorySegment& g = segments_[k];
  const double sigma = std::clamp(s - g.start_m, 0.0, g.length_m);
  TrajectorySample out;
  out.path_m = s;
  out.segment = static_cast<std::uint32_t>(k);
  out.on_arc = g.arc;
  glm::dvec3 tangent = g.start_direction;
  if (g.arc) {
    // p = C + r (u cos phi + w sin phi), phi = sigma / r; tangent = -u sin phi + w cos phi,
    // u = centre to start, w = start tangent.
    const double phi = sigma / g.radius_m;
    const double c = std::cos(phi), sn = std::sin(phi);
    out.position_m = g.centre_m + g.radius_m * (c * g.centre_to_start + sn * g.start_direction);
    tangent = -sn * g.centre_to_start + c * g.start_direction;
  } else {
    out.position_m = g.start_position_m + sigma * g.start_direction;
  }
  out.velocity_mps = resting ? glm::dvec3(0.0) : speed_mps_ * tangent;
  out.world_from_body = orientation(tangent, g.roll_rad, g.fallback_left);
  return out;
}

}  // namespace radar_emu::scene
