// The directional densities of guided-bpt and guided-vcm at one vertex (bidir_guiding.h): a
// subpath samples its next direction from a one-sample MIS mixture of the BSDF and a learned
// distribution, so every density the MIS of the bidirectional core evaluates there must be that
// mixture's, in both directions (Vorba et al. 2014, "On-line Learning of Parametric Mixture
// Models for Light Transport Simulation", sec. 6):
//   camera subpaths (TransportMode::Radiance) sample wi from the incident radiance learned at
//     the vertex: p(wo -> wi) = a p_bsdf(wo -> wi) + (1 - a) p_radiance(wi);
//   light subpaths (TransportMode::Importance) sample wi from the incident importance learned
//     there: p(wo -> wi) = a p_bsdf(wo -> wi) + (1 - a) p_importance(wi).
// A reverse density (what the other subpath would have sampled) is the same function with the
// other mode: direction_pdf(bsdf, g, wi, wo, !mode). Without a learned distribution (no guide,
// or an unguided integrator) it is the BSDF's density alone, bit for bit.
#pragma once

#include <optional>

#include "core/math.h"
#include "guiding/directional_quadtree.h"
#include "materials/bsdf.h"

namespace caustica::bidir {

struct VertexGuides {
  const DirectionalQuadtree* radiance = nullptr;  // camera subpaths' guide (nullptr: none)
  const DirectionalQuadtree* importance = nullptr;  // light subpaths' guide
  float radiance_bsdf = 1, importance_bsdf = 1;     // probabilities of sampling the BSDF

  const DirectionalQuadtree* guide(TransportMode mode) const {
    return mode == TransportMode::Radiance ? radiance : importance;
  }
  float bsdf_fraction(TransportMode mode) const {
    return mode == TransportMode::Radiance ? radiance_bsdf : importance_bsdf;
  }
};

// The density with which a subpath of `mode` at this vertex samples wi given wo.
inline float direction_pdf(const Bsdf& bsdf, const VertexGuides& g, Vec3 wo, Vec3 wi,
                           TransportMode mode) {
  const DirectionalQuadtree* guide = g.guide(mode);
  if (!guide) return bsdf.pdf(wo, wi, mode);
  const float a = g.bsdf_fraction(mode);
  return a * bsdf.pdf(wo, wi, mode) +
         (1 - a) * guide->pdf_square(direction_to_square(wi)) * kInv4Pi;
}

// A direction sampled from the mixture of `mode` at a vertex with a guide for it.
struct GuidedSample {
  Vec3 wi;
  float pdf = 0;     // the mixture's
  Rgb weight;        // f |cos| / pdf
  Rgb bsdf_weight;   // f |cos| / p_bsdf: the weight had the BSDF alone been sampled (roulette)
  float eta = 1;     // of a sampled refraction, else 1
};

// u_technique picks the BSDF (below the BSDF fraction) or the guide; uc and u sample either.
// Requires g.guide(mode) (a vertex without one samples its BSDF as the unguided core does).
inline std::optional<GuidedSample> sample_guided(const Bsdf& bsdf, const VertexGuides& g, Vec3 wo,
                                                 TransportMode mode, float u_technique, float uc,
                                                 Vec2 u) {
  GuidedSample s;
  if (u_technique < g.bsdf_fraction(mode)) {
    const auto bs = bsdf.sample(wo, uc, u, mode);
    if (!bs) return std::nullopt;
    s.wi = bs->wi;
    if (bs->is_transmission()) s.eta = bs->eta;
  } else {
    s.wi = square_to_direction(g.guide(mode)->sample_square(u));
  }
  const float bsdf_pdf = bsdf.pdf(wo, s.wi, mode);
  const float a = g.bsdf_fraction(mode);
  s.pdf = a * bsdf_pdf + (1 - a) * g.guide(mode)->pdf_square(direction_to_square(s.wi)) * kInv4Pi;
  if (!(s.pdf > 0)) return std::nullopt;
  const Rgb f_cos = bsdf.f(wo, s.wi, mode) * bsdf.abs_cos(s.wi);
  if (f_cos.is_black()) return std::nullopt;
  s.weight = f_cos / s.pdf;
  s.bsdf_weight = bsdf_pdf > 0 ? f_cos / bsdf_pdf : Rgb(0.f);
  return s;
}

}  // namespace caustica::bidir
