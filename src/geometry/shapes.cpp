#include "geometry/shapes.h"

namespace caustica {

void TriangleMesh::transform(const Transform& t) {
  for (Vec3& p : positions) p = t.point(p);
  for (Vec3& n : normals) {
    n = t.normal(n);
    const float len = length(n);
    if (len > 0) n = n / len;
  }
  if (t.swaps_handedness()) reverse_orientation = !reverse_orientation;
}

void TriangleMesh::flip_orientation() {
  reverse_orientation = !reverse_orientation;
  for (Vec3& n : normals) n = -n;
}

Vec3 TriangleMesh::face_normal(size_t i) const {
  const Vec3 p0 = positions[indices[3 * i]], p1 = positions[indices[3 * i + 1]],
             p2 = positions[indices[3 * i + 2]];
  Vec3 n = cross(p1 - p0, p2 - p0);
  const float len = length(n);
  if (len == 0) return {0, 0, 1};
  n = n / len;
  if (!normals.empty()) {
    // pbrt-v4: the shading normals are authoritative for the side of the surface.
    const Vec3 ns =
        normals[indices[3 * i]] + normals[indices[3 * i + 1]] + normals[indices[3 * i + 2]];
    return face_forward(n, ns);
  }
  return reverse_orientation ? -n : n;
}

float TriangleMesh::area(size_t i) const {
  const Vec3 p0 = positions[indices[3 * i]], p1 = positions[indices[3 * i + 1]],
             p2 = positions[indices[3 * i + 2]];
  return 0.5f * length(cross(p1 - p0, p2 - p0));
}

}  // namespace caustica
