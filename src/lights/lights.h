// Factories for every light model; the classes stay private to lights/*.cpp.
// Radiance / intensity values are linear RGB as they should appear in the image (the pbrt
// loader applies pbrt-v4's photometric normalisation before calling these).
#pragma once

#include <memory>

#include "core/transform.h"
#include "geometry/shapes.h"
#include "lights/light.h"

namespace caustica {

class Image;

// Diffuse emitter on triangle `tri` of a world-space mesh: emits `radiance` on the side of
// mesh.face_normal(tri), or both sides if two_sided.
LightPtr make_triangle_area_light(const TriangleMesh& mesh, size_t tri, Rgb radiance,
                                  bool two_sided);
// Diffuse emitter on a sphere: emits on the outside (inside if reverse_orientation).
LightPtr make_sphere_area_light(const Sphere& sphere, Rgb radiance, bool two_sided);

LightPtr make_point_light(Vec3 position, Rgb intensity);
// pbrt-v4 spot: full intensity inside cone_angle - cone_delta, smoothstep falloff to cone_angle.
LightPtr make_spot_light(Vec3 position, Vec3 direction, Rgb intensity, float cone_angle_degrees,
                         float cone_delta_degrees);
// Parallel light travelling along `direction` (pbrt "distant": to - from) with radiance.
LightPtr make_distant_light(Vec3 direction, Rgb radiance);

LightPtr make_uniform_environment(Rgb radiance);

enum class EnvironmentMapping {
  EqualAreaOctahedral,  // pbrt-v4's square equal-area map (Clarberg 2008)
  LatLong,              // equirectangular: u = phi / 2pi, v = theta / pi (row 0 = +z up)
};
// Image-based environment, importance sampled by its luminance. light_to_world orients it
// (pbrt's transform before LightSource); `scale` multiplies the texels.
LightPtr make_image_environment(std::shared_ptr<const Image> image, EnvironmentMapping mapping,
                                const Transform& light_to_world, Rgb scale = Rgb(1.f));

}  // namespace caustica
