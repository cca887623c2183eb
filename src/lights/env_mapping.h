// Parameterisations of the sphere of directions used by environment maps. Both map a unit
// direction to image coordinates uv in [0,1]^2 with u to the right (column) and v down (row;
// v = 0 is the top row of an Image as read from a file).
#pragma once

#include "core/vec.h"

namespace caustica {

// Clarberg 2008, "Fast Equal-Area Mapping of the (Hemi)Sphere using SIMD", as pbrt-v4's
// EqualAreaSquareToSphere / EqualAreaSphereToSquare (same orientation: the square's centre is
// +z, its corners -z, u grows with +x and v with +y). The Jacobian is constant:
// d omega = 4 pi du dv.
Vec3 equal_area_square_to_sphere(Vec2 uv);
Vec2 equal_area_sphere_to_square(Vec3 d);

// Equirectangular: u = phi / 2pi with phi = atan2(y, x) in [0, 2pi), v = theta / pi with theta
// measured from +z (v = 0 is +z). d omega = 2 pi^2 sin(theta) du dv.
Vec3 lat_long_to_sphere(Vec2 uv);
Vec2 lat_long_from_sphere(Vec3 d);

}  // namespace caustica
