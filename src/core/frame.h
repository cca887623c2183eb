// Orthonormal frames. A shading frame has z = normal; BSDFs work in it (cos theta = w.z).
#pragma once

#include "core/vec.h"

namespace caustica {

struct Frame {
  Vec3 s{1, 0, 0}, t{0, 1, 0}, n{0, 0, 1};

  Frame() = default;
  Frame(Vec3 s_, Vec3 t_, Vec3 n_) : s(s_), t(t_), n(n_) {}

  // Duff et al. 2017, "Building an Orthonormal Basis, Revisited": branchless and continuous
  // except at n.z = -1.
  static Frame from_normal(Vec3 n) {
    const float sign = std::copysign(1.f, n.z);
    const float a = -1.f / (sign + n.z);
    const float b = n.x * n.y * a;
    return Frame(Vec3(1.f + sign * n.x * n.x * a, sign * b, -sign * n.x),
                 Vec3(b, sign + n.y * n.y * a, -n.y), n);
  }
  // Frame with normal n whose s axis follows the projection of dpdu onto the tangent plane.
  static Frame from_normal_tangent(Vec3 n, Vec3 dpdu) {
    Vec3 s = dpdu - n * dot(n, dpdu);
    const float len2 = length_squared(s);
    if (!(len2 > 1e-12f)) return from_normal(n);
    s = s / std::sqrt(len2);
    return Frame(s, cross(n, s), n);
  }

  Vec3 to_local(Vec3 v) const { return {dot(v, s), dot(v, t), dot(v, n)}; }
  Vec3 to_world(Vec3 v) const { return s * v.x + t * v.y + n * v.z; }
};

// Spherical-coordinate helpers for local directions (z up).
inline float cos_theta(Vec3 w) { return w.z; }
inline float abs_cos_theta(Vec3 w) { return std::abs(w.z); }
inline float cos2_theta(Vec3 w) { return w.z * w.z; }
inline float sin2_theta(Vec3 w) { return std::max(0.f, 1.f - cos2_theta(w)); }
inline float sin_theta(Vec3 w) { return std::sqrt(sin2_theta(w)); }
inline float tan2_theta(Vec3 w) { return sin2_theta(w) / cos2_theta(w); }
inline float cos_phi(Vec3 w) {
  const float st = sin_theta(w);
  return st == 0 ? 1.f : clamp(w.x / st, -1.f, 1.f);
}
inline float sin_phi(Vec3 w) {
  const float st = sin_theta(w);
  return st == 0 ? 0.f : clamp(w.y / st, -1.f, 1.f);
}
inline bool same_hemisphere(Vec3 a, Vec3 b) { return a.z * b.z > 0; }

}  // namespace caustica
