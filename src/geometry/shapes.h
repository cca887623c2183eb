// Geometry as the scene stores it: triangle meshes and exact analytic spheres, in world space.
#pragma once

#include <cstdint>
#include <memory>
#include <vector>

#include "core/rgb.h"
#include "core/transform.h"
#include "core/vec.h"

namespace caustica {

class Material;
class Light;

struct TriangleMesh {
  std::vector<Vec3> positions;
  std::vector<Vec3> normals;      // optional: per-vertex shading normals (empty if none)
  std::vector<Vec2> uvs;          // optional: per-vertex uv (empty: (0,0),(1,0),(1,1) per triangle)
  std::vector<uint32_t> indices;  // 3 per triangle
  // Which side is "outside" when there are no shading normals: false = the winding normal
  // cross(p1 - p0, p2 - p0). Loaders call flip_orientation() for pbrt's ReverseOrientation;
  // transform() toggles it when the transform swaps handedness (as pbrt-v4 does).
  bool reverse_orientation = false;

  size_t triangle_count() const { return indices.size() / 3; }
  void transform(const Transform& t);  // object to world
  void flip_orientation();             // ReverseOrientation: flips the flag and the normals
  // Geometric normal of triangle i as pbrt-v4 orients it: the winding normal, faced toward
  // the shading normals when there are some, else flipped if reverse_orientation.
  Vec3 face_normal(size_t i) const;
  float area(size_t i) const;
};

struct Sphere {
  Vec3 center;
  float radius = 1;
  bool reverse_orientation = false;  // normals point inward (pbrt ReverseOrientation)
};

// What one shape contributes to a scene: the geometry, its material and, if emissive,
// the parameters of its diffuse area light (one light per triangle, as pbrt-v4).
struct AreaEmission {
  Rgb radiance;
  bool two_sided = false;
};

}  // namespace caustica
