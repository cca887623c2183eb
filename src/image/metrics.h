// Error metrics between an image and a reference, as used by equal-time comparisons.
// All metrics average over every pixel and the three channels, accumulate in double, and throw
// std::invalid_argument when the two images differ in size (or are empty). Non-finite pixels
// are not filtered: they make MSE and relMSE non-finite, which a comparison should notice.
#pragma once

#include "image/image.h"

namespace caustica {

// Mean over pixels and channels of (img - ref)^2.
double mse(const Image& img, const Image& ref);
double rmse(const Image& img, const Image& ref);
// Relative MSE: mean over pixels and channels of (img - ref)^2 / (ref^2 + eps), each channel
// normalised by its own reference value.
double rel_mse(const Image& img, const Image& ref, double eps = 0.01);
// relMSE after discarding the floor(trim_fraction * pixel_count) pixels with the largest
// per-pixel relMSE (the three channels' average), so a few fireflies do not dominate.
// trim_fraction must lie in [0, 1).
double rel_mse_trimmed(const Image& img, const Image& ref, double trim_fraction = 0.001,
                       double eps = 0.01);
// relMSE of the images averaged over block x block pixel tiles (a partial tile at the border
// averages what it has): per-pixel noise averages out, so what remains is mostly bias, such as
// light leaking through a wall. block must be >= 1.
double block_rel_mse(const Image& img, const Image& ref, int block = 16, double eps = 0.01);
// Mean of img over mean of ref (channel averages); 1 for an unbiased image in the limit.
double mean_ratio(const Image& img, const Image& ref);
// Mean SSIM (Wang et al. 2004) of the luminance (Rec.709 weights) of tonemap_srgb(·, 0) of
// each image: 11x11 Gaussian window with sigma 1.5, K1 = 0.01, K2 = 0.03, dynamic range 1.
// At the borders the window is clipped to the image and renormalised, so every pixel counts and
// images smaller than the window work. 1 for identical images; symmetric in its arguments.
double ssim(const Image& img, const Image& ref);

}  // namespace caustica
