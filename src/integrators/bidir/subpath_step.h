// One scattering step of a camera or light subpath in the bidirectional core: the next direction
// from the guided mixture where the vertex has a guide for the subpath's mode (vertex_guides.h),
// else from the BSDF, with the MIS sums and the throughputs updated. The random numbers drawn
// are the unguided core's exactly when there is no guide, so unguided images do not change.
#pragma once

#include <optional>

#include "core/rng.h"
#include "integrators/bidir/techniques.h"

namespace caustica::bidir {

struct SubpathStep {
  Vec3 wi;
  bool specular = false;  // a delta lobe was sampled
  float eta = 1;          // of a sampled refraction, else 1
  float pdf = 0;          // the density wi was sampled with (the mixture's where guided)
  float bsdf_pdf = 0;     // the BSDF's density of wi
  float guide_pdf = 0;    // the learned distribution's density of wi (0: not guided)
  Rgb weight;             // f |cos| / pdf
};

// beta *= f |cos| / pdf; rr_beta *= f |cos| / p_bsdf (what BSDF sampling alone would give, for
// guided Russian roulette). guided_mis: the MIS sums take the mixture's densities (else the
// BSDF's alone; GuidingSettings::guided_mis). nullopt: the subpath ends here.
std::optional<SubpathStep> scatter_subpath(const MisRules& rules, MisSums& mis,
                                           const SurfaceInteraction& si, const Bsdf& bsdf,
                                           const VertexGuides& guides, TransportMode mode,
                                           Pcg32& rng, Rgb& beta, Rgb& rr_beta,
                                           bool guided_mis = true);

}  // namespace caustica::bidir
