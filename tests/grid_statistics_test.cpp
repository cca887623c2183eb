// adaptive-vcm's pooling of per-pixel estimates (integrators/bidir/grid_statistics.h): the box
// filter against the mean over each clamped window, its infinities, and its independence of the
// thread count.
#include "integrators/bidir/grid_statistics.h"

#include <gtest/gtest.h>
#include <tbb/task_arena.h>

#include <cmath>
#include <cstring>
#include <limits>
#include <random>
#include <vector>

namespace caustica::bidir {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

// The mean of the finite values in the (2r + 1)^2 window clamped to the image, or infinity where
// the window holds a value that is not finite.
double window_mean(const std::vector<double>& in, int w, int h, int r, int x, int y) {
  double sum = 0;
  int count = 0;
  for (int yy = std::max(0, y - r); yy <= std::min(h - 1, y + r); ++yy)
    for (int xx = std::max(0, x - r); xx <= std::min(w - 1, x + r); ++xx) {
      const double v = in[size_t(yy) * w + xx];
      if (!std::isfinite(v)) return kInf;
      sum += v;
      ++count;
    }
  return sum / count;
}

std::vector<double> random_image(int w, int h, uint32_t seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(-1.0, 3.0);
  std::vector<double> in(size_t(w) * h);
  for (double& v : in) v = u(rng);
  return in;
}

void expect_window_means(const std::vector<double>& in, int w, int h, int r) {
  const std::vector<double> out = box_blur(in, w, h, r);
  ASSERT_EQ(out.size(), in.size());
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      const double expected = window_mean(in, w, h, r, x, y);
      const double got = out[size_t(y) * w + x];
      if (std::isinf(expected))
        EXPECT_TRUE(std::isinf(got) && got > 0) << x << ", " << y;
      else
        EXPECT_NEAR(got, expected, 1e-12) << x << ", " << y;
    }
}

// Wider than two bands of columns (the filter sweeps columns in bands), with a partial last one.
TEST(BoxBlur, IsTheMeanOverEachClampedWindow) {
  expect_window_means(random_image(150, 37, 1), 150, 37, 3);
  expect_window_means(random_image(64, 5, 2), 64, 5, 3);  // one full band, fewer rows than r
  expect_window_means(random_image(2, 90, 3), 2, 90, 3);  // fewer columns than the radius
  expect_window_means(random_image(1, 1, 4), 1, 1, 3);
}

// A value that is not finite makes every pixel whose window holds it infinite (NaN too), and
// only those: the running sums recover once it leaves the window.
TEST(BoxBlur, InfinityAndNaNSpreadOverTheirWindowOnly) {
  const int w = 131, h = 29;
  std::vector<double> in = random_image(w, h, 5);
  in[size_t(4) * w + 70] = kInf;
  in[size_t(20) * w + 2] = std::numeric_limits<double>::quiet_NaN();
  in[size_t(28) * w + 130] = kInf;
  expect_window_means(in, w, h, 3);
}

// The pooled values, bit for bit, do not depend on how many threads compute them.
TEST(BoxBlur, IsTheSameForAnyThreadCount) {
  const int w = 200, h = 61;
  const std::vector<double> in = random_image(w, h, 6);
  std::vector<double> one, two;
  tbb::task_arena(1).execute([&] { one = box_blur(in, w, h, 3); });
  tbb::task_arena(2).execute([&] { two = box_blur(in, w, h, 3); });
  ASSERT_EQ(one.size(), two.size());
  EXPECT_EQ(0, std::memcmp(one.data(), two.data(), one.size() * sizeof(double)));
}

}  // namespace
}  // namespace caustica::bidir
