// Chi-square goodness-of-fit test of a direction sampler against its density, in the style of
// Mitsuba's and pbrt-v4's BSDF tests: histogram the samples over a (cos theta, phi) grid of the
// sphere, integrate the claimed pdf over each cell numerically, pool cells whose expected count
// is small, and compare with the chi-square distribution.
#pragma once

#include <functional>
#include <optional>
#include <string>

#include "core/rng.h"
#include "core/vec.h"

namespace caustica::test {

struct DirectionSample {
  Vec3 w;     // unit direction (any frame, as long as pdf() uses the same)
  float pdf;  // what the sampler reports for w
};

struct Chi2Result {
  bool passed = false;
  double p_value = 0;
  double statistic = 0;
  int dof = 0;
  double sampled_mass = 0;  // fraction of samples that succeeded
  double pdf_integral = 0;  // integral of pdf over the sphere (should be <= 1)
  std::string message;      // diagnostics when failing
};

struct Chi2Options {
  int theta_bins = 10, phi_bins = 20;
  int sample_count = 200000;
  double significance = 0.01;  // Sidak-corrected by the caller if it runs many tests
  int min_expected = 5;
  uint64_t seed = 7;
};

// `sample` returns nothing for failed samples (they count as lost mass, which must equal
// 1 - integral of pdf). Densities are in solid angle over the full sphere.
Chi2Result chi2_test(const std::function<std::optional<DirectionSample>(Pcg32&)>& sample,
                     const std::function<float(Vec3)>& pdf, const Chi2Options& options = {});

// Integral of f over the sphere by stratified quadrature on the (cos theta, phi) grid.
double integrate_sphere(const std::function<double(Vec3)>& f, int theta_res = 256,
                        int phi_res = 512);

}  // namespace caustica::test
