// guided-pt's direction sampling at a vertex: the one-sample MIS mixture of the BSDF and the
// learned distribution (Veach 1997, sec. 9.2.4; Müller et al. 2017), chosen per vertex by
// mixture_at() in guided_path_tracer.cpp.
//
// Layered (stochastic) BSDFs are guided too. Their sample() returns only the ratio f |cos| / pdf
// of a random walk, their f() is an unbiased estimate and their pdf() an approximation p~ of the
// sampling density, so the mixture density a p_bsdf + (1 - a) p_guide cannot be evaluated.
// Their vertices use the two techniques with the balance weights of the approximate densities
// (any weights that sum to one keep MIS unbiased, Veach 1997 sec. 9.2.2):
//   the BSDF (probability a):  (f |cos| / pdf)_walk * p~ / (a p~ + (1 - a) p_guide),
//                              or (f |cos| / pdf)_walk / a for a specular (delta) sample, which
//                              only the BSDF can make;
//   the guide (1 - a):         f_estimate |cos| / (a p~ + (1 - a) p_guide).
// In expectation the two sum to the integral of f |cos| (tests/guided_mixture_test.cpp checks it
// against the BSDF's own sample weights). a p~ + (1 - a) p_guide is also the density the
// emitter-hit and next event MIS weights use, as for every other BSDF.
#pragma once

#include <optional>

#include "core/vec.h"
#include "guiding/directional_quadtree.h"
#include "materials/bsdf.h"

namespace caustica {

// The densities of one direction, evaluated once: where it lies on the guide's square, the
// BSDF's density and the learned one (0 without a guide).
struct DirectionPdfs {
  Vec2 square;
  float bsdf = 0, guide = 0;
};

// The mixture at a vertex; without a guide (guide == nullptr), the BSDF alone.
struct Mixture {
  const DirectionalQuadtree* guide = nullptr;
  float bsdf_fraction = 1;
  uint32_t leaf = 0;          // the vertex's spatial leaf
  uint32_t record_leaf = 0;   // where this vertex's records go (the spatial filter's jitter)
  bool guidable = false;      // records are learned here
  float nee_probability = 1;  // of next event estimation here (GuidingSettings::nee_floor)
  // The records' weight along wi: |cos| to the shading normal where the guides learn the
  // product with the cosine (GuidingSettings::cosine_product), else 1.
  Vec3 cosine_normal;
  float record_weight(Vec3 wi) const {
    return cosine_normal == Vec3() ? 1.f : std::abs(dot(cosine_normal, wi));
  }

  DirectionPdfs evaluate(const Bsdf& bsdf, Vec3 wo, Vec3 wi) const {
    DirectionPdfs d;
    d.square = direction_to_square(wi);
    d.bsdf = bsdf.pdf(wo, wi, TransportMode::Radiance);
    if (guide) d.guide = guide->pdf_square(d.square) * kInv4Pi;
    return d;
  }
  float pdf(const DirectionPdfs& d) const {
    return guide ? bsdf_fraction * d.bsdf + (1 - bsdf_fraction) * d.guide : d.bsdf;
  }
};

// A direction sampled from the mixture.
struct MixtureSample {
  Vec3 wi;
  float pdf = 0;       // the mixture's (the BSDF's alone without a guide)
  DirectionPdfs pdfs;  // filled where the vertex is guidable
  Rgb weight;          // f |cos| / pdf (for layered BSDFs, the MIS estimate above)
  // f |cos| / p_bsdf: what the weight would be had the BSDF alone been sampled (Russian roulette)
  Rgb bsdf_weight;
  bool specular = false;
  float eta2 = 1;  // eta^2 of a sampled refraction (for Russian roulette)
};

// Whether a BSDF is guided: not delta and, unless it is layered (whose specular coat reflection
// the BSDF technique keeps, see above), without specular lobes.
inline bool guidable_bsdf(const Bsdf& bsdf) {
  return !bsdf.is_delta() && (bsdf.stochastic() || !is_specular(bsdf.flags()));
}

std::optional<MixtureSample> sample_mixture(const Bsdf& bsdf, Vec3 wo, const Mixture& m,
                                            float u_technique, float uc, Vec2 u);

}  // namespace caustica
