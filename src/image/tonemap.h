// Display transform for PNG output, kept deliberately simple and documented:
//   display = clamp(linear * 2^exposure, 0, 1), then the sRGB transfer curve.
// That is what pbrt-v4's `imgtool convert` does by default, so PNGs of the two renderers
// compare directly. EXR output is never tone mapped.
#pragma once

#include "image/image.h"

namespace caustica {

// Returns an image with values in [0,1] in sRGB-encoded space (ready for 8-bit PNG).
Image tonemap_srgb(const Image& linear, float exposure_stops = 0.f);

}  // namespace caustica
