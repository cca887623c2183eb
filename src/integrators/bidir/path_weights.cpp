#include "integrators/bidir/path_weights.h"

#include "integrators/bidir/light_vertex.h"
#include "integrators/bidir/techniques.h"
#include "lights/light.h"
#include "lights/light_sampler.h"
#include "materials/material.h"
#include "scene/scene.h"

namespace caustica::bidir {

namespace {
TechniqueWeight weight_of(const MisRules& rules, bool merge, int s, int t,
                          const TechniqueTerms& terms) {
  const MisCounts& n = rules.counts();
  const float stop = terms.stop_denominator(n.emitter, n.merge);
  const float w = terms.weight(n), own = n.of(terms.own) * terms.own_factor;
  return {merge,
          s,
          t,
          w,
          stop > 0 ? terms.stop_own(n.emitter, n.merge) / stop : 0.f,
          own > 0 ? w * stop / own : 0.f};
}
}  // namespace

std::vector<TechniqueWeight> production_weights(const Scene& scene, BidirAlgorithm algorithm,
                                                MisHeuristic heuristic, float light_paths,
                                                float radius, const ExplicitPath& path,
                                                ScratchArena& arena, float raster_density,
                                                int connections, bool pixel_merges,
                                                const BidirGuiding* guiding, float merge_mis_scale,
                                                bool correlation_aware) {
  const bool connect = algorithm != BidirAlgorithm::Bpm;
  const bool merge =
      algorithm != BidirAlgorithm::Bpt && algorithm != BidirAlgorithm::GuidedBpt && pixel_merges;
  MisCounts counts;
  counts.emitter = connect ? 1.f : 0.f;
  counts.light_trace = connect ? light_paths : 0.f;
  counts.connect = connect ? float(connections) : 0.f;
  counts.merge = merge ? kPi * radius * radius * light_paths * merge_mis_scale : 0.f;
  MisRules rules(heuristic, counts);
  if (correlation_aware && merge)
    rules.enable_correlation(kPi * radius * radius, 1.f / light_paths);
  const Light& light = *path.light;
  const float pmf = scene.light_sampler().pmf(&light);
  const bool finite = !light.is_infinite();
  const int k = int(path.surfaces.size()) + 1;  // segments
  if (k == 1) {
    // An area light seen straight from the lens: the camera ray hitting it (s = 0) and its
    // emission point connected to the lens (s = 1, t = 1).
    if (!connect || light.type() != LightType::Area) return {};
    SurfaceInteraction emitter;
    emitter.p = path.light_point;
    emitter.ng = path.light_normal;
    emitter.wo = normalize(path.lens_point - path.light_point);
    MisSums m = rules.camera_start(
        camera_pdf_w(scene.camera(), path.lens_point, -emitter.wo, raster_density));
    rules.hit(m, distance_squared(path.lens_point, emitter.p), geometric_cos(emitter, emitter.wo));
    float pdf_pos, pdf_dir;
    light.pdf_le(emitter.p, emitter.ng, emitter.wo, &pdf_pos, &pdf_dir);
    const LensConnection lens =
        lens_connection_of_emission(scene.camera(), emitter.p, emitter.ng, path.lens_point);
    return {
        weight_of(rules, false, 0, 2, terms_light_seen_from_lens(rules, light, pmf, emitter, m)),
        weight_of(rules, false, 1, 1,
                  terms_light_origin_to_camera(rules, lens, pmf * pdf_pos, raster_density))};
  }

  // Positions x0..xk; for infinite lights x0 is a point far back along the emission direction.
  std::vector<Vec3> x(k + 1);
  x[0] = finite ? path.light_point : path.surfaces[0].p - path.emit_dir * 1e3f;
  for (int i = 1; i < k; ++i) x[i] = path.surfaces[i - 1].p;
  x[k] = path.lens_point;
  auto dir = [&](int from, int to) { return normalize(x[to] - x[from]); };

  // Hit records as seen by each subpath (wo toward the subpath's previous vertex), and BSDFs.
  std::vector<SurfaceInteraction> light_si(k), camera_si(k);
  std::vector<Bsdf> bsdf(k);
  for (int i = 1; i < k; ++i) {
    light_si[i] = camera_si[i] = path.surfaces[i - 1];
    light_si[i].wo = (i == 1 && !finite) ? -path.emit_dir : dir(i, i - 1);
    camera_si[i].wo = dir(i, i + 1);
    bsdf[i] = path.surfaces[i - 1].material->bsdf(path.surfaces[i - 1], arena);
  }
  auto delta = [&](int i) { return bsdf[i].is_delta(); };
  std::vector<VertexGuides> guides(k);
  for (int i = 1; guiding && i < k; ++i)
    guides[i] = guiding->at(x[i], path.surfaces[i - 1].ng, bsdf[i]);
  // The learned probability of technique t at the non-delta vertex x_i toward w
  // (technique_probabilities.h), as the renderer looks it up; 1 unguided.
  auto probability = [&](GuidingField::Technique t, int i, Vec3 w) {
    if (!guiding || delta(i)) return 1.f;
    return guiding->probabilities_at(x[i], path.surfaces[i - 1].ng).of(t, w);
  };

  // Light subpath replay: sums at x1..x(k-1), stored and reloaded as the renderer does.
  LightLeSample le;
  le.p = x[0];
  le.n = finite ? path.light_normal : path.emit_dir;
  le.dir = finite ? dir(0, 1) : path.emit_dir;
  light.pdf_le(le.p, le.n, le.dir, &le.pdf_pos, &le.pdf_dir);
  le.cos_at_light = light.type() == LightType::Area ? abs_dot(le.n, le.dir) : 1.f;
  std::vector<MisSums> light_mis(k);
  // Correlation-aware MIS: each subpath's merges at each of its vertices (mis.h).
  std::vector<OwnedCorrelationTrack> light_tracks(k), camera_tracks(k);
  for (int i = 1; i < k; ++i) {
    if (i == 1) {
      light_mis[1] = light_subpath_start(rules, light, pmf, le, light_si[1], distance(x[0], x[1]),
                                         &light_tracks[1]);
      rules.scale_vcm(light_mis[1], probability(GuidingField::kNextEvent, 1, light_si[1].wo));
    } else {
      MisSums m = light_mis[i - 1];
      light_tracks[i] = light_tracks[i - 1];
      if (m.corr) m.corr = &light_tracks[i];
      const bool specular = delta(i - 1);
      const float pdf_fwd = specular ? 1.f
                                     : direction_pdf(bsdf[i - 1], guides[i - 1], light_si[i - 1].wo,
                                                     dir(i - 1, i), TransportMode::Importance);
      scatter_update(rules, m, light_si[i - 1], bsdf[i - 1], light_si[i - 1].wo, dir(i - 1, i),
                     TransportMode::Importance, specular, pdf_fwd, guides[i - 1]);
      rules.scale_vcm(m, probability(GuidingField::kConnection, i - 1, dir(i - 1, i)));
      rules.hit(m, distance_squared(x[i - 1], x[i]), geometric_cos(light_si[i], dir(i, i - 1)));
      light_mis[i] = m;
    }
  }
  auto stored = [&](int i) {
    MisSums m =
        unpack_light_vertex(pack_light_vertex({x[i], light_si[i].wo, 0, i, Rgb(1.f), light_mis[i]}))
            .mis;
    m.corr = light_mis[i].corr;
    return m;
  };

  // Camera subpath replay: sums at x(k-1) down to x1, and at the emitter (s = 0).
  std::vector<MisSums> camera_mis(k);
  const float pdf_camera = camera_pdf_w(scene.camera(), x[k], dir(k, k - 1), raster_density);
  camera_mis[k - 1] = rules.camera_start(pdf_camera);
  if (rules.correlated()) {
    rules.correlation_camera_start(camera_tracks[k - 1], pdf_camera);
    camera_mis[k - 1].corr = &camera_tracks[k - 1];
  }
  rules.hit(camera_mis[k - 1], distance_squared(x[k], x[k - 1]),
            geometric_cos(camera_si[k - 1], dir(k - 1, k)));
  rules.scale_vcm(camera_mis[k - 1],
                  probability(GuidingField::kLensConnection, k - 1, camera_si[k - 1].wo));
  for (int i = k - 2; i >= 1; --i) {
    MisSums m = camera_mis[i + 1];
    camera_tracks[i] = camera_tracks[i + 1];
    if (m.corr) m.corr = &camera_tracks[i];
    const bool specular = delta(i + 1);
    const float pdf_fwd = specular ? 1.f
                                   : direction_pdf(bsdf[i + 1], guides[i + 1], camera_si[i + 1].wo,
                                                   dir(i + 1, i), TransportMode::Radiance);
    scatter_update(rules, m, camera_si[i + 1], bsdf[i + 1], camera_si[i + 1].wo, dir(i + 1, i),
                   TransportMode::Radiance, specular, pdf_fwd, guides[i + 1]);
    rules.hit(m, distance_squared(x[i + 1], x[i]), geometric_cos(camera_si[i], dir(i, i + 1)));
    rules.scale_vcm(m, probability(GuidingField::kConnection, i, camera_si[i].wo));
    camera_mis[i] = m;
  }

  std::vector<TechniqueWeight> out;
  const Vec3 to_light = finite ? dir(1, 0) : -path.emit_dir;
  // s = 0: the camera subpath hits the emitter.
  if (connect && !light.is_delta()) {
    MisSums m = camera_mis[1];
    OwnedCorrelationTrack emitter_track = camera_tracks[1];
    if (m.corr) m.corr = &emitter_track;
    const bool specular = delta(1);
    const float pdf_fwd = specular ? 1.f
                                   : direction_pdf(bsdf[1], guides[1], camera_si[1].wo, to_light,
                                                   TransportMode::Radiance);
    scatter_update(rules, m, camera_si[1], bsdf[1], camera_si[1].wo, to_light,
                   TransportMode::Radiance, specular, pdf_fwd, guides[1]);
    const float q = probability(GuidingField::kNextEvent, 1, to_light);
    if (finite) {
      SurfaceInteraction emitter;
      emitter.p = x[0];
      emitter.ng = path.light_normal;
      emitter.wo = dir(0, 1);
      rules.hit(m, distance_squared(x[0], x[1]), geometric_cos(emitter, emitter.wo));
      out.push_back(
          weight_of(rules, false, 0, k + 1,
                    terms_emitter_hit(rules, light, pmf, x[1], to_light, &emitter, m, q)));
    } else {
      out.push_back(weight_of(rules, false, 0, k + 1,
                              terms_emitter_hit(rules, light, pmf, x[1], to_light, nullptr, m, q)));
    }
  }
  // s = 1: next event estimation from x1.
  if (connect && !delta(1)) {
    LightLiSample ls;
    ls.wi = to_light;
    ls.distance = finite ? distance(x[0], x[1]) : kInfinity;
    ls.p_light = x[0];
    ls.n_light = finite ? path.light_normal : Vec3();
    ls.pdf_w = light.is_delta() ? 1.f : light.pdf_li(x[1], ls.wi, x[0], ls.n_light);
    light.pdf_le(x[0], le.n, -ls.wi, &ls.pdf_emit_pos, &ls.pdf_emit_dir);
    ls.cos_at_light = light.type() == LightType::Area ? abs_dot(path.light_normal, ls.wi) : 1.f;
    TechniqueTerms terms =
        terms_next_event(rules, light, pmf, ls, camera_si[1], bsdf[1], camera_mis[1], guides[1]);
    terms.own_factor = rules.mis(probability(GuidingField::kNextEvent, 1, to_light));
    out.push_back(weight_of(rules, false, 1, k, terms));
  }
  // 2 <= s <= k - 1: connections of x(s-1) and x(s).
  for (int s = 2; connect && s <= k - 1; ++s) {
    if (delta(s - 1) || delta(s)) continue;
    TechniqueTerms terms =
        terms_connection(rules, light_si[s - 1], bsdf[s - 1], light_si[s - 1].wo, stored(s - 1),
                         camera_si[s], bsdf[s], camera_mis[s], guides[s - 1], guides[s]);
    terms.own_factor = rules.mis(probability(GuidingField::kConnection, s - 1, dir(s - 1, s)));
    out.push_back(weight_of(rules, false, s, k + 1 - s, terms));
  }
  // t = 1: x(k-1) connected to the lens.
  if (connect && k >= 2 && !delta(k - 1)) {
    TechniqueTerms terms = terms_light_to_camera(rules, scene.camera(), light_si[k - 1],
                                                 bsdf[k - 1], light_si[k - 1].wo, stored(k - 1),
                                                 x[k], raster_density, guides[k - 1]);
    terms.own_factor = rules.mis(probability(GuidingField::kLensConnection, k - 1, dir(k - 1, k)));
    out.push_back(weight_of(rules, false, k, 1, terms));
  }
  // Merges at every non-delta interior vertex.
  for (int j = 1; merge && j <= k - 1; ++j) {
    if (delta(j)) continue;
    out.push_back(weight_of(rules, true, j + 1, k + 1 - j,
                            terms_merge(rules, light_si[j].wo, stored(j), camera_si[j], bsdf[j],
                                        camera_mis[j], guides[j])));
  }
  return out;
}

}  // namespace caustica::bidir
