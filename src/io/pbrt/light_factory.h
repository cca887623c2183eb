// pbrt-v4 lights: LightSource "point" (from, I), "spot" (from, to, coneangle,
// conedeltaangle, I), "distant" (from, to, L), "infinite" (L, or filename: a square
// equal-area octahedral image oriented by the current transform; a non-square image is
// taken as lat-long with a warning), and AreaLightSource "diffuse" (L, twosided).
// All take "scale"; point, spot and area lights take "power", distant and infinite
// "illuminance" (uniform only). Spectra are photometrically normalised as pbrt-v4 does:
// RGB values come out as written, blackbodies and spectra with luminance 1.
#pragma once

#include <string>

#include "core/transform.h"
#include "io/pbrt/context.h"
#include "io/pbrt/material_factory.h"
#include "io/pbrt/parameters.h"
#include "io/scene_builder.h"

namespace caustica::pbrt {

struct AreaLightDesc {
  Rgb radiance;  // after scale and normalisation, before power
  bool two_sided = false;
  float power = -1;  // > 0: pbrt-v4 rescales each shape (each triangle) to emit this power
  SourceLocation where;
};

AreaLightDesc make_area_light(const std::string& type, const ParamList& params,
                              const SourceLocation& where, LoaderContext& ctx);

// Adds the light to `builder` (nothing if unsupported, with a warning).
void add_light_source(const std::string& type, const ParamList& params, const SourceLocation& where,
                      const Transform& light_to_world, MaterialFactory& images,
                      SceneBuilder& builder, LoaderContext& ctx);

}  // namespace caustica::pbrt
