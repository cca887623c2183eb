#include "core/warp.h"

#include <cmath>

namespace caustica {

Vec2 sample_uniform_disk_concentric(Vec2 u) {
  const float ox = 2.f * u.x - 1.f, oy = 2.f * u.y - 1.f;
  if (ox == 0 && oy == 0) return {0, 0};
  float r, theta;
  if (std::abs(ox) > std::abs(oy)) {
    r = ox;
    theta = (kPi / 4) * (oy / ox);
  } else {
    r = oy;
    theta = kPi / 2 - (kPi / 4) * (ox / oy);
  }
  return {r * std::cos(theta), r * std::sin(theta)};
}

Vec3 sample_cosine_hemisphere(Vec2 u) {
  const Vec2 d = sample_uniform_disk_concentric(u);
  const float z = safe_sqrt(1.f - d.x * d.x - d.y * d.y);
  return {d.x, d.y, z};
}

Vec3 sample_uniform_hemisphere(Vec2 u) {
  const float z = u.x;
  const float r = safe_sqrt(1.f - z * z);
  const float phi = 2 * kPi * u.y;
  return {r * std::cos(phi), r * std::sin(phi), z};
}

Vec3 sample_uniform_sphere(Vec2 u) {
  const float z = 1.f - 2.f * u.x;
  const float r = safe_sqrt(1.f - z * z);
  const float phi = 2 * kPi * u.y;
  return {r * std::cos(phi), r * std::sin(phi), z};
}

Vec3 sample_uniform_cone(Vec2 u, float cos_max) {
  const float cos_theta = (1.f - u.x) + u.x * cos_max;
  const float sin_theta = safe_sqrt(1.f - cos_theta * cos_theta);
  const float phi = u.y * 2 * kPi;
  return {std::cos(phi) * sin_theta, std::sin(phi) * sin_theta, cos_theta};
}

Vec2 sample_uniform_triangle(Vec2 u) {
  float b0, b1;
  if (u.x < u.y) {
    b0 = u.x / 2;
    b1 = u.y - b0;
  } else {
    b1 = u.y / 2;
    b0 = u.x - b1;
  }
  return {b0, b1};
}

}  // namespace caustica
