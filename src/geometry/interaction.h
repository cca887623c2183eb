// The record of a ray hitting a surface, and robust spawning of rays from it.
#pragma once

#include <cstdint>

#include "core/frame.h"
#include "core/vec.h"
#include "geometry/medium.h"

namespace caustica {

class Material;
class Light;

struct SurfaceInteraction {
  Vec3 p;         // hit position (recomputed from the primitive, not o + t d)
  Vec3 p_error;   // conservative absolute error bound on p, per axis
  Vec3 ng;        // unit geometric normal: winding normal cross(p1-p0, p2-p0) for triangles
                  // (flipped by ReverseOrientation / handedness; faced toward the shading
                  // normal when the mesh has normals), outward for spheres
  Frame shading;  // shading frame; shading.n is the interpolated normal (ng if none)
  Vec2 uv;        // surface parameterisation (mesh uv, or sphere phi/theta)
  // dp/du and dp/dv of the shading geometry (pbrt-v4's shading.dpdu / dpdv): with per-vertex
  // normals the uv tangent made perpendicular to the shading normal and cross(n, it), else the
  // geometric derivatives. Bump mapping (materials/bump_mapped.cpp) displaces along them.
  Vec3 dpdu, dpdv;
  Vec3 wo;                            // unit direction back toward the ray origin
  float t = 0;                        // ray parameter of the hit
  uint32_t geom_id = 0, prim_id = 0;  // Embree ids, for debugging and stored light vertices
  // The Embree instance (its geometry id in the top-level scene) of a hit on an instanced
  // object, whose geom_id and prim_id are then those in the object's own Embree scene.
  uint32_t inst_id = kNoInstance;
  static constexpr uint32_t kNoInstance = 0xffffffffu;
  const Material* material = nullptr;  // may be null: an interface only (no scattering)
  const Light* area_light = nullptr;   // the emitter of this primitive, if any
  MediumInterface media;               // the media this primitive separates (medium.h)

  // This end of a segment leaving along w, as far as media go (medium.h).
  SegmentEnd medium_toward(Vec3 w) const { return segment_end(media, ng, w); }

  // Ray origin nudged off the surface along ng, to the side of w (pbrt-v4's OffsetRayOrigin).
  Vec3 offset_origin(Vec3 w) const {
    // The error bound is exactly 0 for a point on an axis-aligned plane through 0 (all
    // coordinates along the normal are 0): the origin would stay on the plane and Embree,
    // which accepts t >= tnear = 0, would report the surface itself. A tiny absolute floor puts
    // the origin strictly on the side of w in that case and is negligible otherwise.
    const float d = dot(abs(ng), p_error) + 1e-9f;
    Vec3 offset = ng * d;
    if (dot(w, ng) < 0) offset = -offset;
    Vec3 po = p + offset;
    for (int i = 0; i < 3; ++i) {  // round away from p so the offset is never lost
      if (offset[i] > 0)
        po[i] = next_float_up(po[i]);
      else if (offset[i] < 0)
        po[i] = next_float_down(po[i]);
    }
    return po;
  }
  Ray spawn_ray(Vec3 d) const { return {offset_origin(d), d, kInfinity}; }
  // Ray toward `target`, stopping just short of it (for shadow rays to a point).
  Ray spawn_ray_to(Vec3 target) const {
    const Vec3 o = offset_origin(target - p);
    const Vec3 d = target - o;
    return {o, d, 1.f - 1e-4f};
  }
};

// Segment between two surface points, each end offset off its own surface.
inline Ray spawn_ray_between(const SurfaceInteraction& a, const SurfaceInteraction& b) {
  const Vec3 pa = a.offset_origin(b.p - a.p);
  const Vec3 pb = b.offset_origin(pa - b.p);
  return {pa, pb - pa, 1.f - 1e-4f};
}

}  // namespace caustica
