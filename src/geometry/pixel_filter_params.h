// The pixel filter a scene asks for (pbrt-v4's `PixelFilter` directive): its kind and parameters,
// with pbrt-v4's defaults. Only the description: loaders fill it in, the camera carries it (its
// radius widens the raster region that reaches some pixel), and render/pixel_filter.h evaluates
// and samples it.
//
// Parameters (pbrt-v4 names and defaults, radii in pixels):
//   box       xradius, yradius 0.5
//   gaussian  xradius, yradius 1.5; sigma 0.5
//   triangle  xradius, yradius 2
//   mitchell  xradius, yradius 2; B, C 1/3
//   sinc      xradius, yradius 4; tau 3   (Lanczos-windowed sinc; "lanczos" is accepted too)
#pragma once

#include <optional>
#include <string_view>

#include "core/vec.h"

namespace caustica {

enum class PixelFilterKind { Box, Gaussian, Triangle, Mitchell, Lanczos };

struct PixelFilterParams {
  PixelFilterKind kind = PixelFilterKind::Box;
  Vec2 radius{0.5f, 0.5f};         // half-width of the support along x and y, in pixels
  float sigma = 0.5f;              // gaussian: standard deviation in pixels
  float b = 1.f / 3, c = 1.f / 3;  // mitchell: Mitchell & Netravali's B and C
  float tau = 3;                   // sinc: the Lanczos window is sinc(x / tau)

  // The kind with all of pbrt-v4's defaults.
  static PixelFilterParams defaults(PixelFilterKind kind);
};

// pbrt-v4's name of a filter kind, and the kind of a name (nothing if unknown).
const char* pixel_filter_name(PixelFilterKind kind);
std::optional<PixelFilterKind> pixel_filter_kind(std::string_view name);
// The names pixel_filter_kind() accepts, for error messages.
inline constexpr const char* kPixelFilterNames =
    "box, gaussian, mitchell, sinc (lanczos), triangle";

}  // namespace caustica
