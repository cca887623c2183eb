// Hands the recorded shapes to the builder once the file is read: spheres stay exact under a
// similarity transform, everything else becomes a world-space triangle mesh; emitters get
// their radiance, rescaled where AreaLightSource gave "power".
#include <cmath>

#include "io/pbrt/scene_converter.h"
#include "io/pbrt/transforms.h"
#include "lights/light_power.h"

namespace caustica::pbrt {

namespace {

// "power" spread over a tiny area can overflow; the light's power (and the light selection
// distribution) would then be infinite or NaN at render time.
void check_area_emission(Rgb radiance, const AreaLightDesc& light) {
  if (!radiance.is_finite())
    throw SceneLoadError(light.where,
                         "\"power\" over the area of a shape makes its radiance overflow to "
                         "infinity");
}

}  // namespace

void SceneConverter::emit_shape(const ShapeRecord& r) {
  MaterialPtr m = material(r.material);
  const MediumInterface media = medium_interface_of(r.media);
  if (!m && !media.transition()) return;  // "interface" that bounds no medium: nothing to see
  const ShapeGeometry& g = *r.geometry;
  const Transform& t = r.object_to_world;
  if (!is_invertible(t)) {
    ctx_.warnings.warn(r.where, "shape with a singular transformation skipped", "singular shape");
    return;
  }
  if (!g.sphere_radius) {
    emit_mesh(r, *g.mesh, g.quadric, m, media);
    return;
  }
  // An alpha mask is a filter on triangles: a masked sphere is tessellated, with its uv.
  if (std::optional<float> s = r.alpha ? std::nullopt : similarity_scale(t)) {
    Sphere sphere;
    sphere.center = t.point({0, 0, 0});
    sphere.radius = *g.sphere_radius * *s;
    // pbrt-v4 flips a quadric's normal when its transform swaps handedness.
    sphere.reverse_orientation = r.reverse_orientation != t.swaps_handedness();
    emit_sphere(r, sphere, m, media);
    return;
  }
  if (!r.alpha)
    ctx_.warnings.warn(r.where,
                       "sphere under a non-uniform scale or shear is tessellated into triangles",
                       "tessellated sphere");
  emit_mesh(r, tessellate_sphere(*g.sphere_radius, -*g.sphere_radius, *g.sphere_radius, 360), true,
            m, media);
}

void SceneConverter::emit_sphere(const ShapeRecord& r, const Sphere& sphere, const MaterialPtr& m,
                                 MediumInterface media) {
  if (!is_finite(sphere.center) || !std::isfinite(sphere.radius)) {
    ctx_.warnings.warn(r.where, "shape with non-finite coordinates skipped", "non-finite shape");
    return;
  }
  AreaEmission e;
  if (r.emission) {
    e.radiance = r.emission->radiance;
    e.two_sided = r.emission->two_sided;
    if (r.emission->power > 0) {
      const float area = 4 * kPi * sqr(sphere.radius);
      e.radiance = e.radiance *
                   (r.emission->power / diffuse_area_light_power_per_radiance(area, e.two_sided));
    }
    check_area_emission(e.radiance, *r.emission);
  }
  builder_.add_sphere(sphere, m, r.emission ? &e : nullptr, media);
}

// `mesh` is in object space; a quadric's is flipped like the sphere's normal above.
void SceneConverter::emit_mesh(const ShapeRecord& r, TriangleMesh mesh, bool quadric,
                               const MaterialPtr& m, MediumInterface media) {
  if (mesh.indices.empty()) return;
  const Transform& t = r.object_to_world;
  mesh.transform(t);
  if (r.reverse_orientation) mesh.flip_orientation();
  if (quadric && t.swaps_handedness()) mesh.flip_orientation();
  for (const Vec3& p : mesh.positions)
    if (!is_finite(p)) {
      ctx_.warnings.warn(r.where, "shape with non-finite coordinates skipped", "non-finite shape");
      return;
    }
  if (!r.emission) {
    builder_.add_mesh(std::move(mesh), m, nullptr, media, r.alpha);
    return;
  }
  AreaEmission e{r.emission->radiance, r.emission->two_sided};
  if (r.emission->power <= 0) {
    builder_.add_mesh(std::move(mesh), m, &e, media, r.alpha);
    return;
  }
  // pbrt-v4 gives "power" to each shape, and each triangle is a shape: one mesh per triangle.
  for (size_t i = 0; i < mesh.triangle_count(); ++i) {
    TriangleMesh tri;
    for (int k = 0; k < 3; ++k) {
      const uint32_t v = mesh.indices[3 * i + k];
      tri.positions.push_back(mesh.positions[v]);
      if (!mesh.normals.empty()) tri.normals.push_back(mesh.normals[v]);
      if (!mesh.uvs.empty()) tri.uvs.push_back(mesh.uvs[v]);
      tri.indices.push_back(uint32_t(k));
    }
    tri.reverse_orientation = mesh.reverse_orientation;
    const float area = tri.area(0);
    AreaEmission ei = e;
    ei.radiance = area > 0 ? e.radiance * (r.emission->power /
                                           diffuse_area_light_power_per_radiance(area, e.two_sided))
                           : Rgb(0.f);
    check_area_emission(ei.radiance, *r.emission);
    builder_.add_mesh(std::move(tri), m, &ei, media, r.alpha);
  }
}

}  // namespace caustica::pbrt
