// Pixel filters as pbrt-v4 has them (box, gaussian, triangle, mitchell, sinc), applied by filter
// importance sampling. Pixel p, with centre c_p = (x + 1/2, y + 1/2) in raster space, estimates
//
//   I_p = integral f(r - c_p) L(r) dr / integral f                                   (1)
//
// Camera rays: pixel p traces the raster point c_p + o with the offset o drawn from
// pdf(o) = |f(o)| / integral |f|, and its sample is L times weight(o) = f(o) / (integral f pdf(o))
// = sign f(o) integral |f| / integral f: +1 everywhere for a positive filter, so a pixel stays
// the plain average of its samples (pbrt-v4's filter importance sampling).
// Light-tracing splats: a vertex seen at raster point r adds to every pixel p whose support
// holds r, with the weight f(r - c_p) / integral f = weight(o) pdf(o), o = r - c_p; the MIS of
// the bidirectional core takes pdf(o) as the raster density of pixel p's camera technique.
//
// All five filters are separable, f(x, y) = f_x(x) f_y(y), so each axis is sampled on its own:
// box and triangle exactly; gaussian, mitchell and sinc from a table of f_x at the centres of
// 32 cells per unit of radius (pbrt-v4's FilterSampler, whose 2D table is the product of these
// two). As in pbrt-v4 those are rendered with the tabulated (piecewise-constant) filter:
// weights, pdfs and splats all come from the table, so camera samples and splats estimate the
// same I_p exactly. evaluate() and integral() are the analytic filter.
//
// Supports are half-open, -r <= o < r per axis, so with the box of radius 1/2 a raster point
// belongs to exactly one pixel, with weight and pdf 1 (SmallVCM's uniform jitter).
#pragma once

#include <algorithm>
#include <cmath>
#include <vector>

#include "core/distribution.h"
#include "core/vec.h"
#include "geometry/pixel_filter_params.h"

namespace caustica {

struct FilterSample {
  Vec2 offset;       // from the pixel centre, in pixels
  float pdf = 0;     // density of offset per unit raster area: |f| / integral |f|
  float weight = 0;  // f / (integral f * pdf): sign(f) integral |f| / integral f
};

// A camera sample of one pixel: where its ray crosses the film, and the offset's pdf and weight.
struct CameraFilterSample {
  Vec2 raster;
  float pdf = 0;
  float weight = 0;
};

class PixelFilter {
 public:
  PixelFilter() : PixelFilter(PixelFilterParams{}) {}
  // Throws std::invalid_argument for a non-positive radius or a filter whose integral is not
  // positive.
  explicit PixelFilter(const PixelFilterParams& params);

  const PixelFilterParams& params() const { return params_; }
  Vec2 radius() const { return params_.radius; }
  // f(offset), pbrt-v4's Filter::Evaluate (zero outside the support).
  float evaluate(Vec2 offset) const { return x_.evaluate(offset.x) * y_.evaluate(offset.y); }
  // The integral of f over its support (analytic; numeric for sinc).
  float integral() const { return x_.integral * y_.integral; }

  // An offset with density pdf = |f| / integral |f|, u uniform in [0, 1)^2.
  FilterSample sample(Vec2 u) const;
  // What sample() reports for `offset`: its pdf (0 outside the support) and weight.
  FilterSample at(Vec2 offset) const;
  // Pixel (x, y)'s camera sample for u: its centre plus sample(u).
  CameraFilterSample sample_camera(int x, int y, Vec2 u) const;

  // Calls fn(x, y, const FilterSample&) for each pixel of a width x height film whose support
  // holds raster point `raster` (pdf > 0), with offset = raster - c_p. A splat adds its value
  // times pdf * weight (= f / integral f) to each.
  template <typename Fn>
  void for_each_pixel(Vec2 raster, int width, int height, Fn&& fn) const;

  // The pixels for_each_pixel considers for `raster`, [x0, x1] x [y0, y1] (empty when x0 > x1
  // or y0 > y1): every pixel whose support holds raster is among them (the range is one pixel
  // wider than the support against rounding).
  struct PixelRange {
    int x0, x1, y0, y1;
  };
  PixelRange candidate_pixels(Vec2 raster, int width, int height) const {
    // Pixel x's support holds raster.x iff -r <= raster.x - (x + 1/2) < r.
    const Vec2 r = radius();
    return {std::max(0, int(std::floor(raster.x - 0.5f - r.x))),
            std::min(width - 1, int(std::floor(raster.x - 0.5f + r.x)) + 1),
            std::max(0, int(std::floor(raster.y - 0.5f - r.y))),
            std::min(height - 1, int(std::floor(raster.y - 0.5f + r.y)) + 1)};
  }

 private:
  // One axis: f_x, its integral, and its sampling (exact or tabulated).
  struct Axis {
    PixelFilterKind kind = PixelFilterKind::Box;
    float radius = 0.5f;
    float sigma = 0.5f, b = 0, c = 0, tau = 3, gauss_at_radius = 0;
    float integral = 1;
    // Tabulated kinds: f at the cell centres, |f| as a distribution, integral |f| / integral f.
    std::vector<float> table;
    Distribution1D distribution;
    float weight_scale = 1;

    Axis() = default;
    Axis(const PixelFilterParams& params, float radius);
    float evaluate(float x) const;
    float sample(float u, float* pdf, float* weight) const;
    float pdf(float x, float* weight) const;
  };

  PixelFilterParams params_;
  Axis x_, y_;
};

template <typename Fn>
void PixelFilter::for_each_pixel(Vec2 raster, int width, int height, Fn&& fn) const {
  // Axis::pdf decides among the candidate pixels.
  const auto [x0, x1, y0, y1] = candidate_pixels(raster, width, height);
  for (int y = y0; y <= y1; ++y) {
    FilterSample s;
    s.offset.y = raster.y - (float(y) + 0.5f);
    float weight_y;
    const float pdf_y = y_.pdf(s.offset.y, &weight_y);
    if (!(pdf_y > 0)) continue;
    for (int x = x0; x <= x1; ++x) {
      s.offset.x = raster.x - (float(x) + 0.5f);
      float weight_x;
      const float pdf_x = x_.pdf(s.offset.x, &weight_x);
      if (!(pdf_x > 0)) continue;
      s.pdf = pdf_x * pdf_y;
      s.weight = weight_x * weight_y;
      fn(x, y, s);
    }
  }
}

}  // namespace caustica
