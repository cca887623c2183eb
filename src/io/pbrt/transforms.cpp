#include "io/pbrt/transforms.h"

#include <cmath>
#include <limits>

namespace caustica::pbrt {

Transform make_transform(const Mat4& m) {
  Mat4 inv;
  if (m.inverse(&inv)) return Transform(m, inv);
  for (auto& row : inv.m) row.fill(std::numeric_limits<float>::quiet_NaN());
  return Transform(m, inv);
}

bool is_invertible(const Transform& t) {
  for (const auto& row : t.inverse_matrix().m)
    for (float v : row)
      if (!std::isfinite(v)) return false;
  for (const auto& row : t.matrix().m)
    for (float v : row)
      if (!std::isfinite(v)) return false;
  return true;
}

std::optional<float> similarity_scale(const Transform& t) {
  const Mat4& m = t.matrix();
  if (m(3, 0) != 0 || m(3, 1) != 0 || m(3, 2) != 0 || m(3, 3) != 1) return std::nullopt;
  Vec3 c[3];
  for (int j = 0; j < 3; ++j) c[j] = Vec3(m(0, j), m(1, j), m(2, j));
  const float s = length(c[0]);
  if (!(s > 0) || !std::isfinite(s)) return std::nullopt;
  const float tol = 1e-4f;
  for (int j = 1; j < 3; ++j)
    if (std::abs(length(c[j]) - s) > tol * s) return std::nullopt;
  if (std::abs(dot(c[0], c[1])) > tol * s * s || std::abs(dot(c[0], c[2])) > tol * s * s ||
      std::abs(dot(c[1], c[2])) > tol * s * s)
    return std::nullopt;
  return s;
}

}  // namespace caustica::pbrt
