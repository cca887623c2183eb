// adaptive-vcm's per-pixel modes (integrators/bidir/pixel_modes.h): the modes should minimise
// the image's total variance x total cost, which the rule "each pixel's own variance x cost"
// does not.
#include "integrators/bidir/pixel_modes.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <limits>
#include <random>
#include <vector>

using namespace caustica::bidir;

namespace {

struct Instance {
  std::vector<double> core, merge, pt, stop;
  ModePrices price;
};

double total(const PixelChoice& c) { return c.variance * c.cost; }

// The lowest total variance x total cost over every assignment of modes that choose_pixel_modes
// may make (path tracing only where finite and at most 1.1x the core's variance, as there).
double brute_force(const Instance& in) {
  const size_t n = in.pt.size();
  const std::vector<double>* v[4] = {&in.core, &in.merge, &in.pt, &in.stop};
  const double c[4] = {in.price.core, in.price.core + in.price.merge_extra, in.price.path_traced,
                       in.price.stopped};
  size_t count = 1;
  for (size_t p = 0; p < n; ++p) count *= 4;
  double best = std::numeric_limits<double>::infinity();
  for (size_t code = 0; code < count; ++code) {
    double variance = 0, cost = 0;
    size_t x = code;
    bool allowed = true;
    for (size_t p = 0; p < n && allowed; ++p, x /= 4) {
      const size_t m = x % 4;
      if (m == 2 && !(in.pt[p] <= 1.1 * std::min(in.core[p], in.merge[p]))) allowed = false;
      variance += (*v[m])[p];
      cost += c[m];
    }
    if (allowed) best = std::min(best, variance * cost);
  }
  return best;
}

}  // namespace

// Easy pixels (little variance in any mode) should take the cheapest mode even where the core
// is a little more efficient per pixel, and the hard ones the mode of least variance: with the
// light paths' share of the cost (the same in every mode) in each price, the per-pixel product
// keeps the core everywhere.
TEST(PixelModes, EasyPixelsTakeTheCheapModeHardOnesTheGoodOne) {
  const size_t easy = 90, hard = 10;
  Instance in;
  for (size_t p = 0; p < easy + hard; ++p) {
    const double v = p < easy ? 0.01 : 1.0;
    in.core.push_back(v);
    in.merge.push_back(2 * v);
    in.pt.push_back(1.08 * v);  // within the 1.1 bound on path-traced pixels
    in.stop.push_back(10 * v);
  }
  in.price = {2.75, 0.2, 2.6, 2.7};  // light paths 2.0 of each
  const PixelChoice product =
      choose_pixel_modes(in.core, in.merge, in.pt, &in.stop, in.price, false);
  const PixelChoice chosen = choose_modes(in.core, in.merge, in.pt, &in.stop, in.price, false);
  for (size_t p = 0; p < easy + hard; ++p)
    ASSERT_EQ(product.modes[p], PixelMode::Bidirectional) << p;  // 1.08 x 2.6 > 2.75
  for (size_t p = 0; p < easy + hard; ++p)
    EXPECT_EQ(chosen.modes[p], p < easy ? PixelMode::PathTrace : PixelMode::Bidirectional) << p;
  EXPECT_LT(total(chosen), 0.96 * total(product));
}

// On small random images (8 pixels, every assignment of the four modes tried), the modes chosen
// are within 1% of the lowest total variance x total cost; the per-pixel product is not.
TEST(PixelModes, NearTheLowestTotalOnSmallImages) {
  std::mt19937 rng(7);
  std::normal_distribution<double> log_variance(0.0, 2.0);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  double product_gap = 0, chosen_gap = 0, worst = 0;
  const int instances = 60;
  for (int i = 0; i < instances; ++i) {
    Instance in;
    for (int p = 0; p < 8; ++p) {
      const double v = std::exp(log_variance(rng));
      in.core.push_back(v);
      in.merge.push_back(v * (0.5 + u(rng)));
      in.pt.push_back(v * (0.9 + 0.4 * u(rng)));
      in.stop.push_back(v * (0.3 + 2.7 * u(rng)));
    }
    const double light = 3 * u(rng);
    in.price = {light + 0.75, 0.3, light + 0.6, light + 0.4 + 0.4 * u(rng)};
    const double best = brute_force(in);
    const double product =
        total(choose_pixel_modes(in.core, in.merge, in.pt, &in.stop, in.price, false));
    const double chosen = total(choose_modes(in.core, in.merge, in.pt, &in.stop, in.price, false));
    ASSERT_GE(chosen, best * (1 - 1e-12)) << i;
    EXPECT_LE(chosen, product * (1 + 1e-12)) << i;
    product_gap += product / best - 1;
    chosen_gap += chosen / best - 1;
    worst = std::max(worst, chosen / best - 1);
  }
  std::printf(
      "[ pixel modes ] above the lowest total: product rule %.2f%%, chosen %.3f%% (worst %.3f%%)\n",
      100 * product_gap / instances, 100 * chosen_gap / instances, 100 * worst);
  EXPECT_LT(worst, 0.01);
  EXPECT_GT(product_gap, 4 * chosen_gap);
}

// With per-pixel weights (a pixel's camera vertices over the image's mean), the camera passes'
// part of a mode's price is the pixel's own, the light paths' share stays the same in every
// pixel: among pixels of equal variances the dear ones (many vertices) path trace, where the
// core's extra cost is largest, and the cheap ones keep the core. Without weights every pixel
// takes the same mode.
TEST(PixelModes, DearPixelsPathTraceFirst) {
  const size_t n = 100;
  Instance in;
  std::vector<double> weights;
  for (size_t p = 0; p < n; ++p) {
    in.core.push_back(1.0);
    in.merge.push_back(2.0);
    in.pt.push_back(1.08);
    in.stop.push_back(10.0);
    weights.push_back(p % 2 ? 1.8 : 0.2);  // mean 1
  }
  in.price = {3.0, 0.2, 2.6, 2.7, 2.0, 2.0};  // light paths 2.0 of core and of path tracing
  const PixelChoice uniform = choose_modes(in.core, in.merge, in.pt, &in.stop, in.price, false);
  for (size_t p = 1; p < n; ++p) ASSERT_EQ(uniform.modes[p], uniform.modes[0]) << p;

  in.price.weights = &weights;
  const ModePrices dear = in.price.at(1), cheap = in.price.at(0);
  EXPECT_DOUBLE_EQ(dear.core, 2.0 + 1.8 * 1.0);
  EXPECT_DOUBLE_EQ(cheap.path_traced, 2.0 + 0.2 * 0.6);
  EXPECT_DOUBLE_EQ(dear.merge_extra, 1.8 * 0.2);
  EXPECT_DOUBLE_EQ(dear.stopped, 2.7);
  const PixelChoice chosen = choose_modes(in.core, in.merge, in.pt, &in.stop, in.price, false);
  double cost = 0;
  for (size_t p = 0; p < n; ++p) {
    EXPECT_EQ(chosen.modes[p], p % 2 ? PixelMode::PathTrace : PixelMode::Bidirectional) << p;
    const ModePrices q = in.price.at(p);
    cost += chosen.modes[p] == PixelMode::PathTrace ? q.path_traced : q.core;
  }
  EXPECT_NEAR(chosen.cost, cost, 1e-9 * cost);
  // Better than either mode everywhere, priced per pixel.
  const double all_core = 100.0 * (2.0 * n + 1.0 * n), all_pt = 108.0 * (2.0 * n + 0.6 * n);
  EXPECT_LT(total(chosen), std::min(all_core, all_pt));
}
