// adaptive-vcm's per-pixel modes under one candidate configuration (AdaptivePlan::choose,
// adaptive_choice.cpp): from each probed pixel's predicted relative variance in each mode
// (path tracing alone, the bidirectional core, the core and merging, photon mapping alone) and
// what a pixel costs per iteration in each, the modes of lowest total variance x total cost.
#pragma once

#include <vector>

#include "integrators/bidir/adaptive_plan.h"

namespace caustica::bidir {

// One candidate's decision per pixel, and its sums over the pixels.
struct PixelChoice {
  std::vector<PixelMode> modes;
  std::vector<double> variances;  // of the mode each pixel took
  double variance = 0;            // the finite ones'
  double cost = 0;                // microseconds per iteration
  double missing = 0;             // pixels of infinite variance
  double variance_no_merge = 0, variance_all_merge = 0, variance_all_stop = 0;
};

// What a pixel costs per iteration in each mode under one candidate: the image's mean, and with
// weights, per pixel (at()).
struct ModePrices {
  double core = 0, merge_extra = 0, path_traced = 0, stopped = 0;
  // The light paths' share of core and of path_traced: the same in every pixel.
  double core_light = 0, path_traced_light = 0;
  // Per pixel, its camera vertices relative to the image's mean (AdaptivePlan::pixel_vertices_):
  // what scales the camera passes' part of core, merge_extra and path_traced. stopped stays
  // the mean (photon mapping's camera subpath ends at its first non-delta vertex).
  const std::vector<double>* weights = nullptr;
  ModePrices at(size_t p) const {
    if (!weights) return *this;
    const double w = (*weights)[p];
    ModePrices q = *this;
    q.core = core_light + (core - core_light) * w;
    q.merge_extra = merge_extra * w;
    q.path_traced = path_traced_light + (path_traced - path_traced_light) * w;
    q.weights = nullptr;
    return q;
  }
};

// How a pixel's (variance, cost) in a mode is scored: their product (each pixel's own
// efficiency), or, with weights, variance / V + cost / C for the means V and C over the image of
// a choice (Lagrange). What a candidate minimises is the image's total variance x total cost;
// moving pixel p from mode a to b changes it by about C dv + V dc, so the best modes are those
// of lowest dv / V + dc / C given the optimum's V and C. The product rule normalises by the
// pixel's own v and c instead: it pays for variance where a pixel's is small (an easy pixel's
// core beside path tracing) and spares it where it is large; and the light paths' share of the
// cost, the same in every mode of a pixel, cancels from the sum but not from the product.
struct ModeScore {
  double per_variance = 0, per_cost = 0;  // 1 / V, 1 / C; 0: the product
  double operator()(double v, double c) const {
    return per_variance > 0 ? v * per_variance + c * per_cost : v * c;
  }
};

// Per pixel, the option of lowest score (ModeScore): path tracing alone (where it is as good as
// the light paths' techniques, it is cheaper: a caustic that only light paths make need not make
// every pixel pay for the bidirectional core), the core, or the core and merging; photon mapping
// alone where it beats the core (ppm's estimator: a caustic seen on a diffuse surface needs no
// connections or light tracing there). stops: photon mapping's variances (none: not an option);
// path_tracing_only: the candidate without light paths.
PixelChoice choose_pixel_modes(const std::vector<double>& no_merge,
                               const std::vector<double>& merge, const std::vector<double>& pt,
                               const std::vector<double>* stops, const ModePrices& price,
                               bool path_tracing_only, const ModeScore& score = {});

// The per-pixel modes of lowest total variance x total cost: the product rule's, then
// kLagrangePasses passes of the Lagrange rule at the means of the choice before (ModeScore),
// keeping the lowest predicted total (fewest pixels missing energy first).
PixelChoice choose_modes(const std::vector<double>& no_merge, const std::vector<double>& merge,
                         const std::vector<double>& pt, const std::vector<double>* stops,
                         const ModePrices& price, bool path_tracing_only);

}  // namespace caustica::bidir
