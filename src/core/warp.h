// Sample warps: maps from [0,1)^2 to domains, each with its density (solid angle for
// directions, area for points, barycentric for triangles).
#pragma once

#include "core/vec.h"

namespace caustica {

// Shirley-Chiu concentric map to the unit disk; pdf = 1/pi.
Vec2 sample_uniform_disk_concentric(Vec2 u);

// Cosine-weighted hemisphere around +z; pdf = cos(theta)/pi.
Vec3 sample_cosine_hemisphere(Vec2 u);
inline float cosine_hemisphere_pdf(float cos_theta) {
  return cos_theta > 0 ? cos_theta * kInvPi : 0.f;
}

Vec3 sample_uniform_hemisphere(Vec2 u);
inline float uniform_hemisphere_pdf() { return kInv2Pi; }

Vec3 sample_uniform_sphere(Vec2 u);
inline float uniform_sphere_pdf() { return kInv4Pi; }

// Uniform over the cone of directions around +z with cos(theta) >= cos_max.
Vec3 sample_uniform_cone(Vec2 u, float cos_max);
inline float uniform_cone_pdf(float cos_max) { return 1.f / (2.f * kPi * (1.f - cos_max)); }

// Uniform barycentrics (b0, b1) on a triangle, b2 = 1 - b0 - b1 (Heitz 2019, low distortion).
Vec2 sample_uniform_triangle(Vec2 u);

}  // namespace caustica
