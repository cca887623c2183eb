#include "integrators/bidir/pixel_modes.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>

#include "integrators/bidir/grid_statistics.h"

namespace caustica::bidir {

namespace {
// A pixel path traces alone only where its predicted variance is at most this much above the
// core's: the prediction is that of path tracing under the balance heuristic (the candidate
// without light paths) while pt's estimator uses the power heuristic, and a pixel's rare bright
// paths are the least predictable part. 20 s, 1 thread, seeds 0 / 1, relMSE: veach-mis without
// the bound 0.000696 / 0.000692, with 1.0 0.000620 / 0.000584, with 1.1 0.000684 / 0.000643
// (before pixels could path trace: 0.000666 / 0.000622); sun-glass 0.000339 / 0.000324,
// 0.000586 / 0.000420, 0.000362 / 0.000320; material-spheres 0.000257 / 0.000278, 0.000264 /
// 0.000276, 0.000253 / 0.000257.
constexpr double kPathTracingPixelMargin = 1.1;
constexpr int kLagrangePasses = 2;  // choose_modes
}  // namespace

PixelChoice choose_pixel_modes(const std::vector<double>& no_merge,
                               const std::vector<double>& merge, const std::vector<double>& pt,
                               const std::vector<double>* stops, const ModePrices& prices,
                               bool path_tracing_only, const ModeScore& score) {
  const size_t n = pt.size();
  PixelChoice out;
  out.modes.resize(n);
  out.variances.resize(n);
  // Per block of pixels: finite variance, cost, variance without and with merging and with
  // photon mapping everywhere, pixels of infinite variance.
  std::vector<std::array<double, 6>> blocks((n + kPixelBlock - 1) / kPixelBlock);
  for_pixel_blocks(n, [&](size_t b, size_t begin, size_t end) {
    std::array<double, 6> sum{};
    for (size_t p = begin; p < end; ++p) {
      const ModePrices price = prices.at(p);
      const double v0 = no_merge[p], v1 = merge[p], vt = pt[p];
      const double vs = stops ? (*stops)[p] : std::numeric_limits<double>::infinity();
      sum[2] += v0;
      sum[3] += v1;
      sum[5] += vs;
      // The core, with merging where that is better; path tracing where it beats both.
      double v = v0, pixel_cost = price.core;
      out.modes[p] = PixelMode::Bidirectional;
      if (score(v1, price.core + price.merge_extra) < score(v0, price.core)) {
        v = v1;
        pixel_cost = price.core + price.merge_extra;
        out.modes[p] = PixelMode::Merge;
      }
      if (score(vs, price.stopped) < score(v, pixel_cost)) {
        v = vs;
        pixel_cost = price.stopped;
        out.modes[p] = PixelMode::Stop;
      }
      if (path_tracing_only ||
          (score(vt, price.path_traced) <= score(v, pixel_cost) && std::isfinite(vt) &&
           vt <= kPathTracingPixelMargin * std::min(v0, v1))) {
        v = vt;
        pixel_cost = price.path_traced;
        out.modes[p] = PixelMode::PathTrace;
      }
      out.variances[p] = v;
      if (std::isfinite(v))
        sum[0] += v;
      else
        sum[4] += 1;
      sum[1] += pixel_cost;
    }
    blocks[b] = sum;
  });
  for (const std::array<double, 6>& sum : blocks) {
    out.variance += sum[0];
    out.cost += sum[1];
    out.variance_no_merge += sum[2];
    out.variance_all_merge += sum[3];
    out.missing += sum[4];
    out.variance_all_stop += sum[5];
  }
  return out;
}

PixelChoice choose_modes(const std::vector<double>& no_merge, const std::vector<double>& merge,
                         const std::vector<double>& pt, const std::vector<double>* stops,
                         const ModePrices& price, bool path_tracing_only) {
  PixelChoice best = choose_pixel_modes(no_merge, merge, pt, stops, price, path_tracing_only);
  if (path_tracing_only) return best;
  const double n = double(pt.size());
  double missing = best.missing, variance = best.variance, cost = best.cost;  // the last pass's
  for (int pass = 0; pass < kLagrangePasses; ++pass) {
    if (!(n > missing) || !(variance > 0) || !(cost > 0)) break;
    PixelChoice next = choose_pixel_modes(no_merge, merge, pt, stops, price, false,
                                          ModeScore{(n - missing) / variance, n / cost});
    missing = next.missing;
    variance = next.variance;
    cost = next.cost;
    if (missing < best.missing ||
        (missing == best.missing && variance * cost < best.variance * best.cost))
      best = std::move(next);
  }
  return best;
}

}  // namespace caustica::bidir
