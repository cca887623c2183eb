#include "image/metrics.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>
#include <vector>

#include "image/tonemap.h"

namespace caustica {
namespace {

void check_same_size(const Image& img, const Image& ref, const char* metric) {
  if (img.width() != ref.width() || img.height() != ref.height())
    throw std::invalid_argument(std::string(metric) + ": image is " + std::to_string(img.width()) +
                                "x" + std::to_string(img.height()) + ", reference is " +
                                std::to_string(ref.width()) + "x" + std::to_string(ref.height()));
  if (img.empty()) throw std::invalid_argument(std::string(metric) + ": empty images");
}

// Mean over channels of (img - ref)^2 / (ref^2 + eps) for one pixel.
double pixel_rel_error(const Rgb& img, const Rgb& ref, double eps) {
  double sum = 0;
  for (int c = 0; c < 3; ++c) {
    const double d = double(img[c]) - double(ref[c]);
    sum += d * d / (double(ref[c]) * double(ref[c]) + eps);
  }
  return sum / 3;
}

// Normalised 1D Gaussian taps for offsets -radius..radius.
std::vector<double> gaussian_taps(int radius, double sigma) {
  std::vector<double> taps(2 * radius + 1);
  double sum = 0;
  for (int i = -radius; i <= radius; ++i)
    sum += taps[i + radius] = std::exp(-0.5 * i * i / (sigma * sigma));
  for (double& t : taps) t /= sum;
  return taps;
}

// Separable Gaussian blur whose window is clipped to the image and renormalised (the taps that
// fall outside are dropped and the rest rescaled to sum to 1).
std::vector<double> blur(const std::vector<double>& in, int width, int height,
                         const std::vector<double>& taps) {
  const int radius = int(taps.size() / 2);
  std::vector<double> rows(in.size()), out(in.size());
  for (int y = 0; y < height; ++y)
    for (int x = 0; x < width; ++x) {
      double sum = 0, weight = 0;
      for (int k = std::max(-radius, -x); k <= std::min(radius, width - 1 - x); ++k) {
        sum += taps[k + radius] * in[size_t(y) * width + x + k];
        weight += taps[k + radius];
      }
      rows[size_t(y) * width + x] = sum / weight;
    }
  for (int y = 0; y < height; ++y)
    for (int x = 0; x < width; ++x) {
      double sum = 0, weight = 0;
      for (int k = std::max(-radius, -y); k <= std::min(radius, height - 1 - y); ++k) {
        sum += taps[k + radius] * rows[size_t(y + k) * width + x];
        weight += taps[k + radius];
      }
      out[size_t(y) * width + x] = sum / weight;
    }
  return out;
}

std::vector<double> display_luminance(const Image& linear) {
  const Image display = tonemap_srgb(linear, 0.f);
  std::vector<double> lum(display.pixel_count());
  for (size_t i = 0; i < lum.size(); ++i) lum[i] = display[i].luminance();
  return lum;
}

}  // namespace

double mse(const Image& img, const Image& ref) {
  check_same_size(img, ref, "mse");
  double sum = 0;
  for (size_t i = 0; i < img.pixel_count(); ++i)
    for (int c = 0; c < 3; ++c) {
      const double d = double(img[i][c]) - double(ref[i][c]);
      sum += d * d;
    }
  return sum / (3.0 * double(img.pixel_count()));
}

double rmse(const Image& img, const Image& ref) { return std::sqrt(mse(img, ref)); }

double rel_mse(const Image& img, const Image& ref, double eps) {
  check_same_size(img, ref, "rel_mse");
  double sum = 0;
  for (size_t i = 0; i < img.pixel_count(); ++i) sum += pixel_rel_error(img[i], ref[i], eps);
  return sum / double(img.pixel_count());
}

double block_rel_mse(const Image& img, const Image& ref, int block, double eps) {
  check_same_size(img, ref, "block_rel_mse");
  if (block < 1) throw std::invalid_argument("block_rel_mse: block must be >= 1");
  const int bw = (img.width() + block - 1) / block, bh = (img.height() + block - 1) / block;
  Image a(bw, bh), b(bw, bh);
  for (int y = 0; y < img.height(); ++y)
    for (int x = 0; x < img.width(); ++x) {
      a.at(x / block, y / block) += img.at(x, y);
      b.at(x / block, y / block) += ref.at(x, y);
    }
  for (int y = 0; y < bh; ++y)
    for (int x = 0; x < bw; ++x) {
      const int n = (std::min(img.width(), (x + 1) * block) - x * block) *
                    (std::min(img.height(), (y + 1) * block) - y * block);
      a.at(x, y) *= 1.f / float(n);
      b.at(x, y) *= 1.f / float(n);
    }
  return rel_mse(a, b, eps);
}

double mean_ratio(const Image& img, const Image& ref) {
  check_same_size(img, ref, "mean_ratio");
  double s_img = 0, s_ref = 0;
  for (size_t i = 0; i < img.pixel_count(); ++i) {
    s_img += img[i].average();
    s_ref += ref[i].average();
  }
  return s_ref > 0 ? s_img / s_ref : 0.0;
}

double rel_mse_trimmed(const Image& img, const Image& ref, double trim_fraction, double eps) {
  check_same_size(img, ref, "rel_mse_trimmed");
  if (!(trim_fraction >= 0 && trim_fraction < 1))
    throw std::invalid_argument("rel_mse_trimmed: trim_fraction must be in [0, 1)");
  std::vector<double> errors(img.pixel_count());
  for (size_t i = 0; i < errors.size(); ++i) errors[i] = pixel_rel_error(img[i], ref[i], eps);
  const size_t trimmed = size_t(std::floor(trim_fraction * double(errors.size())));
  const size_t kept = errors.size() - trimmed;  // >= 1 since trim_fraction < 1.
  // Partition so the `kept` smallest errors come first; NaN errors count as the largest.
  auto less = [](double a, double b) { return std::isnan(b) ? !std::isnan(a) : a < b; };
  if (trimmed > 0) std::nth_element(errors.begin(), errors.begin() + kept - 1, errors.end(), less);
  double sum = 0;
  for (size_t i = 0; i < kept; ++i) sum += errors[i];
  return sum / double(kept);
}

double ssim(const Image& img, const Image& ref) {
  check_same_size(img, ref, "ssim");
  // Wang, Bovik, Sheikh, Simoncelli 2004, eq. 13 with C1 = (K1 L)^2, C2 = (K2 L)^2, L = 1.
  constexpr double kC1 = (0.01 * 1.0) * (0.01 * 1.0), kC2 = (0.03 * 1.0) * (0.03 * 1.0);
  const int width = img.width(), height = img.height();
  const std::vector<double> taps = gaussian_taps(5, 1.5);
  const std::vector<double> x = display_luminance(img), y = display_luminance(ref);
  std::vector<double> xx(x.size()), yy(x.size()), xy(x.size());
  for (size_t i = 0; i < x.size(); ++i) {
    xx[i] = x[i] * x[i];
    yy[i] = y[i] * y[i];
    xy[i] = x[i] * y[i];
  }
  const std::vector<double> mu_x = blur(x, width, height, taps),
                            mu_y = blur(y, width, height, taps);
  const std::vector<double> e_xx = blur(xx, width, height, taps);
  const std::vector<double> e_yy = blur(yy, width, height, taps);
  const std::vector<double> e_xy = blur(xy, width, height, taps);
  double sum = 0;
  for (size_t i = 0; i < x.size(); ++i) {
    const double var_x = e_xx[i] - mu_x[i] * mu_x[i];
    const double var_y = e_yy[i] - mu_y[i] * mu_y[i];
    const double cov = e_xy[i] - mu_x[i] * mu_y[i];
    sum += (2 * mu_x[i] * mu_y[i] + kC1) * (2 * cov + kC2) /
           ((mu_x[i] * mu_x[i] + mu_y[i] * mu_y[i] + kC1) * (var_x + var_y + kC2));
  }
  return sum / double(x.size());
}

}  // namespace caustica
