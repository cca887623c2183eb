// pbrt-v4 shapes as object-space geometry: "trianglemesh", "plymesh", "bilinearmesh" (two
// triangles per quad), "disk" and "cylinder" (finely tessellated), "sphere" (kept exact when
// whole; partial spheres are tessellated with a warning), "loopsubdiv" (its control mesh, with
// a warning). Curves and the quadrics pbrt-v4 dropped warn once and are skipped.
#pragma once

#include <optional>
#include <string>

#include "geometry/shapes.h"
#include "io/pbrt/context.h"
#include "io/pbrt/parameters.h"

namespace caustica::pbrt {

struct ShapeGeometry {
  std::optional<TriangleMesh> mesh;    // object space
  std::optional<float> sphere_radius;  // a whole sphere at the origin
  // True for tessellated quadrics (disk, cylinder, partial sphere): pbrt-v4 computes their normal
  // in object space and flips it when the transform swaps handedness, unlike triangle meshes.
  bool quadric = false;
};

// Nothing if the shape is unsupported (warned). Throws SceneLoadError on malformed input.
std::optional<ShapeGeometry> make_shape(const std::string& type, const ParamList& params,
                                        const SourceLocation& where, LoaderContext& ctx);

// Tessellated sphere cap/wedge in object space (pbrt-v4's parameterisation), with outward
// shading normals and uv.
TriangleMesh tessellate_sphere(float radius, float z_min, float z_max, float phi_max_degrees);

}  // namespace caustica::pbrt
