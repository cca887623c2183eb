#include "integrators/guided_path_tracer.h"

#include <algorithm>
#include <bit>
#include <nlohmann/json.hpp>

#include "integrators/path_vertex.h"
#include "lights/light.h"
#include "lights/light_sampler.h"
#include "materials/material.h"
#include "scene/scene.h"

namespace caustica {

namespace {

// A scattering vertex whose incident radiance along wi is recorded once the path is done.
struct GuidedVertex {
  uint32_t leaf;
  Vec3 wi;
  float pdf;       // the density wi was sampled with (the mixture's where guided)
  Rgb beta_after;  // path throughput including this vertex's f |cos| / pdf
  Rgb incident;    // estimate of the radiance arriving along wi (Müller et al. 2017, sec. 4)
};

}  // namespace

int GuidedPathTracer::training_pass(uint32_t iteration) {
  return std::bit_width(uint64_t(iteration) + 1) - 1;
}

float GuidedPathTracer::mis_weight(float pdf_a, float pdf_b) const {
  return settings_.mis_or(MisHeuristic::Power) == MisHeuristic::Power
             ? power_heuristic(pdf_a, pdf_b)
             : balance_heuristic(pdf_a, pdf_b);
}

void GuidedPathTracer::prepare(const Scene& scene, Film& film) {
  CameraPathIntegrator::prepare(scene, film);
  field_ = GuidingField(scene.bounds(), guiding_);
  pass_ = 0;
  recorded_ = 0;
}

void GuidedPathTracer::render_iteration(const Scene& scene, uint32_t iteration, Film& film) {
  const int pass = training_pass(iteration);
  if (pass > pass_) {
    field_.end_iteration(pass_);
    pass_ = pass;
  }
  for (std::vector<Record>& r : records_) r.clear();
  trace_camera_paths(scene, iteration, film);
  merged_.clear();
  for (const std::vector<Record>& r : records_) merged_.insert(merged_.end(), r.begin(), r.end());
  // Threads' buffers come in any order; a pixel's records come from one path, in path order.
  std::stable_sort(merged_.begin(), merged_.end(),
                   [](const Record& a, const Record& b) { return a.pixel < b.pixel; });
  for (const Record& r : merged_) field_.record(r.leaf, r.wi, r.value);
  recorded_ += merged_.size();
}

Rgb GuidedPathTracer::estimate(const Scene& scene, const CameraSample& sample, Pcg32& rng,
                               ScratchArena& arena, uint64_t*) const {
  const LightSampler& lights = scene.light_sampler();
  std::vector<Record>& records = records_.local();
  auto* vertices = static_cast<GuidedVertex*>(arena.allocate(
      sizeof(GuidedVertex) * size_t(std::max(settings_.max_depth, 1)), alignof(GuidedVertex)));
  int vertex_count = 0;

  Rgb L(0.f), beta(1.f);
  Ray ray = sample.ray;
  int depth = 0;
  bool specular_bounce = false;
  float eta_scale = 1;  // refractions sampled by the BSDF, undone for Russian roulette
  float prev_pdf = 0;   // density of the direction that produced `ray` (mixture where guided)
  Vec3 prev_p;

  // Every contribution also reaches the earlier vertices' incident radiance: a contribution c
  // after vertex j is beta_after_j times an estimate of what arrives along its wi.
  auto add = [&](Rgb c) {
    L += c;
    for (int j = 0; j < vertex_count; ++j)
      for (int ch = 0; ch < 3; ++ch)
        if (vertices[j].beta_after[ch] > 0)
          vertices[j].incident[ch] += c[ch] / vertices[j].beta_after[ch];
  };
  auto add_emission = [&](const SurfaceInteraction* hit) {
    for_each_emitter_seen(scene.infinite_lights(), ray, hit, [&](const Light& light, Rgb Le) {
      if (depth == 0 || specular_bounce)
        add(beta * Le);
      else
        add(beta * Le * mis_weight(prev_pdf, next_event_pdf(lights, light, prev_p, ray.d, hit)));
    });
  };

  for (;;) {
    SurfaceInteraction si;
    Bsdf bsdf;
    if (!next_scattering_vertex(scene, ray, arena, &si, &bsdf, add_emission)) break;
    if (depth++ == settings_.max_depth) break;

    const Vec3 wo = si.wo;
    const bool guidable = !is_specular(bsdf.flags()) && !bsdf.is_delta() && !bsdf.stochastic();
    const uint32_t leaf = guidable ? field_.leaf_at(si.p) : 0;
    const DirectionalQuadtree* guide =
        guidable && field_.sampling(leaf).total() > 0 ? &field_.sampling(leaf) : nullptr;
    // One-sample MIS (Veach 1997, sec. 9.2.4): the density of the mixture that picks the
    // learned distribution with probability kGuidedFraction.
    auto mixture_pdf = [&](Vec3 wi) {
      const float bsdf_pdf = bsdf.pdf(wo, wi, TransportMode::Radiance);
      return guide ? (1 - kGuidedFraction) * bsdf_pdf + kGuidedFraction * guide->pdf(wi) : bsdf_pdf;
    };

    const float u_light = rng.next_float();
    const Vec2 u = rng.next_2d();
    add(direct_light_mis(scene, si, bsdf, beta, u_light, u, mixture_pdf,
                         [&](float a, float b) { return mis_weight(a, b); }));

    const float uc = rng.next_float();
    const Vec2 u_dir = rng.next_2d();
    const float u_technique = rng.next_float();
    Vec3 wi;
    float pdf;
    Rgb weight;  // f |cos| / pdf
    bool specular = false;
    if (guide && u_technique < kGuidedFraction) {
      wi = guide->sample(u_dir);
      pdf = mixture_pdf(wi);
      if (!(pdf > 0)) break;
      weight = bsdf.f(wo, wi, TransportMode::Radiance) * (bsdf.abs_cos(wi) / pdf);
    } else {
      const auto bs = bsdf.sample(wo, uc, u_dir, TransportMode::Radiance);
      if (!bs) break;
      wi = bs->wi;
      specular = bs->is_specular();
      if (bs->is_transmission()) eta_scale *= sqr(bs->eta);
      if (guide) {
        pdf = mixture_pdf(wi);
        weight = bsdf.f(wo, wi, TransportMode::Radiance) * (bsdf.abs_cos(wi) / pdf);
      } else {
        pdf = bs->pdf_is_proportional ? bsdf.pdf(wo, wi, TransportMode::Radiance) : bs->pdf;
        weight = bs->f * (bsdf.abs_cos(wi) / bs->pdf);
      }
    }
    beta *= weight;
    if (guidable) vertices[vertex_count++] = {leaf, wi, pdf, beta, Rgb(0.f)};
    prev_pdf = pdf;
    specular_bounce = specular;
    prev_p = si.p;
    ray = si.spawn_ray(wi);
    if (beta.is_black()) break;
    if (!survives_russian_roulette(beta, eta_scale, depth, rng)) break;
  }

  // Müller et al. 2017, sec. 3.2: each vertex splats L_i / pdf, an estimate of the flux through
  // the quadrant it lands in.
  for (int j = 0; j < vertex_count; ++j) {
    const GuidedVertex& v = vertices[j];
    const float value = v.pdf > 0 ? v.incident.luminance() / v.pdf : 0.f;
    records.push_back({sample.pixel, v.leaf, v.wi, std::isfinite(value) ? value : 0.f});
  }
  return L;
}

void GuidedPathTracer::report(nlohmann::json& stats) const {
  nlohmann::json g;
  g["training_passes_completed"] = pass_;
  g["spatial_leaves"] = field_.leaf_count();
  g["spatial_nodes"] = field_.spatial_node_count();
  g["quadtree_nodes"] = field_.quadtree_node_count();
  g["max_quadtree_nodes"] = guiding_.max_quadtree_nodes;
  g["guiding_bytes"] = field_.memory_bytes();
  g["radiance_samples_recorded"] = recorded_;
  stats["guiding"] = g;
}

}  // namespace caustica
