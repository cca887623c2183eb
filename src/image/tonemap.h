// Display transform for PNG output, kept deliberately simple and documented:
//   display = srgb_oetf(clamp(linear * 2^exposure, 0, 1)), channel by channel,
// with NaN mapped to 0 (+inf to 1, -inf to 0). No tone curve, no hue-preserving clamp.
// That is what pbrt-v4's `imgtool convert` does by default, so PNGs of the two renderers
// compare directly. EXR output is never tone mapped.
#pragma once

#include "image/image.h"

namespace caustica {

// Returns an image with values in [0,1] in sRGB-encoded space (ready for 8-bit PNG).
Image tonemap_srgb(const Image& linear, float exposure_stops = 0.f);

}  // namespace caustica
