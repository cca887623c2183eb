// Choosing adaptive-vcm's configuration from the probes (AdaptivePlan::choose): every
// candidate's per-pixel relative variance from the recorded second moments, its per-pixel modes
// (pixel_modes.h), the candidate of lowest total, and the check of the last choice against
// what rendering it showed (adaptive_plan.h).
#include <tbb/parallel_for.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <nlohmann/json.hpp>

#include "core/compact_float.h"
#include "integrators/bidir/adaptive_costs.h"
#include "integrators/bidir/adaptive_plan.h"
#include "integrators/bidir/grid_statistics.h"
#include "integrators/bidir/pixel_modes.h"

namespace caustica::bidir {

namespace {
// A pixel's film mean is kept where it differs from its pooled mean by more than this many of
// its standard errors (AdaptivePlan::denominators, the positive-part James-Stein factor).
constexpr double kShrinkSigmas = 2.0;
// Path tracing is kept unless another configuration's predicted relVar x time is lower by more
// than this factor. The cost model has no term for the per-iteration costs of light paths (their
// pipeline, the splats), and the predicted variances carry a few percent of noise: on mis-plates
// a quarter of the light paths won by 0.25% of the score while `pt` was 1.09x (20 s) and 1.15x
// (60 s) better. The margin changes no choice where a configuration is predicted 5% better.
constexpr double kPathTracingMargin = 1.05;
// A candidate renders every pixel in one mode instead of its per-pixel mix only where that is
// predicted better by more than this factor: the mix is priced with the modes that half of the
// probes chose (cross_fit), worse than those that all of them choose, so the
// price is high by that. On cornell-glass at 48 x 48 the mix (4% of the pixels merging at the
// caustic) and the core everywhere were priced within 0.1% of each other.
constexpr double kMixMargin = 1.05;

// Candidates compare by the pixels where their variance is infinite (energy they would miss:
// paths none of their techniques there can make), then by score (relative variance x time).
struct Score {
  double missing = std::numeric_limits<double>::infinity();
  double value = std::numeric_limits<double>::infinity();
  bool operator<(const Score& o) const {
    return missing != o.missing ? missing < o.missing : value < o.value;
  }
};

// One candidate's per-pixel variances from one set of probes (every probe, or one half):
// without and with merging, path tracing, photon mapping (null: not an option).
struct PairVariances {
  std::vector<double> no_merge, merge;
  const std::vector<double>* pt = nullptr;
  const std::vector<double>* stops = nullptr;
  const std::vector<double>* of(PixelMode m) const {
    return m == PixelMode::Bidirectional ? &no_merge
           : m == PixelMode::Merge       ? &merge
           : m == PixelMode::PathTrace   ? pt
                                         : stops;
  }
};

// The sum over pixels of the finite values of value(p), the same for any thread count.
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

// A candidate's options: its per-pixel mix of modes, or every pixel in one mode.
enum Variant : size_t { kMixed, kAllCore, kAllMerge, kAllStop, kVariants };
constexpr std::array<const char*, kVariants> kVariantNames{"mixed", "bidirectional", "merge",
                                                           "photon_mapping"};
constexpr std::array<PixelMode, kVariants> kVariantModes{
    PixelMode::Bidirectional, PixelMode::Bidirectional, PixelMode::Merge, PixelMode::Stop};

// The photon-mapping candidate of a light-path factor: its index after kCoreCandidates
// (kStopCandidates: none).
size_t stop_index_of(float factor) {
  const std::vector<AdaptivePlan::Candidate>& list = AdaptivePlan::candidates();
  for (size_t i = 0; i < AdaptivePlan::kStopCandidates; ++i)
    if (list[AdaptivePlan::kCoreCandidates + i].light_path_factor == factor) return i;
  return AdaptivePlan::kStopCandidates;
}

// What a pixel costs per iteration under a one-mode option.
double variant_pixel_cost(size_t variant, const ModePrices& price) {
  return variant == kAllCore    ? price.core
         : variant == kAllMerge ? price.core + price.merge_extra
                                : price.stopped;
}

// The sums of every pixel in the one mode of `variant` (the candidate's options beside its
// per-pixel mix): variance, cost and missing pixels, without the per-pixel vectors.
PixelChoice uniform_sums(const PairVariances& v, size_t variant, const ModePrices& price) {
  const std::vector<double>& variances = *v.of(kVariantModes[variant]);
  PixelChoice out;
  out.variance = finite_sum(variances.size(), [&](size_t p) { return variances[p]; });
  for (size_t p = 0; p < variances.size(); ++p) {
    out.missing += std::isfinite(variances[p]) ? 0.0 : 1.0;
    out.cost += variant_pixel_cost(variant, price.at(p));
  }
  return out;
}

// Every pixel in the one mode of `variant`, with its per-pixel vectors (the option taken).
PixelChoice uniform_choice(const PairVariances& v, size_t variant, const ModePrices& price) {
  PixelChoice out = uniform_sums(v, variant, price);
  out.variances = *v.of(kVariantModes[variant]);
  out.modes.assign(out.variances.size(), kVariantModes[variant]);
  return out;
}

// The option a candidate takes: the best scored, a one-mode option only if it beats the mix by
// kMixMargin; with a forced mode (force_mode >= 0, experiments and tests), that mode everywhere.
size_t pick_variant(const std::array<Score, kVariants>& scores, int force_mode) {
  size_t variant = kMixed;
  for (size_t k = kAllCore; k < kVariants; ++k) {
    const Score needed{scores[variant].missing, scores[variant].value / kMixMargin};
    if (scores[k] < (variant == kMixed ? needed : scores[variant])) variant = k;
  }
  for (size_t k = kAllCore; k < kVariants; ++k)
    if (force_mode == int(kVariantModes[k])) variant = k;
  return variant;
}

// How a candidate's per-pixel mix is priced: its modes chosen and priced on every probe
// (in_sample), each half's modes priced on that half (halves) and on the other half
// (cross_fitted), and the estimate scored. crossed: halves and cross_fitted were computed (with
// fewer than two probes they are in_sample; for a candidate that could not win, not priced).
struct MixPrice {
  double in_sample = 0, halves = 0, cross_fitted = 0, estimate = 0;
  bool crossed = false;
};

// A row of the report's candidate table (history[].candidates): what the candidate would render
// (choice: its option `variant`), and its per-pixel mix (mixed).
nlohmann::json candidate_row(const AdaptivePlan::Candidate& c, const PixelChoice& choice,
                             const PixelChoice& mixed, const ModePrices& price, bool stops,
                             double pixels, double roulette, double roulette_merge,
                             const std::array<Score, kVariants>& scores, size_t variant,
                             const MixPrice& mix, bool cross) {
  const auto score_of = [&](size_t v) {
    return std::isfinite(scores[v].value) ? scores[v].value : -1.0;
  };
  const bool not_priced = cross && !mix.crossed;
  const nlohmann::json null(nullptr);
  return {
      {"light_path_factor", c.light_path_factor},
      {"connections", c.connections},
      {"merge_fraction", fraction_of(choice.modes, PixelMode::Merge)},
      {"path_trace_fraction", fraction_of(choice.modes, PixelMode::PathTrace)},
      {"relative_variance", choice.variance / pixels},
      {"relative_variance_no_merge", mixed.variance_no_merge / pixels},
      {"relative_variance_all_merge", mixed.variance_all_merge / pixels},
      {"stop_fraction", fraction_of(choice.modes, PixelMode::Stop)},
      {"relative_variance_all_stop", stops ? mixed.variance_all_stop / pixels : -1.0},
      {"cost_us_per_pixel_stop", price.stopped},
      {"cost_us_per_pixel", choice.cost / pixels},
      {"pixels_missing_energy", choice.missing},
      {"roulette_factor", roulette},
      {"roulette_factor_merge", roulette_merge},
      {"relative_variance_mixed", mix.estimate / pixels},
      {"relative_variance_mixed_in_sample", mix.in_sample / pixels},
      {"relative_variance_mixed_halves", not_priced ? null : nlohmann::json(mix.halves / pixels)},
      {"relative_variance_cross_fitted",
       not_priced ? null : nlohmann::json(mix.cross_fitted / pixels)},
      {"cost_us_per_pixel_mixed", mixed.cost / pixels},
      {"variant", kVariantNames[variant]},
      {"score_mixed", score_of(kMixed)},
      {"score_all_core", score_of(kAllCore)},
      {"score_all_merge", score_of(kAllMerge)},
      {"score_all_stop", score_of(kAllStop)},
      {"score", scores[variant].value}};
}

// A candidate's options scored (relative variance x time; the pixels where each misses energy)
// from every probe's variances v: every pixel in one mode, and its per-pixel mix `mixed` at its
// in-sample price, which cross_fit can only raise.
std::array<Score, kVariants> variant_scores(const PairVariances& v, const PixelChoice& mixed,
                                            const ModePrices& price, bool path_tracing) {
  std::array<Score, kVariants> scores{};
  scores[kMixed] = {mixed.missing, mixed.variance * mixed.cost};
  if (path_tracing) return scores;  // every pixel path traces: no other option
  for (size_t k = kAllCore; k < kVariants; ++k) {
    if (!v.of(kVariantModes[k])) continue;
    const PixelChoice all = uniform_sums(v, k, price);
    scores[k] = {all.missing, all.variance * all.cost};
  }
  return scores;
}

// The per-pixel mix `mixed` (chosen on every probe) priced from the even and the odd probes'
// variances (v[1], v[2]).
MixPrice cross_fit(size_t n, const std::array<PairVariances, 3>& v, const PixelChoice& mixed,
                   const ModePrices& price) {
  // The per-pixel minimum over noisy estimates is biased low by their noise, and the modes it
  // picks are priced by the same noise: door-ajar at 640 x 480 predicted 7.3 for its mix against
  // 24.7 for photon mapping everywhere, and rendered 2.8x worse than the latter. So the mix is
  // also chosen on each half of the probes and priced on the other half (where that half saw an
  // infinite variance, a path it happened to find, the whole's estimate for the mix's mode there
  // stands in). The excess of that price over the halves' own is the optimism of choosing on
  // half of the probes; the noise of an estimate, and with it the optimism, falls with the
  // square root of the probes, so the whole's mix is priced at its own estimate plus that
  // excess / sqrt(2). (Pricing every option from the halves instead made the choice between
  // candidates as noisy as one probe: point-room and sun-glass at 640 x 480 rendered 8-33% worse.)
  MixPrice mix;
  mix.in_sample = mix.estimate = mixed.variance;
  const auto priced = [&](const std::vector<PixelMode>& modes, const PairVariances& other) {
    return finite_sum(n, [&](size_t p) {
      const double x = (*other.of(modes[p]))[p];
      return std::isfinite(x) ? x : mixed.variances[p];
    });
  };
  const PixelChoice even =
      choose_modes(v[1].no_merge, v[1].merge, *v[1].pt, v[1].stops, price, false);
  const PixelChoice odd =
      choose_modes(v[2].no_merge, v[2].merge, *v[2].pt, v[2].stops, price, false);
  mix.halves = 0.5 * (even.variance + odd.variance);
  mix.cross_fitted = 0.5 * (priced(even.modes, v[2]) + priced(odd.modes, v[1]));
  mix.estimate += std::max(0.0, mix.cross_fitted - mix.halves) / std::sqrt(2.0);
  mix.crossed = true;
  return mix;
}
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

void AdaptivePlan::choose(const std::vector<float>& means) {
  const std::vector<Candidate>& list = candidates();
  const double pixels = double(grid_pixels_);
  const PixelWork pw = pixel_work_of(work_, double(probes_), pixels, kProbeConnections);
  const CostModel t = costs_of(work_, measured_);
  denominator_ = denominators(means);
  // Every probe, then the even and the odd ones alone (cross-fitting needs one in each).
  const bool cross = probes_ >= 2;
  const std::array<Half, 3> halves{Half::All, Half::Even, Half::Odd};
  const size_t sets = cross ? 3 : 1;
  std::array<std::vector<double>, 3> squares_of;  // the squares per half (squares())
  for (size_t h = 0; h < sets; ++h) squares_of[h] = squares(means, halves[h]);
  update_roulette_factors(means, squares_of[0]);
  const std::vector<double> weights = pixel_cost_weights();
  const std::vector<double> unseen = unseen_variance();  // every candidate's (check_last_choice)
  std::array<std::vector<double>, 3> correction;
  // Path tracing, and photon mapping per light-path factor (kLightPathFactors' order).
  Rows pt, stop;
  // Path tracing's bias where it misses energy, weighted by the iterations it would render.
  bias_iterations_ = path_tracing_bias_weight(pw, t);
  const std::vector<double> pt_bias = path_tracing_bias(bias_iterations_, &relative_bias_sum_);
  correction[0] = shared_firefly_correction(means, Half::All, squares_of[0]);
  relative_variances(0, 1, 0, 1, means, squares_of, correction, unseen, pt);
  relative_variances(kCoreCandidates, kStopCandidates, 0, 1, means, squares_of, correction, unseen,
                     stop);
  // The halves' path tracing and photon mapping, when the first candidate needs them.
  bool halves_ready = false;
  const auto prepare_halves = [&] {
    if (halves_ready) return;
    halves_ready = true;
    for (size_t h = 1; h < sets; ++h)
      correction[h] = shared_firefly_correction(means, halves[h], squares_of[h]);
    relative_variances(0, 1, 1, sets, means, squares_of, correction, unseen, pt);
    for (size_t h = 1; h < sets; ++h)
      for (size_t p = 0; p < grid_pixels_; ++p) pt[h][0][p] += pt_bias[p];
    relative_variances(kCoreCandidates, kStopCandidates, 1, sets, means, squares_of, correction,
                       unseen, stop);
  };
  for (size_t p = 0; p < grid_pixels_; ++p) pt[0][0][p] += pt_bias[p];
  // Path tracing is the default only among equals (kPathTracingMargin).
  Score best, path_tracing;
  size_t best_j = 0, best_variant = kMixed;
  PixelChoice best_choice, pt_choice;
  best_choice.modes.assign(grid_pixels_, PixelMode::PathTrace);
  best_choice.variances.assign(grid_pixels_, 0.0);
  nlohmann::json table = nlohmann::json::array();
  // Candidates come in (no merge, merge) pairs after path tracing at index 0.
  for (size_t j = 0; j < kCoreCandidates; j += (j == 0 ? 1 : 2)) {
    const Candidate& c = list[j];
    const size_t si = j == 0 ? kStopCandidates : stop_index_of(c.light_path_factor);
    std::array<PairVariances, 3> v;
    Rows pair;
    // Every probe's variances first; the halves' only for a candidate that may win (below).
    const auto take = [&](size_t h_begin, size_t h_end) {
      if (j != 0)
        relative_variances(j, 2, h_begin, h_end, means, squares_of, correction, unseen, pair);
      for (size_t h = h_begin; h < h_end; ++h) {
        v[h].pt = &pt[h][0];
        v[h].stops = si < kStopCandidates ? &stop[h][si] : nullptr;
        if (j == 0) continue;
        v[h].no_merge = std::move(pair[h][0]);
        v[h].merge = std::move(pair[h][1]);
      }
    };
    take(0, 1);
    const ModePrices price{base_cost(c, pw, t),
                           j == 0 ? 0.0 : merge_cost(list[j + 1], pw, t),
                           path_tracing_cost(c, pw, t),
                           v[0].stops ? stop_cost(list[kCoreCandidates + si], pw, t) : 0.0,
                           light_cost(c, pw, t, true),
                           light_cost(c, pw, t, false),
                           &weights};
    PixelChoice choice =
        j == 0 ? choose_modes(pt[0][0], pt[0][0], pt[0][0], nullptr, price, true)
               : choose_modes(v[0].no_merge, v[0].merge, pt[0][0], v[0].stops, price, false);
    MixPrice mix;
    mix.in_sample = mix.halves = mix.cross_fitted = mix.estimate = choice.variance;
    std::array<Score, kVariants> scores = variant_scores(v[0], choice, price, j == 0);
    // Cross-fitting can only raise the mix's score, so a candidate none of whose options beats
    // the best so far at the mix's in-sample price cannot be taken: its halves are not priced
    // (they were most of a choice's time where one candidate leads by far, as path tracing on
    // material-testball). The choice is the same.
    const bool contender =
        std::any_of(scores.begin(), scores.end(), [&](const Score& x) { return x < best; });
    if (cross && j != 0 && (contender || price_all_)) {
      prepare_halves();
      take(1, sets);
      mix = cross_fit(grid_pixels_, v, choice, price);
      scores[kMixed].value = mix.estimate * choice.cost;
    }
    const size_t variant = pick_variant(scores, j == 0 ? -1 : force_mode_);
    PixelChoice option = variant == kMixed ? choice : uniform_choice(v[0], variant, price);
    table.push_back(candidate_row(c, option, choice, price, v[0].stops != nullptr, pixels,
                                  roulette_[j], roulette_[j == 0 ? j : j + 1], scores, variant, mix,
                                  cross && j != 0));
    // A forced mode other than path tracing needs light paths (force_mode_).
    const bool excluded = j == 0 && force_mode_ >= 0 && force_mode_ != int(PixelMode::PathTrace);
    if (scores[variant] < best && !excluded) {
      best = scores[variant];
      best_j = j;
      best_variant = variant;
      best_choice = std::move(option);
    }
    if (j == 0) {
      path_tracing = scores[kMixed];
      pt_choice = std::move(choice);
    }
  }
  if (best_j != 0 && force_mode_ < 0 && path_tracing.missing == best.missing &&
      path_tracing.value <= kPathTracingMargin * best.value) {
    best_j = 0;
    best_variant = kMixed;
    best_choice = std::move(pt_choice);  // every pixel path traces
  }
  if (force_mode_ >= 0 && best_j != 0)
    std::fill(best_choice.modes.begin(), best_choice.modes.end(), PixelMode(force_mode_));
  take_choice(best_j, best_choice.modes);
  chosen_variance_ = std::move(best_choice.variances);
  // What rendering the choice shows (check_last_choice) is its noise: path tracing's bias is
  // not part of it.
  for (size_t p = 0; p < grid_pixels_; ++p)
    if (best_choice.modes[p] == PixelMode::PathTrace && std::isfinite(pt_bias[p]))
      chosen_variance_[p] -= pt_bias[p];
  // Nor is the variance the probes did not predict: each check measures what it adds anew.
  if (!unseen.empty())
    for (size_t p = 0; p < grid_pixels_; ++p) chosen_variance_[p] -= unseen[p];
  chosen_cost_ = best_choice.cost / pixels;
  predict_probe_cost(pw, t);
  record_choice(kVariantNames[best_variant], t, std::move(table));
}

void AdaptivePlan::record_choice(const char* variant, const CostModel& t, nlohmann::json table) {
  const Candidate& c = candidates()[chosen_j_];
  history_.push_back({{"after_probe", probes_},
                      {"predicted_probe_us_per_pixel", probe_cost_},
                      {"light_path_factor", c.light_path_factor},
                      {"connections", c.connections},
                      {"variant", variant},
                      // Path tracing's missed energy: its relative bias^2 per pixel, and the
                      // iterations that weighted it (null: no budget, so it was ruled out).
                      {"path_tracing_relative_bias", relative_bias_sum_ / double(grid_pixels_)},
                      {"path_tracing_bias_iterations", std::isfinite(bias_iterations_)
                                                           ? nlohmann::json(bias_iterations_)
                                                           : nlohmann::json(nullptr)},
                      {"merge_fraction", fraction_of(modes_, PixelMode::Merge)},
                      {"path_trace_fraction", fraction_of(modes_, PixelMode::PathTrace)},
                      {"stop_fraction", fraction_of(modes_, PixelMode::Stop)},
                      {"settled_choices", settled_choices_},
                      {"costs_us", to_json(t)},
                      {"candidates", std::move(table)}});
}

void AdaptivePlan::take_choice(size_t j, const std::vector<PixelMode>& grid_modes) {
  const Candidate& c = candidates()[j];
  // Each image pixel takes the mode of its block's probed pixel (the last row and column of
  // grid pixels also cover what is left of the image beyond them).
  size_t changed = 0;
  for (int y = 0; y < height_; ++y) {
    const size_t gy = std::min(size_t(y) / stride_, size_t(grid_h_ - 1));
    for (int x = 0; x < width_; ++x) {
      const size_t gx = std::min(size_t(x) / stride_, size_t(grid_w_ - 1));
      PixelMode& mode = modes_[size_t(y) * width_ + x];
      changed += mode != grid_modes[gy * grid_w_ + gx];
      mode = grid_modes[gy * grid_w_ + gx];
    }
  }
  // A choice that repeats the last one (the same candidate, at most kSettledChange of the
  // pixels in another mode) lets the next probe wait longer (schedule_next_probe).
  const bool repeats = chosen_j_ == j && double(changed) <= kSettledChange * double(pixels_);
  settled_choices_ = repeats ? settled_choices_ + 1 : 0;
  chosen_j_ = j;
  chosen_ = {};
  chosen_.light_paths = uint64_t(std::llround(double(c.light_path_factor) * double(pixels_)));
  chosen_.connections = c.connections;
  chosen_.merge_everywhere = false;
  chosen_.splats_nowhere = std::none_of(modes_.begin(), modes_.end(), [](PixelMode m) {
    return m == PixelMode::Bidirectional || m == PixelMode::Merge;
  });
}

void AdaptivePlan::predict_probe_cost(const PixelWork& pw, const CostModel& t) {
  // A probe's predicted cost: its recorded pixels at the probe's configuration (one light path
  // per pixel, two connections, merging), times what recording every contribution adds; the
  // others at the choice, with the probe's light paths (at least kSparseProbeLightPaths).
  const Candidate probe_config{1.f, kProbeConnections, true};
  const double recorded = double(grid_pixels_) / double(pixels_);
  const double choice_paths = double(chosen_.light_paths) / double(pixels_);
  const double probe_paths =
      stride_ > 1 ? std::clamp(choice_paths, kSparseProbeLightPaths, 1.0) : choice_paths;
  probe_cost_ =
      recorded * (base_cost(probe_config, pw, t) + merge_cost(probe_config, pw, t)) *
          kProbeRecordingFactor +
      (1 - recorded) * (chosen_cost_ + (probe_paths - choice_paths) * light_path_cost(pw, t, true));
}

}  // namespace caustica::bidir
