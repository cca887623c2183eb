// Helpers shared by integrator tests: render a scene with an integrator at a fixed budget.
#pragma once

#include <tbb/global_control.h>

#include <cmath>
#include <memory>
#include <string>
#include <vector>

#include "image/image.h"
#include "integrators/registry.h"
#include "render/renderer.h"
#include "scene/scene.h"

namespace caustica::test {

inline RenderResult render_with(const Scene& scene, const std::string& integrator, int spp,
                                IntegratorSettings settings = {}, int threads = 0) {
  std::unique_ptr<tbb::global_control> limit;
  if (threads > 0)
    limit = std::make_unique<tbb::global_control>(tbb::global_control::max_allowed_parallelism,
                                                  threads);
  auto in = make_integrator(integrator, settings);
  if (!in) throw std::runtime_error("unknown integrator " + integrator);
  RenderBudget budget;
  budget.spp = spp;
  RenderCallbacks cb;
  cb.quiet = true;
  return render(scene, *in, budget, cb);
}

// Mean and standard error of the per-pixel luminance-free channel average, treating pixels
// as independent estimates of the same value (valid for the furnace scenes).
struct PixelStats {
  double mean = 0, standard_error = 0, min = 0, max = 0;
};
inline PixelStats pixel_stats(const Image& img) {
  double s = 0, s2 = 0, mn = 1e30, mx = -1e30;
  const size_t n = img.pixel_count();
  for (size_t i = 0; i < n; ++i) {
    const double v = img[i].average();
    s += v;
    s2 += v * v;
    mn = std::min(mn, v);
    mx = std::max(mx, v);
  }
  const double mean = s / n;
  const double var = std::max(0.0, s2 / n - mean * mean) * n / (n - 1);
  return {mean, std::sqrt(var / n), mn, mx};
}

// Mean and standard error of a statistic over independent renders: fn(seed) for `runs` seeds
// from first_seed on. The standard error comes from the spread of the per-run values, so it is
// valid even when pixels of one render are correlated (bidirectional pixels share light paths).
struct SeedStats {
  double mean = 0, standard_error = 0;
};
template <typename Fn>
SeedStats over_seeds(int runs, Fn&& fn, uint64_t first_seed = 100) {
  std::vector<double> v;
  for (int k = 0; k < runs; ++k) v.push_back(fn(first_seed + uint64_t(k)));
  double m = 0, s = 0;
  for (double x : v) m += x;
  m /= runs;
  for (double x : v) s += (x - m) * (x - m);
  return {m, std::sqrt(s / (runs - 1) / runs)};
}

}  // namespace caustica::test
