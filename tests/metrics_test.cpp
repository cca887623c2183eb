// Error metrics against hand-computed values on tiny images.
#include "image/metrics.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <stdexcept>

#include "image/image.h"
#include "image/tonemap.h"

namespace caustica {
namespace {

// ref = [(1,1,1), (0,0,0)], img = [(2,1,1), (0,0,3)]: squared errors 1 and 9 among 6 values.
struct TwoPixels {
  Image img{2, 1}, ref{2, 1};
  TwoPixels() {
    ref.at(0, 0) = Rgb(1, 1, 1);
    ref.at(1, 0) = Rgb(0, 0, 0);
    img.at(0, 0) = Rgb(2, 1, 1);
    img.at(1, 0) = Rgb(0, 0, 3);
  }
};

TEST(Metrics, MseAndRmseKnownValues) {
  TwoPixels p;
  EXPECT_DOUBLE_EQ(mse(p.img, p.ref), 10.0 / 6.0);
  EXPECT_DOUBLE_EQ(rmse(p.img, p.ref), std::sqrt(10.0 / 6.0));
  EXPECT_EQ(mse(p.ref, p.ref), 0.0);
}

TEST(Metrics, RelMseNormalisesEachChannelByItsReference) {
  TwoPixels p;
  // Channel r of pixel 0: 1 / (1 + 0.01); channel b of pixel 1: 9 / (0 + 0.01).
  EXPECT_DOUBLE_EQ(rel_mse(p.img, p.ref), (1.0 / 1.01 + 9.0 / 0.01) / 6.0);
  EXPECT_DOUBLE_EQ(rel_mse(p.img, p.ref, 1.0), (1.0 / 2.0 + 9.0 / 1.0) / 6.0);
}

TEST(Metrics, TrimmingRemovesExactlyTheOutlier) {
  Image ref(10, 10, Rgb(1.f)), img(10, 10, Rgb(1.5f, 1.f, 1.f));
  img.at(3, 7) = Rgb(9.f);  // One firefly among 100 pixels.
  const double typical = 0.25 / 1.01 / 3.0;
  const double outlier = 64.0 / 1.01;
  EXPECT_NEAR(rel_mse(img, ref), (99 * typical + outlier) / 100, 1e-12);
  EXPECT_NEAR(rel_mse_trimmed(img, ref, 0.0), rel_mse(img, ref), 1e-12);
  EXPECT_NEAR(rel_mse_trimmed(img, ref, 0.001), rel_mse(img, ref), 1e-12);  // floor(0.1) = 0.
  EXPECT_NEAR(rel_mse_trimmed(img, ref, 0.01), typical, 1e-15);
  EXPECT_NEAR(rel_mse_trimmed(img, ref, 0.019), typical, 1e-15);  // Still one pixel.
  EXPECT_NEAR(rel_mse_trimmed(img, ref, 0.5), typical, 1e-15);    // Only typical pixels left.
  EXPECT_THROW(rel_mse_trimmed(img, ref, 1.0), std::invalid_argument);
  EXPECT_THROW(rel_mse_trimmed(img, ref, -0.1), std::invalid_argument);
}

TEST(Metrics, TrimmingDropsNonFinitePixelsFirst) {
  Image ref(10, 10, Rgb(1.f)), img(10, 10, Rgb(1.5f, 1.f, 1.f));
  img.at(0, 0) = Rgb(NAN);
  EXPECT_TRUE(std::isnan(rel_mse(img, ref)));
  EXPECT_NEAR(rel_mse_trimmed(img, ref, 0.01), 0.25 / 1.01 / 3.0, 1e-15);
}

TEST(Metrics, SizeMismatchThrows) {
  const Image a(4, 3), b(3, 4), empty;
  EXPECT_THROW(mse(a, b), std::invalid_argument);
  EXPECT_THROW(rmse(a, b), std::invalid_argument);
  EXPECT_THROW(rel_mse(a, b), std::invalid_argument);
  EXPECT_THROW(rel_mse_trimmed(a, b), std::invalid_argument);
  EXPECT_THROW(ssim(a, b), std::invalid_argument);
  EXPECT_THROW(mse(empty, empty), std::invalid_argument);
}

// A smooth gradient, plus deterministic noise of the given amplitude.
Image noisy_gradient(int size, float noise) {
  Image image(size, size);
  uint32_t state = 12345;
  for (int y = 0; y < size; ++y)
    for (int x = 0; x < size; ++x) {
      state = state * 1664525u + 1013904223u;
      const float n = noise * (float(state >> 8) / float(1u << 24) - 0.5f);
      image.at(x, y) = Rgb(0.05f + 0.8f * x / size + n, 0.3f + 0.4f * y / size + n, 0.2f);
    }
  return image;
}

TEST(Metrics, SsimOfIdenticalImagesIsOne) {
  const Image image = noisy_gradient(24, 0.2f);
  EXPECT_NEAR(ssim(image, image), 1.0, 1e-12);
}

TEST(Metrics, SsimDropsWithNoiseAndIsSymmetric) {
  const Image clean = noisy_gradient(32, 0.f);
  const Image slightly = noisy_gradient(32, 0.02f), very = noisy_gradient(32, 0.3f);
  const double s_slight = ssim(slightly, clean), s_very = ssim(very, clean);
  EXPECT_LT(s_slight, 1.0);
  EXPECT_LT(s_very, s_slight);
  EXPECT_GT(s_very, 0.0);
  EXPECT_DOUBLE_EQ(ssim(clean, very), s_very);
}

TEST(Metrics, SsimOfConstantImagesIsTheLuminanceTerm) {
  // No variance: SSIM = (2 a b + C1) / (a^2 + b^2 + C1) with a, b the display luminances.
  // The images are smaller than the 11x11 window, which the clipped window handles.
  const double c1 = 1e-4;
  // White's luminance is 1 to float precision (the Rec.709 weights are rounded to float).
  EXPECT_NEAR(ssim(Image(3, 3, Rgb(1.f)), Image(3, 3, Rgb(0.f))), c1 / (1 + c1), 1e-10);
  const double a = linear_to_srgb(0.5f), b = 1.0;  // Linear 7 tone maps to 1.
  EXPECT_NEAR(ssim(Image(5, 2, Rgb(0.5f)), Image(5, 2, Rgb(7.f))),
              (2 * a * b + c1) / (a * a + b * b + c1), 1e-6);
}

TEST(Metrics, SsimUsesToneMappedLuminance) {
  // Values above 1 are all white after tone mapping, so they are indistinguishable.
  EXPECT_NEAR(ssim(noisy_gradient(16, 0.f), noisy_gradient(16, 0.f)), 1.0, 1e-12);
  Image bright(8, 8, Rgb(2.f)), brighter(8, 8, Rgb(50.f));
  brighter.at(4, 4) = Rgb(3.f);
  EXPECT_NEAR(ssim(bright, brighter), 1.0, 1e-12);
}

}  // namespace
}  // namespace caustica

TEST(Metrics, BlockRelMseSeesBiasNotNoise) {
  // Zero-mean checkerboard noise cancels within 2x2 blocks; a constant offset does not.
  caustica::Image ref(4, 4, caustica::Rgb(1.f)), noisy = ref, biased = ref;
  for (int y = 0; y < 4; ++y)
    for (int x = 0; x < 4; ++x) {
      noisy.at(x, y) = caustica::Rgb((x + y) % 2 ? 1.5f : 0.5f);
      biased.at(x, y) = caustica::Rgb(1.1f);
    }
  EXPECT_NEAR(caustica::block_rel_mse(noisy, ref, 2), 0.0, 1e-12);
  EXPECT_GT(caustica::rel_mse(noisy, ref), 0.2);
  EXPECT_NEAR(caustica::block_rel_mse(biased, ref, 2), 0.01 / 1.01, 1e-6);
  EXPECT_NEAR(caustica::mean_ratio(biased, ref), 1.1, 1e-6);
  // A partial border block averages only its own pixels.
  EXPECT_NEAR(caustica::block_rel_mse(biased, ref, 3), 0.01 / 1.01, 1e-6);
}
