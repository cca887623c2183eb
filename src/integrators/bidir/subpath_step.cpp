#include "integrators/bidir/subpath_step.h"

namespace caustica::bidir {

std::optional<SubpathStep> scatter_subpath(const MisRules& rules, MisSums& mis,
                                           const SurfaceInteraction& si, const Bsdf& bsdf,
                                           const VertexGuides& guides, TransportMode mode,
                                           Pcg32& rng, Rgb& beta, Rgb& rr_beta, bool guided_mis) {
  SubpathStep step;
  const VertexGuides& mis_guides = guided_mis ? guides : kUnguided;
  if (guides.guide(mode, si.wo)) {
    const float u_technique = rng.next_float(), uc = rng.next_float();
    const auto gs = sample_guided(bsdf, guides, si.wo, mode, u_technique, uc, rng.next_2d());
    if (!gs) return std::nullopt;
    step.wi = gs->wi;
    step.eta = gs->eta;
    step.pdf = gs->pdf;
    step.bsdf_pdf = gs->bsdf_pdf;
    step.guide_pdf = gs->guide_pdf;
    step.weight = gs->weight;
    step.specular = gs->specular;
    scatter_update(rules, mis, si, bsdf, si.wo, step.wi, mode, step.specular,
                   guided_mis ? gs->pdf : gs->bsdf_pdf, mis_guides);
    beta *= gs->weight;
    rr_beta *= gs->bsdf_weight;
    return step;
  }
  const float uc = rng.next_float();
  const auto bs = bsdf.sample(si.wo, uc, rng.next_2d(), mode);
  if (!bs) return std::nullopt;
  step.wi = bs->wi;
  step.specular = bs->is_specular();
  if (bs->is_transmission()) step.eta = bs->eta;
  const float pdf_fwd =
      bs->pdf_is_proportional ? direction_pdf(bsdf, mis_guides, si.wo, step.wi, mode) : bs->pdf;
  scatter_update(rules, mis, si, bsdf, si.wo, step.wi, mode, step.specular, pdf_fwd, mis_guides);
  const Rgb weight = bs->f * (bsdf.abs_cos(step.wi) / bs->pdf);
  // A layered BSDF's sample carries only the ratio f / pdf: its density is pdf()'s.
  step.pdf = bs->pdf_is_proportional ? pdf_fwd : bs->pdf;
  step.bsdf_pdf = step.pdf;
  step.weight = weight;
  beta *= weight;
  rr_beta *= weight;
  return step;
}

}  // namespace caustica::bidir
