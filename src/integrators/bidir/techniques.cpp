#include "integrators/bidir/techniques.h"

#include "geometry/camera.h"
#include "lights/light.h"

namespace caustica::bidir {

float camera_pdf_w(const Camera& camera, Vec3 p_lens, Vec3 dir, float raster_density) {
  float pdf_pos, pdf_dir;
  camera.pdf_we(p_lens, dir, &pdf_pos, &pdf_dir);
  // pdf_we is normalised over the whole image, a raster density of 1 / pixel_count; one camera
  // sample per pixel has the filter's raster density instead, pixel_count * raster_density times
  // as much.
  return float(camera.pixel_count()) * pdf_dir * raster_density;
}

MisSums light_subpath_start(const MisRules& rules, const Light& light, float pmf,
                            const LightLeSample& le, const SurfaceInteraction& y1, float dist) {
  const bool finite = !light.is_infinite();
  const float dist2 = dist * dist;
  float direct;
  if (light.is_delta()) {
    direct = pmf;  // a point or a direction is chosen with probability one (tech. rep. 5.1)
  } else if (finite) {
    direct = pmf * light.pdf_li(y1.p, -le.dir, le.p, le.n) * le.cos_at_light / dist2;
  } else {
    direct = pmf * light.pdf_li(y1.p, -le.dir, {}, {});
  }
  const float emission = pmf * le.pdf_pos * le.pdf_dir;
  return rules.light_first_hit(direct, emission, le.cos_at_light, light.is_delta(), finite, dist2,
                               geometric_cos(y1, le.dir));
}

void scatter_update(const MisRules& rules, MisSums& mis, const SurfaceInteraction& si,
                    const Bsdf& bsdf, Vec3 wo, Vec3 wi, TransportMode mode, bool specular,
                    float pdf_fwd, const VertexGuides& guides) {
  // Without light-subpath techniques the reverse density meets only counts of zero: the weights
  // are the same bit for bit without evaluating it (a random walk for a layered BSDF).
  const float pdf_rev = specular                       ? pdf_fwd
                        : !rules.uses_light_subpaths() ? 0.f
                                                       : direction_pdf(bsdf, guides, wi, wo, !mode);
  rules.scatter(mis, geometric_cos(si, wi), pdf_fwd, pdf_rev, specular);
}

TechniqueTerms terms_emitter_hit(const MisRules& rules, const Light& light, float pmf, Vec3 prev_p,
                                 Vec3 dir, const SurfaceInteraction* hit, const MisSums& camera,
                                 float nee_probability) {
  float pdf_pos = 0, pdf_dir = 0, direct;
  if (hit) {
    light.pdf_le(hit->p, hit->ng, hit->wo, &pdf_pos, &pdf_dir);
    direct = pmf * light.pdf_li(prev_p, dir, hit->p, hit->ng) * geometric_cos(*hit, dir) /
             distance_squared(prev_p, hit->p);
  } else {
    light.pdf_le({}, {}, -dir, &pdf_pos, &pdf_dir);
    direct = pmf * light.pdf_li(prev_p, dir, {}, {});
  }
  return rules.hit_light(camera, direct, pmf * pdf_pos * pdf_dir, nee_probability);
}

TechniqueTerms terms_light_seen_from_lens(const MisRules& rules, const Light& light, float pmf,
                                          const SurfaceInteraction& hit, const MisSums& camera) {
  float pdf_pos = 0, pdf_dir = 0;
  light.pdf_le(hit.p, hit.ng, hit.wo, &pdf_pos, &pdf_dir);
  return rules.hit_light_from_lens(camera, pmf * pdf_pos);
}

TechniqueTerms terms_next_event(const MisRules& rules, const Light& light, float pmf,
                                const LightLiSample& ls, const SurfaceInteraction& si,
                                const Bsdf& bsdf, const MisSums& camera,
                                const VertexGuides& guides) {
  const float bsdf_fwd =
      light.is_delta() ? 0.f : direction_pdf(bsdf, guides, si.wo, ls.wi, TransportMode::Radiance);
  const float bsdf_rev = rules.uses_light_subpaths()
                             ? direction_pdf(bsdf, guides, ls.wi, si.wo, TransportMode::Importance)
                             : 0.f;
  // Delta positions have area density 1: in solid angle at si that is dist^2.
  const float direct_w =
      pmf * (light.type() == LightType::DeltaPosition ? ls.distance * ls.distance : ls.pdf_w);
  const float emission_w = pmf * ls.pdf_emit_pos * ls.pdf_emit_dir;
  return rules.next_event(camera, bsdf_fwd, bsdf_rev, direct_w, emission_w,
                          geometric_cos(si, ls.wi), ls.cos_at_light);
}

TechniqueTerms terms_connection(const MisRules& rules, const SurfaceInteraction& light_si,
                                const Bsdf& light_bsdf, Vec3 light_wo, const MisSums& light,
                                const SurfaceInteraction& camera_si, const Bsdf& camera_bsdf,
                                const MisSums& camera, const VertexGuides& light_guides,
                                const VertexGuides& camera_guides) {
  const Vec3 d = light_si.p - camera_si.p;
  const float dist2 = length_squared(d);
  const Vec3 dir = d / std::sqrt(dist2);  // camera vertex -> light vertex
  const VertexGuides& cg = camera_guides;
  const VertexGuides& lg = light_guides;
  const float camera_pdf_a =
      direction_pdf(camera_bsdf, cg, camera_si.wo, dir, TransportMode::Radiance) *
      geometric_cos(light_si, dir) / dist2;
  const float camera_rev =
      direction_pdf(camera_bsdf, cg, dir, camera_si.wo, TransportMode::Importance);
  const float light_pdf_a =
      direction_pdf(light_bsdf, lg, light_wo, -dir, TransportMode::Importance) *
      geometric_cos(camera_si, dir) / dist2;
  const float light_rev = direction_pdf(light_bsdf, lg, -dir, light_wo, TransportMode::Radiance);
  return rules.connect(light, camera, camera_pdf_a, camera_rev, light_pdf_a, light_rev);
}

namespace {
// The per-pixel camera density of the connected point in area measure: camera_pdf_w's value
// (pixel_count x pdf_dir x raster density), in its order of operations, times cos / d^2.
float camera_pdf_a(const LensConnection& c, float raster_density) {
  return c.pixels_pdf_dir * raster_density * c.cos_at_vertex / c.dist2;
}
}  // namespace

LensConnection lens_connection_of_emission(const Camera& camera, Vec3 p, Vec3 n, Vec3 p_lens) {
  const Vec3 d = p_lens - p;
  LensConnection c;
  c.dist2 = length_squared(d);
  const Vec3 dir = d / std::sqrt(c.dist2);
  // The lens point came from sample_wi, whose ray reached the film: no second film test.
  c.pixels_pdf_dir = float(camera.pixel_count()) * camera.pdf_dir_on_film(-dir);
  c.cos_at_vertex = abs_dot(n, dir);
  return c;
}

LensConnection lens_connection(const Camera& camera, const SurfaceInteraction& si, const Bsdf& bsdf,
                               Vec3 wo, Vec3 p_lens, const VertexGuides& guides) {
  LensConnection c = lens_connection_of_emission(camera, si.p, si.ng, p_lens);
  const Vec3 dir = (p_lens - si.p) / std::sqrt(c.dist2);  // as lens_connection_of_emission's
  c.rev = direction_pdf(bsdf, guides, dir, wo, TransportMode::Radiance);
  return c;
}

TechniqueTerms terms_light_to_camera(const MisRules& rules, const LensConnection& c,
                                     const MisSums& light, float raster_density) {
  return rules.light_to_camera(light, camera_pdf_a(c, raster_density), c.rev);
}

TechniqueTerms terms_light_to_camera(const MisRules& rules, const Camera& camera,
                                     const SurfaceInteraction& si, const Bsdf& bsdf, Vec3 wo,
                                     const MisSums& light, Vec3 p_lens, float raster_density,
                                     const VertexGuides& guides) {
  return terms_light_to_camera(rules, lens_connection(camera, si, bsdf, wo, p_lens, guides), light,
                               raster_density);
}

TechniqueTerms terms_light_origin_to_camera(const MisRules& rules, const LensConnection& c,
                                            float emission_pos_pdf, float raster_density) {
  return rules.light_origin_to_camera(camera_pdf_a(c, raster_density), emission_pos_pdf);
}

TechniqueTerms terms_merge(const MisRules& rules, Vec3 light_wo, const MisSums& light,
                           const SurfaceInteraction& camera_si, const Bsdf& camera_bsdf,
                           const MisSums& camera, const VertexGuides& camera_guides) {
  const VertexGuides& g = camera_guides;
  const float fwd = direction_pdf(camera_bsdf, g, camera_si.wo, light_wo, TransportMode::Radiance);
  const float rev =
      direction_pdf(camera_bsdf, g, light_wo, camera_si.wo, TransportMode::Importance);
  return rules.merge(light, camera, fwd, rev);
}

}  // namespace caustica::bidir
