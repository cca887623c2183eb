// The directional densities of guided-bpt and guided-vcm at one vertex (bidir_guiding.h): a
// subpath samples its next direction from a one-sample MIS mixture of the BSDF and a learned
// distribution, so every density the MIS of the bidirectional core evaluates there must be that
// mixture's, in both directions (Vorba et al. 2014, "On-line Learning of Parametric Mixture
// Models for Light Transport Simulation", sec. 6):
//   camera subpaths (TransportMode::Radiance) sample wi from the incident radiance learned at
//     the vertex: p(wo -> wi) = a p_bsdf(wo -> wi) + (1 - a) p_radiance(wi);
//   light subpaths (TransportMode::Importance) sample wi from the incident importance learned
//     there: p(wo -> wi) = a p_bsdf(wo -> wi) + (1 - a) p_importance(wi).
// Which distribution depends on the side of the surface the subpath arrived from (wo): the two
// faces of a zero-thickness wall lie in the same spatial leaf, and one distribution for both
// sent half the guided directions into the surface (measured on door-ajar: 49% of guided
// samples had f = 0). A reverse density (what the other subpath would have sampled) is the same
// function with the other mode: direction_pdf(bsdf, g, wi, wo, !mode), keyed by wi, the side
// that subpath arrives from. Without a learned distribution (no guide, or an unguided
// integrator) the density is the BSDF's alone, bit for bit.
#pragma once

#include <optional>

#include "core/math.h"
#include "guiding/directional_quadtree.h"
#include "materials/bsdf.h"

namespace caustica::bidir {

class BidirGuiding;

// A (mode, side)'s guide is looked up in its learned field the first time a density asks for it
// (most vertices only ever need one: the mode of their subpath, on the side it arrives from;
// looking up both fields at once was twice the spatial descents).
struct VertexGuides {
  const BidirGuiding* fields = nullptr;  // nullptr: not guided (the BSDF alone)
  Vec3 p;
  Vec3 n;  // the geometric normal: the side a direction lies on
  // guides[mode][side]: what a subpath of `mode` that arrived from `side` (0: the side n points
  // to) samples from, nullptr where nothing was learned; bsdf[mode][side]: the probability of
  // sampling the BSDF instead. Filled for (mode, side) once resolved has bit 2 mode + side.
  mutable const DirectionalQuadtree* guides[2][2] = {{nullptr, nullptr}, {nullptr, nullptr}};
  mutable float bsdf[2][2] = {{1, 1}, {1, 1}};
  // The field's leaf of each resolved (mode, side) (~0u where its field was not looked up):
  // technique_probabilities.h shares the radiance leaves.
  mutable uint32_t leaf[2][2] = {{~0u, ~0u}, {~0u, ~0u}};
  mutable uint8_t resolved = 0;
  // The last guide density evaluated per (mode, side) and its direction: most densities at a
  // vertex are reverse ones at the same direction (the camera vertex's wo for its NEE, every
  // connection and every merge; the lens direction for every pixel a light vertex splats to).
  mutable Vec3 memo_wi[2][2];
  mutable float memo_pdf[2][2] = {{0, 0}, {0, 0}};
  mutable uint8_t memoized = 0;

  static int side_of(Vec3 n, Vec3 w) { return dot(w, n) < 0 ? 1 : 0; }
  // A (mode, side) marked resolved keeps what it holds (the tests set guides that way).
  const DirectionalQuadtree* guide(TransportMode mode, Vec3 wo) const {
    const int side = side_of(n, wo);
    if (!(resolved & (1u << (2 * int(mode) + side)))) {
      if (!fields) return nullptr;
      resolve(mode, side);
    }
    return guides[int(mode)][side];
  }
  // Only after guide() of the same mode and side.
  float bsdf_fraction(TransportMode mode, Vec3 wo) const { return bsdf[int(mode)][side_of(n, wo)]; }
  void resolve(TransportMode mode, int side) const;  // bidir_guiding.cpp

  // The solid-angle density of the guide of (mode, side of wo) at wi; only after guide() found
  // one.
  float guide_pdf(TransportMode mode, Vec3 wo, Vec3 wi) const {
    const int m = int(mode), side = side_of(n, wo);
    const uint8_t bit = uint8_t(1u << (2 * m + side));
    if ((memoized & bit) && memo_wi[m][side].x == wi.x && memo_wi[m][side].y == wi.y &&
        memo_wi[m][side].z == wi.z)
      return memo_pdf[m][side];
    const float pdf = guides[m][side]->pdf_square(direction_to_square(wi)) * kInv4Pi;
    memo_wi[m][side] = wi;
    memo_pdf[m][side] = pdf;
    memoized |= bit;
    return pdf;
  }
};

// No guides: the BSDF's densities alone (never written: guide() returns before any memo).
inline const VertexGuides kUnguided{};

// The density with which a subpath of `mode` at this vertex samples wi given wo.
inline float direction_pdf(const Bsdf& bsdf, const VertexGuides& g, Vec3 wo, Vec3 wi,
                           TransportMode mode) {
  const DirectionalQuadtree* guide = g.guide(mode, wo);
  if (!guide) return bsdf.pdf(wo, wi, mode);
  const float a = g.bsdf_fraction(mode, wo);
  return a * bsdf.pdf(wo, wi, mode) + (1 - a) * g.guide_pdf(mode, wo, wi);
}

// A direction sampled from the mixture of `mode` at a vertex with a guide for it.
struct GuidedSample {
  Vec3 wi;
  float pdf = 0;          // the mixture's
  float bsdf_pdf = 0;     // the BSDF's alone
  float guide_pdf = 0;    // the learned distribution's alone
  Rgb weight;             // f |cos| / pdf
  Rgb bsdf_weight;        // f |cos| / p_bsdf: the weight had the BSDF alone been sampled (roulette)
  float eta = 1;          // of a sampled refraction, else 1
  bool specular = false;  // a layered BSDF's delta sample (its smooth coat)
};

// u_technique picks the BSDF (below the BSDF fraction) or the guide; uc and u sample either.
// Requires g.guide(mode, wo) (a vertex without one samples its BSDF as the unguided core does).
// A layered (stochastic) BSDF's walk is weighted as guided-pt weighs it (guided_mixture.h): the
// balance weights of its approximate density p~ keep the two techniques unbiased, and a delta
// sample of a smooth coat, which only the BSDF makes, is divided by a.
inline std::optional<GuidedSample> sample_guided(const Bsdf& bsdf, const VertexGuides& g, Vec3 wo,
                                                 TransportMode mode, float u_technique, float uc,
                                                 Vec2 u) {
  const DirectionalQuadtree& guide = *g.guide(mode, wo);
  const float a = g.bsdf_fraction(mode, wo);
  GuidedSample s;
  // The weights from f |cos| at s.wi, once s.pdf (> 0) and s.bsdf_pdf are set.
  auto weigh = [&s](Rgb f_cos) -> std::optional<GuidedSample> {
    if (f_cos.is_black()) return std::nullopt;
    s.weight = f_cos / s.pdf;
    s.bsdf_weight = s.bsdf_pdf > 0 ? f_cos / s.bsdf_pdf : Rgb(0.f);
    return s;
  };
  if (u_technique < a) {
    const auto bs = bsdf.sample(wo, uc, u, mode);
    if (!bs) return std::nullopt;
    s.wi = bs->wi;
    if (bs->is_transmission()) s.eta = bs->eta;
    if (bs->pdf_is_proportional) {
      const Rgb walk = bs->f * (bsdf.abs_cos(s.wi) / bs->pdf);
      s.bsdf_pdf = bsdf.pdf(wo, s.wi, mode);
      s.bsdf_weight = walk;
      if (bs->is_specular()) {
        s.specular = true;
        s.pdf = s.bsdf_pdf;
        s.weight = walk / a;
        return s;
      }
      s.guide_pdf = g.guide_pdf(mode, wo, s.wi);
      s.pdf = a * s.bsdf_pdf + (1 - a) * s.guide_pdf;
      if (!(s.pdf > 0) || walk.is_black()) return std::nullopt;
      s.weight = walk * (s.bsdf_pdf / s.pdf);
      return s;
    }
    // f and the BSDF's density come with its sample (the BSDF tests check that they are f()
    // and pdf()): only the guide's density is evaluated.
    s.guide_pdf = g.guide_pdf(mode, wo, s.wi);
    s.bsdf_pdf = bs->pdf;
    s.pdf = a * s.bsdf_pdf + (1 - a) * s.guide_pdf;
    if (!(s.pdf > 0)) return std::nullopt;
    return weigh(bs->f * bsdf.abs_cos(s.wi));
  }
  // The sampled point's leaf density is the guide's density of the direction (as guided-pt: the
  // round trip through direction_to_square() agrees but within rounding at leaf borders),
  // without a second descent.
  float density;
  s.wi = square_to_direction(guide.sample_square(u, &density));
  s.guide_pdf = density * kInv4Pi;
  s.bsdf_pdf = bsdf.pdf(wo, s.wi, mode);
  s.pdf = a * s.bsdf_pdf + (1 - a) * s.guide_pdf;
  if (!(s.pdf > 0)) return std::nullopt;
  return weigh(bsdf.f(wo, s.wi, mode) * bsdf.abs_cos(s.wi));
}

}  // namespace caustica::bidir
