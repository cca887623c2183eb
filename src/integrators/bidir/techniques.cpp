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
                            const LightLeSample& le, const SurfaceInteraction& y1, float dist,
                            CorrelationTrack* track) {
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
  MisSums s = rules.light_first_hit(direct, emission, le.cos_at_light, light.is_delta(), finite,
                                    dist2, geometric_cos(y1, le.dir));
  if (track && rules.correlated()) {
    // y0: an area light's point (area density pmf pdf_pos); a delta or infinite light's has
    // none to accept (1). y1: the emitted direction's density in area measure, or for an
    // infinite light the density of the ray's origin on the disc, times |cos| at y1.
    const float a_y0 = finite && !light.is_delta() ? rules.acceptance(pmf * le.pdf_pos) : 1.f;
    const float cos_y1 = geometric_cos(y1, le.dir);
    const float a_y1 = rules.acceptance(finite ? le.pdf_dir * cos_y1 / dist2 : le.pdf_pos * cos_y1);
    rules.correlation_light_start(*track, a_y0, a_y1, le.cos_at_light, dist2);
    s.corr = track;
  }
  return s;
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
  TechniqueTerms t = rules.hit_light(camera, direct, pmf * pdf_pos * pdf_dir, nee_probability);
  if (camera.corr && rules.correlated()) {
    // The light subpath is the emitter alone; the camera vertex before it is sampled by the
    // emission direction (area measure), or for an infinite light by the disc (|cos| only).
    const CorrelationTrack& c = *camera.corr;
    const float a_y0 = hit ? rules.acceptance(pmf * pdf_pos) : 1.f;
    const float a_prev =
        rules.acceptance(hit ? pdf_dir * c.seg_cos / c.seg_dist2 : pdf_pos * c.seg_cos);
    t.merge =
        rules.correlated_merges(c, true, 0.f, rules.mis(pmf * pdf_pos * pdf_dir), a_prev, a_y0);
  }
  return t;
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
  const float cos_to_light = geometric_cos(si, ls.wi);
  TechniqueTerms t = rules.next_event(camera, bsdf_fwd, bsdf_rev, direct_w, emission_w,
                                      cos_to_light, ls.cos_at_light);
  if (camera.corr && rules.correlated()) {
    // The light side: the emitter's point and this vertex as the emission samples it.
    const bool finite = !light.is_infinite();
    const float a_y0 =
        light.type() == LightType::Area ? rules.acceptance(pmf * ls.pdf_emit_pos) : 1.f;
    const float a_x =
        rules.acceptance(finite ? ls.pdf_emit_dir * cos_to_light / (ls.distance * ls.distance)
                                : ls.pdf_emit_pos * cos_to_light);
    const float scale = rules.mis(emission_w * cos_to_light / (direct_w * ls.cos_at_light));
    t.merge = rules.correlated_beyond(*camera.corr, true, scale, bsdf_rev, true, a_y0 * a_x);
  }
  return t;
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
  TechniqueTerms t = rules.connect(light, camera, camera_pdf_a, camera_rev, light_pdf_a, light_rev);
  if (light.corr && camera.corr && rules.correlated()) {
    t.merge = rules.correlated_beyond(*light.corr, false, rules.mis(camera_pdf_a), light_rev, true,
                                      camera.corr->own_total * rules.acceptance(camera_pdf_a)) +
              rules.correlated_beyond(*camera.corr, true, rules.mis(light_pdf_a), camera_rev, true,
                                      light.corr->own_total * rules.acceptance(light_pdf_a));
  }
  return t;
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
  const float pdf_a = camera_pdf_a(c, raster_density);
  TechniqueTerms t = rules.light_to_camera(light, pdf_a, c.rev);
  if (light.corr && rules.correlated()) {
    // The camera side is the lens alone: its product is the light vertex's acceptance.
    t.merge = rules.correlated_beyond(*light.corr, false, rules.mis(pdf_a), c.rev, true,
                                      rules.acceptance(pdf_a));
  }
  return t;
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
  TechniqueTerms t = rules.merge(light, camera, fwd, rev);
  if (light.corr && camera.corr && rules.correlated()) {
    // The merged vertex is the camera side's last and the light side's last.
    const float cam = camera.corr->own_total, lig = light.corr->own_total;
    t.merge = rules.correlated_beyond(*light.corr, false, 1.f, fwd, false, cam) +
              rules.correlated_beyond(*camera.corr, true, 1.f, rev, false, lig);
    t.own_factor = rules.mis(rules.correlation(cam, lig));
  }
  return t;
}

}  // namespace caustica::bidir
