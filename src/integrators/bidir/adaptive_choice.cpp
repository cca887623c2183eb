// Choosing adaptive-vcm's configuration from the probes (AdaptivePlan::choose): each
// candidate's per-pixel modes (pixel_modes.h) from its predicted variances
// (adaptive_variances.cpp), its options scored, the mix cross-fitted where it can win, and the
// candidate of lowest total taken.
#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <nlohmann/json.hpp>

#include "integrators/bidir/adaptive_costs.h"
#include "integrators/bidir/adaptive_plan.h"
#include "integrators/bidir/grid_statistics.h"
#include "integrators/bidir/pixel_modes.h"

namespace caustica::bidir {

namespace {
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

// One candidate scored: the option it would render (variant: its per-pixel mix or one mode
// everywhere), that option's score, its per-pixel mix, and its row of the report.
struct ScoredCandidate {
  Score score;
  size_t variant = kMixed;
  PixelChoice option, mixed;
  nlohmann::json row;
};

}  // namespace

// What every candidate of one choice is scored from: the probes' sets (every probe, then the
// even and the odd ones alone: cross-fitting needs one in each), their squares, the fireflies
// every candidate shares, path tracing's and photon mapping's pooled variances, and the pixels'
// cost weights. The halves' share is computed when the first candidate needs it
// (prepare_halves).
struct AdaptivePlan::ChoiceInputs {
  static constexpr std::array<Half, 3> kHalves{Half::All, Half::Even, Half::Odd};
  const AdaptivePlan& plan;
  const std::vector<float>& means;
  const PixelWork pw;
  const CostModel t;
  const bool cross;
  const size_t sets;
  std::array<std::vector<double>, 3> squares, correction;
  std::vector<double> weights, unseen, pt_bias;
  Rows pt, stop;  // path tracing, and photon mapping per light-path factor
  bool halves_ready = false;

  ChoiceInputs(AdaptivePlan& p, const std::vector<float>& m)
      : plan(p),
        means(m),
        pw(pixel_work_of(p.work_, double(p.probes_), double(p.grid_pixels_), kProbeConnections)),
        t(costs_of(p.work_, p.measured_)),
        cross(p.probes_ >= 2),
        sets(cross ? 3 : 1) {
    p.denominator_ = p.denominators(m);
    for (size_t h = 0; h < sets; ++h) squares[h] = p.squares(m, kHalves[h]);
    p.update_roulette_factors(m, squares[0]);
    weights = p.pixel_cost_weights();
    unseen = p.unseen_variance();  // every candidate's (check_last_choice)
    // Path tracing's bias where it misses energy, weighted by the iterations it would render.
    p.bias_iterations_ = p.path_tracing_bias_weight(pw, t);
    pt_bias = p.path_tracing_bias(p.bias_iterations_, &p.relative_bias_sum_);
    correction[0] = p.shared_firefly_correction(m, Half::All, squares[0]);
    variances_of_every_set(0, 1);
  }
  void variances_of_every_set(size_t h_begin, size_t h_end) {
    plan.relative_variances(0, 1, h_begin, h_end, means, squares, correction, unseen, pt);
    for (size_t h = h_begin; h < h_end; ++h)
      for (size_t p = 0; p < plan.grid_pixels_; ++p) pt[h][0][p] += pt_bias[p];
    plan.relative_variances(kCoreCandidates, kStopCandidates, h_begin, h_end, means, squares,
                            correction, unseen, stop);
  }
  void prepare_halves() {
    if (halves_ready) return;
    halves_ready = true;
    for (size_t h = 1; h < sets; ++h)
      correction[h] = plan.shared_firefly_correction(means, kHalves[h], squares[h]);
    variances_of_every_set(1, sets);
  }
  // Candidate j's photon-mapping candidate (kStopCandidates: none; path tracing has none).
  static size_t stop_of(size_t j) {
    return j == 0 ? kStopCandidates : stop_index_of(candidates()[j].light_path_factor);
  }
  // Candidate j's variances (its pair's, path tracing's, its photon mapping's) under the sets
  // [h_begin, h_end) into v.
  void variances(size_t j, size_t h_begin, size_t h_end, std::array<PairVariances, 3>& v) const {
    const size_t si = stop_of(j);
    Rows pair;
    if (j != 0)
      plan.relative_variances(j, 2, h_begin, h_end, means, squares, correction, unseen, pair);
    for (size_t h = h_begin; h < h_end; ++h) {
      v[h].pt = &pt[h][0];
      v[h].stops = si < kStopCandidates ? &stop[h][si] : nullptr;
      if (j == 0) continue;
      v[h].no_merge = std::move(pair[h][0]);
      v[h].merge = std::move(pair[h][1]);
    }
  }
  // Candidate j scored against the best of the candidates before it.
  ScoredCandidate score(size_t j, const Score& best);
  ModePrices prices(size_t j, const PairVariances& v) const {
    const std::vector<Candidate>& list = candidates();
    const Candidate& c = list[j];
    const size_t si = stop_of(j);
    return {base_cost(c, pw, t),
            j == 0 ? 0.0 : merge_cost(list[j + 1], pw, t),
            path_tracing_cost(c, pw, t),
            v.stops ? stop_cost(list[kCoreCandidates + si], pw, t) : 0.0,
            light_cost(c, pw, t, true),
            light_cost(c, pw, t, false),
            &weights};
  }
};

ScoredCandidate AdaptivePlan::ChoiceInputs::score(size_t j, const Score& best) {
  std::array<PairVariances, 3> v;
  variances(j, 0, 1, v);  // every probe's; the halves' only for a candidate that may win
  const ModePrices price = prices(j, v[0]);
  const std::vector<double>& path_traced = pt[0][0];
  ScoredCandidate out;
  out.mixed = j == 0
                  ? choose_modes(path_traced, path_traced, path_traced, nullptr, price, true)
                  : choose_modes(v[0].no_merge, v[0].merge, path_traced, v[0].stops, price, false);
  MixPrice mix;
  mix.in_sample = mix.halves = mix.cross_fitted = mix.estimate = out.mixed.variance;
  std::array<Score, kVariants> scores = variant_scores(v[0], out.mixed, price, j == 0);
  // Cross-fitting can only raise the mix's score, so a candidate none of whose options beats
  // the best so far at the mix's in-sample price cannot be taken: its halves are not priced
  // (they were most of a choice's time where one candidate leads by far, as path tracing on
  // material-testball). The choice is the same.
  const bool contender =
      std::any_of(scores.begin(), scores.end(), [&](const Score& x) { return x < best; });
  if (cross && j != 0 && (contender || plan.price_all_)) {
    prepare_halves();
    variances(j, 1, sets, v);
    mix = cross_fit(plan.grid_pixels_, v, out.mixed, price);
    scores[kMixed].value = mix.estimate * out.mixed.cost;
  }
  out.variant = pick_variant(scores, j == 0 ? -1 : plan.force_mode_);
  out.score = scores[out.variant];
  out.option = out.variant == kMixed ? out.mixed : uniform_choice(v[0], out.variant, price);
  out.row =
      candidate_row(candidates()[j], out.option, out.mixed, price, v[0].stops != nullptr,
                    double(plan.grid_pixels_), plan.roulette_[j],
                    plan.roulette_[j == 0 ? j : j + 1], scores, out.variant, mix, cross && j != 0);
  return out;
}

void AdaptivePlan::choose(const std::vector<float>& means) {
  ChoiceInputs in(*this, means);
  const double pixels = double(grid_pixels_);
  // Path tracing is the default only among equals (kPathTracingMargin).
  Score best, path_tracing;
  size_t best_j = 0, best_variant = kMixed;
  PixelChoice best_choice, pt_choice;
  best_choice.modes.assign(grid_pixels_, PixelMode::PathTrace);
  best_choice.variances.assign(grid_pixels_, 0.0);
  nlohmann::json table = nlohmann::json::array();
  // Candidates come in (no merge, merge) pairs after path tracing at index 0.
  for (size_t j = 0; j < kCoreCandidates; j += (j == 0 ? 1 : 2)) {
    ScoredCandidate scored = in.score(j, best);
    table.push_back(std::move(scored.row));
    // A forced mode other than path tracing needs light paths (force_mode_).
    const bool excluded = j == 0 && force_mode_ >= 0 && force_mode_ != int(PixelMode::PathTrace);
    if (scored.score < best && !excluded) {
      best = scored.score;
      best_j = j;
      best_variant = scored.variant;
      best_choice = std::move(scored.option);
    }
    if (j == 0) {
      path_tracing = scored.score;  // its mix: every pixel path traces
      pt_choice = std::move(scored.mixed);
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
    if (best_choice.modes[p] == PixelMode::PathTrace && std::isfinite(in.pt_bias[p]))
      chosen_variance_[p] -= in.pt_bias[p];
  // Nor is the variance the probes did not predict: each check measures what it adds anew.
  if (!in.unseen.empty())
    for (size_t p = 0; p < grid_pixels_; ++p) chosen_variance_[p] -= in.unseen[p];
  chosen_cost_ = best_choice.cost / pixels;
  predict_probe_cost(in.pw, in.t);
  record_choice(kVariantNames[best_variant], in.t, std::move(table));
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
