// Statistics over adaptive-vcm's grid of probed pixels (adaptive_plan.h): the pooling of
// per-pixel estimates over neighbours, a robust quantile, and parallel loops over fixed blocks
// of pixels whose partial sums are the same for any thread count.
#pragma once

#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <vector>

namespace caustica::bidir {

// The q-quantile of the finite values (0 if none).
double finite_quantile(const std::vector<double>& values, double q);

// Separable box filter of the given radius (clamped at the borders): a pixel's variance estimate
// rests on a handful of probe samples; choosing per pixel between two such estimates picks the
// luckier one (a caustic pixel whose probes missed the caustic stops merging). Neighbours share
// their light transport, so their estimates are pooled.
// An infinite variance (a path the candidate cannot make) makes every pixel whose window holds
// it infinite; it is counted, not summed: inf - inf in the running sum made the rest of the row
// NaN, and a NaN in every candidate's sum left the choice to its default, path tracing, which
// cannot make the path either (sun-glass: the sun's caustic seen through the glass ball).
std::vector<double> box_blur(const std::vector<double>& in, int w, int h, int r);

constexpr size_t kPixelBlock = 4096;  // the blocks of for_pixel_blocks

// fn(block, begin, end) over [0, n) in blocks of a fixed size, in parallel: per-block partial sums
// added in block order afterwards are the same for any thread count.
template <typename Fn>
void for_pixel_blocks(size_t n, Fn&& fn) {
  tbb::parallel_for(size_t(0), (n + kPixelBlock - 1) / kPixelBlock,
                    [&](size_t b) { fn(b, b * kPixelBlock, std::min(n, (b + 1) * kPixelBlock)); });
}

// The sum over [0, n) of the finite values of value(p), the same for any thread count.
template <typename Fn>
double finite_sum(size_t n, Fn&& value) {
  std::vector<double> blocks((n + kPixelBlock - 1) / kPixelBlock);
  for_pixel_blocks(n, [&](size_t b, size_t begin, size_t end) {
    double sum = 0;
    for (size_t p = begin; p < end; ++p) {
      const double x = value(p);
      if (std::isfinite(x)) sum += x;
    }
    blocks[b] = sum;
  });
  double total = 0;
  for (double x : blocks) total += x;
  return total;
}

}  // namespace caustica::bidir
