// False-colour visualisation of per-pixel error, for comparison reports.
#pragma once

#include "image/image.h"

namespace caustica {

// Per-pixel relative squared error (img - ref)^2 / (ref^2 + eps), averaged over channels,
// mapped on a log10 scale from [log_min, log_max] to a perceptually ordered colour ramp
// (black-purple-orange-yellow, like "inferno"). Output is display-ready sRGB in [0,1].
Image false_color_rel_error(const Image& img, const Image& ref, float log_min = -4.f,
                            float log_max = 1.f, float eps = 0.01f);

// The colour ramp itself, t in [0,1] -> display sRGB.
Rgb inferno_ramp(float t);

}  // namespace caustica
