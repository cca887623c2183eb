// Error metrics between an image and a reference, as used by equal-time comparisons.
#pragma once

#include "image/image.h"

namespace caustica {

double mse(const Image& img, const Image& ref);
double rmse(const Image& img, const Image& ref);
// Relative MSE: mean over pixels and channels of (img - ref)^2 / (ref^2 + eps).
double rel_mse(const Image& img, const Image& ref, double eps = 0.01);
// relMSE after discarding the `trim_fraction` largest per-pixel errors (outlier-robust).
double rel_mse_trimmed(const Image& img, const Image& ref, double trim_fraction = 0.001, double eps = 0.01);
// SSIM (Wang et al. 2004, 8x8 windows... see .cpp) on tone-mapped luminance.
double ssim(const Image& img, const Image& ref);

}  // namespace caustica
