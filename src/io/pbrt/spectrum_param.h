// Reads colour-valued parameters ("rgb", "spectrum", "blackbody") as RGB, following what
// pbrt-v4 does with each SpectrumType (see color.h).
#pragma once

#include "core/rgb.h"
#include "io/pbrt/color.h"
#include "io/pbrt/context.h"
#include "io/pbrt/parameters.h"

namespace caustica::pbrt {

// p must be of type rgb, spectrum or blackbody. Albedo RGB above 1 is clamped with a
// warning; negative RGB is an error. Named spectra that are not built in are read as
// files of (wavelength, value) pairs, as pbrt-v4 does.
Rgb spectrum_param_rgb(const Param& p, SpectrumKind kind, LoaderContext& ctx);

}  // namespace caustica::pbrt
