// Anisotropic Trowbridge-Reitz (GGX) microfacet distribution with Smith's height-correlated
// masking-shadowing and visible-normal sampling (Heitz 2018, "Sampling the GGX Distribution of
// Visible Normals"), as pbrt-v4's TrowbridgeReitzDistribution. Private to materials/.
#pragma once

#include "core/frame.h"
#include "core/vec.h"

namespace caustica {

class TrowbridgeReitz {
 public:
  TrowbridgeReitz() = default;
  TrowbridgeReitz(float alpha_x, float alpha_y) : alpha_x_(alpha_x), alpha_y_(alpha_y) {}

  // pbrt-v4's RoughnessToAlpha: user "roughness" -> alpha.
  static float roughness_to_alpha(float roughness) { return std::sqrt(std::max(roughness, 0.f)); }

  float alpha_x() const { return alpha_x_; }
  float alpha_y() const { return alpha_y_; }
  // Below this the lobes are so narrow that they are treated as delta (specular) lobes.
  bool effectively_smooth() const { return std::max(alpha_x_, alpha_y_) < 1e-3f; }

  // Microfacet normal density D(wm) (projected-area normalised: integral of D cos = 1).
  // tan^2(theta) cos^2(phi) is x^2 / z^2 and tan^2(theta) sin^2(phi) is y^2 / z^2 for a unit
  // vector: pbrt-v4's expressions without the square root and the divisions of sin(theta).
  float D(Vec3 wm) const {
    const float cos2 = cos2_theta(wm), cos4 = sqr(cos2);
    if (cos4 < 1e-16f) return 0;  // grazing, and tan(theta) infinite at cos = 0
    const float e = (sqr(wm.x / alpha_x_) + sqr(wm.y / alpha_y_)) / cos2;
    return 1 / (kPi * alpha_x_ * alpha_y_ * cos4 * sqr(1 + e));
  }
  // Smith's auxiliary function (0 where tan(theta) is infinite, as pbrt-v4's).
  float lambda(Vec3 w) const {
    const float cos2 = cos2_theta(w);
    if (cos2 == 0) return 0;
    const float alpha2_tan2 = (sqr(w.x * alpha_x_) + sqr(w.y * alpha_y_)) / cos2;
    return (std::sqrt(1 + alpha2_tan2) - 1) / 2;
  }
  float G1(Vec3 w) const { return 1 / (1 + lambda(w)); }
  // Height-correlated masking-shadowing.
  float G(Vec3 wo, Vec3 wi) const { return 1 / (1 + lambda(wo) + lambda(wi)); }
  // Distribution of normals visible from w: G1(w) / |cos w| D(wm) |w.wm|.
  float D(Vec3 w, Vec3 wm) const { return G1(w) / abs_cos_theta(w) * D(wm) * abs_dot(w, wm); }
  float pdf(Vec3 w, Vec3 wm) const { return D(w, wm); }

  // Samples D(w, .). The normal is always in the +z hemisphere; for w below the surface it
  // is a normal visible from -w (D(w, wm) is symmetric under w -> -w).
  Vec3 sample_wm(Vec3 w, Vec2 u) const {
    // Stretch to the hemisphere configuration (alpha = 1).
    Vec3 wh = normalize(Vec3(alpha_x_ * w.x, alpha_y_ * w.y, w.z));
    if (wh.z < 0) wh = -wh;
    const Vec3 t1 = wh.z < 0.99999f ? normalize(cross(Vec3(0, 0, 1), wh)) : Vec3(1, 0, 0);
    const Vec3 t2 = cross(wh, t1);
    // Uniform disk point (polar map), warped to the projected visible hemisphere.
    const float r = std::sqrt(u.x), phi = 2 * kPi * u.y;
    float px = r * std::cos(phi), py = r * std::sin(phi);
    const float h = std::sqrt(std::max(0.f, 1 - px * px));
    py = lerp((1 + wh.z) / 2, h, py);
    const float pz = std::sqrt(std::max(0.f, 1 - px * px - py * py));
    const Vec3 nh = px * t1 + py * t2 + pz * wh;
    return normalize(Vec3(alpha_x_ * nh.x, alpha_y_ * nh.y, std::max(1e-6f, nh.z)));
  }

 private:
  float alpha_x_ = 0, alpha_y_ = 0;
};

}  // namespace caustica
