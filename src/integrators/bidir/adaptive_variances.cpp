// adaptive-vcm's predicted variances (AdaptivePlan, adaptive_plan.h): each candidate's per-pixel
// relative variance from the probes' recorded second moments, the film mean's square and
// denominator they are reduced and divided by, the Russian-roulette factors, the correction of
// the fireflies every candidate shares, path tracing's bias where it misses energy, and the
// pixels' cost weights. AdaptivePlan::choose (adaptive_choice.cpp) reads them.
#include <tbb/parallel_for.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>

#include "core/compact_float.h"
#include "integrators/bidir/adaptive_costs.h"
#include "integrators/bidir/adaptive_plan.h"
#include "integrators/bidir/grid_statistics.h"

namespace caustica::bidir {

namespace {
// A pixel's film mean is kept where it differs from its pooled mean by more than this many of
// its standard errors (AdaptivePlan::denominators, the positive-part James-Stein factor).
constexpr double kShrinkSigmas = 2.0;
}  // namespace

double AdaptivePlan::square(size_t p, size_t j, const std::vector<float>& means, Half half) const {
  // Path tracing's estimate there has the mean of the paths it makes (pt_missing_): (mu - miss)^2.
  // The halves (cross-fitting) keep the film's m^2: with one probe each at the first choice, the
  // square of the mean of a different probe made their variances too noisy to pick modes on
  // (cornell-glass 48 x 48 stopped merging on its glass sphere), and the optimism they measure
  // is a difference between two of them, where the common bias cancels.
  const double m = means[p], miss = j == 0 ? pt_missing_[p] / double(probes_) : 0.0;
  return (half == Half::All ? mean_square(p, m) : m * m) - 2 * m * miss + miss * miss;
}

std::vector<double> AdaptivePlan::squares(const std::vector<float>& means, Half half) const {
  std::vector<double> out(grid_pixels_);
  for_pixel_blocks(grid_pixels_, [&](size_t, size_t begin, size_t end) {
    for (size_t p = begin; p < end; ++p) out[p] = square(p, 1, means, half);  // any j > 0
  });
  return out;
}

inline double AdaptivePlan::relative_variance(size_t p, size_t j, double square, Half half) const {
  const size_t i = (p * kCandidates + j) * 3;
  const double all = get_float24(&moments_[i]);
  const int odd_probes = probes_ / 2;
  const double moment = half == Half::All ? all / double(probes_)
                        : half == Half::Odd
                            ? get_float24(&moments_odd_[i]) / double(odd_probes)
                            : (all - get_float24(&moments_odd_[i])) / double(probes_ - odd_probes);
  // Signed: clamped only after pooling (relative_variances).
  return (moment - square) / denominator_[p] * roulette_[j];
}

void AdaptivePlan::relative_variance_rows(size_t first, size_t count, size_t h_begin, size_t h_end,
                                          const std::vector<float>& means,
                                          const std::array<std::vector<double>, 3>& squares,
                                          Rows& out) const {
  constexpr std::array<Half, 3> halves{Half::All, Half::Even, Half::Odd};
  for (size_t h = h_begin; h < h_end; ++h)
    for (size_t k = 0; k < count; ++k) out[h][k].resize(grid_pixels_);
  for_pixel_blocks(grid_pixels_, [&](size_t, size_t begin, size_t end) {
    for (size_t p = begin; p < end; ++p)
      for (size_t h = h_begin; h < h_end; ++h)
        for (size_t k = 0, j = first; k < count; ++k, ++j)
          out[h][k][p] = relative_variance(
              p, j, j == 0 ? square(p, 0, means, halves[h]) : squares[h][p], halves[h]);
  });
}

std::vector<double> AdaptivePlan::denominators(const std::vector<float>& means,
                                               const std::vector<double>* rendered) const {
  std::vector<double> d(grid_pixels_);
  const double k = double(probes_), n = double(probe_iteration());
  if (k < 2 || !(n > 0)) {
    for (size_t p = 0; p < grid_pixels_; ++p) d[p] = double(means[p]) * means[p] + kRelEps;
    return d;
  }
  const std::vector<double> m(means.begin(), means.end());
  const std::vector<double> pooled = box_blur(m, grid_w_, grid_h_, kPoolRadius);
  std::vector<double> own(grid_pixels_);
  for (size_t p = 0; p < grid_pixels_; ++p) own[p] = probe_estimate_variance(p);
  const std::vector<double> pooled_variance = box_blur(own, grid_w_, grid_h_, kPoolRadius);
  for (size_t p = 0; p < grid_pixels_; ++p) {
    // kShrinkSigmas^2 times the film mean's variance, from the larger of the pixel's own and
    // its pooled variance of one probe's estimate: an outlier raises its own, and a pixel whose
    // few probes happened to agree takes its neighbours'. (The film's iterations after the
    // first choice render the choice, not the probe: the probe's variance stands in.)
    const double noise =
        kShrinkSigmas * kShrinkSigmas *
        std::max({own[p], pooled_variance[p], rendered ? (*rendered)[p] : 0.0, 0.0}) / n;
    const double diff = m[p] - pooled[p];
    const double keep = diff * diff > noise ? 1.0 - noise / (diff * diff) : 0.0;
    const double shrunk = pooled[p] + keep * diff;
    d[p] = shrunk * shrunk + kRelEps;
  }
  return d;
}

double AdaptivePlan::mean_square(size_t p, double m) const {
  return mean_square_probes_ > 0 ? mean_square_sums_[p] / double(mean_square_probes_) : m * m;
}

std::vector<double> AdaptivePlan::path_tracing_bias(double weight, double* relative_sum) const {
  // The square of the missed energy's mean, pooled over 7 x 7 as the variances are. The square
  // of a mean over K probes overestimates the square of the bias by the mean's variance; the
  // mean over pairs of different probes of M_k M_l (M_k: probe k's missed energy pooled over the
  // window) does not: ((sum_k M_k)^2 - sum_k M_k^2) / (K (K - 1)). Pooled first, so that a pair
  // counts wherever two probes found the caustic in the same window, not only in one pixel: the
  // same pairs per pixel (unpooled) left sun-glass's sun caustic, which one probe in nine finds
  // in a given pixel, at 1e-11 and chose path tracing. The plain square (the estimate before)
  // put material-spheres' relative bias^2 at 0.0007-0.0034 per pixel at 20 s, where `pt`'s
  // relMSE at 20 s and 60 s (0.00335, 0.00179) leaves room for about 0.001 at most, and its
  // noise chose light paths after every second probe there. With one probe there are no pairs,
  // and the plain square stands.
  const double k = double(probes_);
  std::vector<double> sum(pt_missing_.begin(), pt_missing_.end());
  sum = box_blur(sum, grid_w_, grid_h_, kPoolRadius);  // sum over probes of M_k
  std::vector<double> norm = denominator_;
  norm = box_blur(norm, grid_w_, grid_h_, kPoolRadius);
  std::vector<double> bias(grid_pixels_);
  for (size_t p = 0; p < grid_pixels_; ++p) {
    const double square = k >= 2 ? (sum[p] * sum[p] - pooled_missing_squares_[p]) / (k * (k - 1))
                                 : sum[p] * sum[p] / (k * k);
    bias[p] = std::max(square, 0.0) / norm[p];
  }
  *relative_sum = finite_sum(grid_pixels_, [&](size_t p) { return bias[p]; });
  if (std::isfinite(weight)) {
    for (double& x : bias) x *= weight;
    return bias;
  }
  // Ruled out wherever a probe saw it miss energy, pooled as an infinite variance would be.
  for (size_t p = 0; p < grid_pixels_; ++p) bias[p] = pt_missing_[p] != 0 ? 1.0 : 0.0;
  bias = box_blur(bias, grid_w_, grid_h_, kPoolRadius);
  for (double& x : bias) x = x > 0 ? std::numeric_limits<double>::infinity() : 0.0;
  return bias;
}

double AdaptivePlan::path_tracing_bias_weight(const PixelWork& pw, const CostModel& t) const {
  double n = std::numeric_limits<double>::infinity();
  if (budget_iterations_ > 0) n = budget_iterations_;  // --spp
  if (!(budget_seconds_ > 0 && elapsed_seconds_ > 0)) return n;
  // --time: the iterations so far, and those path tracing would render in the seconds left at
  // the pace the model's costs have run so far (its predicted microseconds per pixel of every
  // iteration, accounted as schedule_next_probe does; before the first choice every iteration
  // was a full probe).
  const uint64_t probe = probe_iteration();
  double spent = 0;
  if (probe_iterations_.empty()) {
    const Candidate probe_config{1.f, kProbeConnections, true};
    const double recorded = double(grid_pixels_) / double(pixels_);
    spent = double(probe + 1) * (base_cost(probe_config, pw, t) + merge_cost(probe_config, pw, t)) *
            (recorded * kProbeRecordingFactor + (1 - recorded));
  } else {
    spent = spent_cost_ + double(probe - probe_iterations_.back() - 1) * last_choice_cost_ +
            probe_cost_;
  }
  const double pt_cost = path_tracing_cost(candidates()[0], pw, t);
  if (!(spent > 0) || !(pt_cost > 0)) return n;
  const double seconds_per_cost = elapsed_seconds_ / spent;
  const double rest = std::max(0.0, budget_seconds_ - elapsed_seconds_);
  return std::min(n, double(probe + 1) + rest / (seconds_per_cost * pt_cost));
}

void AdaptivePlan::update_roulette_factors(const std::vector<float>& means,
                                           const std::vector<double>& squares) {
  roulette_.fill(1.0);
  // Per candidate (in parallel; each in pixel order, so deterministic): its relative variance
  // and the relative roulette difference per pixel, both pooled over 7 x 7 as the variances
  // are, and the mean over the pixels of their ratio, each ratio at least -1 and winsorised at
  // its 99.5th percentile (the own techniques' estimate is heavy-tailed). Not the ratio of the
  // image's sums: where a candidate makes a pixel's paths only with tiny densities
  // (veach-bidir's glass egg seen without merging, 5% of the pixels), its own techniques
  // sampled none of them, and their estimate there is about -1 times the proxy's, which carries
  // most of the image's variance. That sum swamped the +40% of every other pixel (a factor of
  // 1.00 instead of 1.42 for two light paths per pixel without connections, whose choice then
  // rendered 1.5x its prediction).
  // In chunks of kRowCandidates candidates, whose moments each pixel keeps side by side.
  const auto roulette_of = [&](size_t j, std::vector<double>& variance) {
    if (j == 0)
      for (size_t p = 0; p < grid_pixels_; ++p)
        if (pt_missing_[p] != 0) variance[p] = std::numeric_limits<double>::infinity();
    std::vector<double> diff(grid_pixels_);
    for (size_t p = 0; p < grid_pixels_; ++p)
      diff[p] = std::isfinite(variance[p])
                    ? get_float24(&roulette_diff_[(p * kCandidates + j) * 3]) /
                          (double(probes_) * denominator_[p])
                    : 0.0;
    variance = box_blur(variance, grid_w_, grid_h_, kPoolRadius);
    diff = box_blur(diff, grid_w_, grid_h_, kPoolRadius);
    std::vector<double> ratio;
    ratio.reserve(grid_pixels_);
    for (size_t p = 0; p < grid_pixels_; ++p)
      if (std::isfinite(variance[p]) && variance[p] > 0 && std::isfinite(diff[p]))
        ratio.push_back(diff[p] / variance[p]);
    if (ratio.empty()) return;
    const double cap = finite_quantile(ratio, kWinsorize);
    double sum = 0;
    for (double r : ratio) sum += std::max(-1.0, std::min(r, cap));  // cap may lie below -1
    const double factor = 1.0 + sum / double(ratio.size());
    roulette_[j] = std::isfinite(factor) ? std::max(factor, 1.0) : 1.0;
  };
  const std::array<std::vector<double>, 3> all_squares{squares, {}, {}};
  tbb::parallel_for(size_t(0), (kCandidates + kRowCandidates - 1) / kRowCandidates, [&](size_t c) {
    const size_t first = c * kRowCandidates, count = std::min(kRowCandidates, kCandidates - first);
    Rows rows;
    relative_variance_rows(first, count, 0, 1, means, all_squares, rows);
    for (size_t k = 0; k < count; ++k) roulette_of(first + k, rows[0][k]);
  });
}

std::vector<double> AdaptivePlan::shared_firefly_correction(
    const std::vector<float>& means, Half half, const std::vector<double>& squares) const {
  // The part of a pixel's variance every candidate has (the least of them) is winsorised at its
  // 99.5th percentile over the pixels: a firefly that a few probes saw in a handful of pixels,
  // and that every candidate shares, is mostly estimation noise; at full weight it drowns the
  // differences everywhere else and lets the cheapest candidate win. What a candidate has beyond
  // the least (its own fireflies: missing connections, fewer light paths) is kept in full.
  std::vector<double> shared(grid_pixels_);
  for_pixel_blocks(grid_pixels_, [&](size_t, size_t begin, size_t end) {
    for (size_t p = begin; p < end; ++p) {
      // Path tracing where it misses energy is out, as every candidate that does (infinite).
      double least = pt_missing_[p] != 0 ? std::numeric_limits<double>::infinity()
                                         : relative_variance(p, 0, square(p, 0, means, half), half);
      for (size_t j = 1; j < kCandidates; ++j)
        least = std::min(least, relative_variance(p, j, squares[p], half));
      shared[p] = least;
    }
  });
  std::vector<double> sorted = shared;
  const size_t q = std::min(grid_pixels_ - 1, size_t(double(grid_pixels_) * kWinsorize));
  std::nth_element(sorted.begin(), sorted.begin() + q, sorted.end());
  const double cap = sorted[q];
  for (double& x : shared) x = std::isfinite(x) && x > cap ? cap - x : 0.0;
  return shared;
}

void AdaptivePlan::relative_variances(size_t first, size_t count, size_t h_begin, size_t h_end,
                                      const std::vector<float>& means,
                                      const std::array<std::vector<double>, 3>& squares,
                                      const std::array<std::vector<double>, 3>& correction,
                                      const std::vector<double>& unseen, Rows& out) const {
  relative_variance_rows(first, count, h_begin, h_end, means, squares, out);
  for (size_t h = h_begin; h < h_end; ++h)
    for (size_t k = 0; k < count; ++k) {
      std::vector<double>& v = out[h][k];
      for (size_t p = 0; p < grid_pixels_; ++p) v[p] += correction[h][p];
      v = box_blur(v, grid_w_, grid_h_, kPoolRadius);
      for (double& x : v) x = std::max(x, 0.0);  // inf stays inf
      if (!unseen.empty())
        for (size_t p = 0; p < grid_pixels_; ++p) v[p] += unseen[p];
    }
}

std::vector<double> AdaptivePlan::pixel_cost_weights() const {
  std::vector<double> w(grid_pixels_);
  for (size_t p = 0; p < grid_pixels_; ++p) w[p] = double(pixel_vertices_[p]);
  w = box_blur(w, grid_w_, grid_h_, kPoolRadius);
  const double mean = finite_sum(grid_pixels_, [&](size_t p) { return w[p]; }) /
                      std::max(double(grid_pixels_), 1.0);
  for (double& x : w) x = mean > 0 ? x / mean : 1.0;
  return w;
}

}  // namespace caustica::bidir
