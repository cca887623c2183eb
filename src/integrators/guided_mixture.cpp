#include "integrators/guided_mixture.h"

namespace caustica {

std::optional<MixtureSample> sample_mixture(const Bsdf& bsdf, Vec3 wo, const Mixture& m,
                                            float u_technique, float uc, Vec2 u) {
  MixtureSample s;
  // The mixture's density and weights from s.pdfs and f |cos| at s.wi.
  auto weigh = [&s, &m](Rgb f_cos) -> std::optional<MixtureSample> {
    s.pdf = m.pdf(s.pdfs);
    if (!(s.pdf > 0)) return std::nullopt;
    s.weight = f_cos / s.pdf;
    s.bsdf_weight = s.pdfs.bsdf > 0 ? f_cos / s.pdfs.bsdf : Rgb(0.f);
    return s;
  };
  if (m.guide && u_technique >= m.bsdf_fraction) {
    // The sampled point's leaf density is the guide's density of the direction (the round trip
    // through direction_to_square() agrees but within float rounding at leaf borders).
    float guide_pdf;
    const Vec2 square = m.guide->sample_square(u, &guide_pdf);
    s.wi = square_to_direction(square);
    s.pdfs = {square, bsdf.pdf(wo, s.wi, TransportMode::Radiance), guide_pdf * kInv4Pi};
    return weigh(bsdf.f(wo, s.wi, TransportMode::Radiance) * bsdf.abs_cos(s.wi));
  }
  const auto bs = bsdf.sample(wo, uc, u, TransportMode::Radiance);
  if (!bs) return std::nullopt;
  s.wi = bs->wi;
  if (bs->is_transmission()) s.eta2 = sqr(bs->eta);
  if (!m.guide) {
    s.specular = bs->is_specular();
    s.pdf = bs->pdf_is_proportional ? bsdf.pdf(wo, s.wi, TransportMode::Radiance) : bs->pdf;
    s.weight = s.bsdf_weight = bs->f * (bsdf.abs_cos(s.wi) / bs->pdf);
    if (m.guidable) s.pdfs = {direction_to_square(s.wi), s.pdf, 0.f};
    return s;
  }
  if (bs->pdf_is_proportional) {
    // A layered BSDF's walk: its weight with the BSDF technique's MIS weight over a.
    const Rgb walk = bs->f * (bsdf.abs_cos(s.wi) / bs->pdf);
    s.bsdf_weight = walk;
    if (bs->is_specular()) {  // a delta sample: no other technique makes it
      s.specular = true;
      s.pdf = bsdf.pdf(wo, s.wi, TransportMode::Radiance);  // unused after a specular bounce
      s.weight = walk / m.bsdf_fraction;
      return s;
    }
    s.pdfs = m.evaluate(bsdf, wo, s.wi);
    s.pdf = m.pdf(s.pdfs);
    if (!(s.pdf > 0)) return std::nullopt;
    s.weight = walk * (s.pdfs.bsdf / s.pdf);
    return s;
  }
  // The BSDF's own sample carries f and its density (the BSDF tests check that they are f()
  // and pdf()): only the guide's density is evaluated.
  const Vec2 square = direction_to_square(s.wi);
  s.pdfs = {square, bs->pdf, m.guide->pdf_square(square) * kInv4Pi};
  return weigh(bs->f * bsdf.abs_cos(s.wi));
}

}  // namespace caustica
