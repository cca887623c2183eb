#include "lights/env_mapping.h"

#include <cmath>

namespace caustica {

// The square [-1,1]^2 is split by its inscribed diamond |u| + |v| = 1: inside is the upper
// hemisphere, the four corner triangles fold onto the lower one. r (distance from the centre
// in the L1 sense, mirrored outside the diamond) gives z = +-(1 - r^2); the position along the
// diamond's edge gives phi, linearly (that linearity is what makes the map equal-area).
Vec3 equal_area_square_to_sphere(Vec2 uv) {
  const float u = 2 * uv.x - 1, v = 2 * uv.y - 1;
  const float au = std::abs(u), av = std::abs(v);
  const float signed_distance = 1 - (au + av);  // > 0 inside the diamond (upper hemisphere)
  const float r = 1 - std::abs(signed_distance);
  const float phi = (r == 0 ? 1 : (av - au) / r + 1) * (kPi / 4);  // in [0, pi/2]
  const float z = std::copysign(1 - r * r, signed_distance);
  const float sin_theta_scale = r * safe_sqrt(2 - r * r);
  return {std::copysign(std::cos(phi), u) * sin_theta_scale,
          std::copysign(std::sin(phi), v) * sin_theta_scale, z};
}

Vec2 equal_area_sphere_to_square(Vec3 d) {
  const float ax = std::abs(d.x), ay = std::abs(d.y), az = std::abs(d.z);
  const float r = safe_sqrt(1 - az);
  // Angle within the quadrant as a fraction of pi/2 (pbrt-v4 uses a polynomial for atan; the
  // exact form keeps the round trip tight).
  const float phi = (ax == 0 && ay == 0) ? 0.f : std::atan2(ay, ax) * (2 * kInvPi);
  float v = phi * r;
  float u = r - v;
  if (d.z < 0) {  // lower hemisphere: mirror across the diamond's edge
    const float t = u;
    u = 1 - v;
    v = 1 - t;
  }
  u = std::copysign(u, d.x);
  v = std::copysign(v, d.y);
  return {0.5f * (u + 1), 0.5f * (v + 1)};
}

Vec3 lat_long_to_sphere(Vec2 uv) {
  const float phi = uv.x * 2 * kPi, theta = uv.y * kPi;
  const float s = std::sin(theta);
  return {s * std::cos(phi), s * std::sin(phi), std::cos(theta)};
}

Vec2 lat_long_from_sphere(Vec3 d) {
  const float theta = safe_acos(d.z);
  float phi = std::atan2(d.y, d.x);
  if (phi < 0) phi += 2 * kPi;
  return {phi * kInv2Pi, theta * kInvPi};
}

}  // namespace caustica
