// adaptive-vcm's choice (integrators/bidir/adaptive_choice.cpp) on synthetic probes whose truth
// is known: every candidate and every pixel mode has the same relative variance, and the probes
// only estimate it. Choosing each pixel's mode by the lowest of those noisy estimates and pricing
// the choice with the same estimates predicts a variance below the truth (the winner's curse);
// the cross-fitted price (modes from half of the probes, priced on the other half) does not.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <nlohmann/json.hpp>
#include <random>
#include <string>
#include <tuple>
#include <vector>

#include "integrators/bidir/adaptive_plan.h"

using namespace caustica::bidir;

namespace {

constexpr int kWidth = 256, kHeight = 256;
constexpr double kMoment = 2.0;  // of every candidate's estimate; its mean is 1

// The relative variance every candidate has: (E[F^2] - mean^2) / (mean^2 + 0.01).
constexpr double kTruth = (kMoment - 1.0) / (1.0 + 0.01);

// One synthetic probe (synthetic_choice's) recorded into `plan`; returns its work, to finish it.
// pt_scale: path tracing's second moments times this (1: every candidate alike).
ProbeWork record_synthetic_probe(AdaptivePlan& plan, std::mt19937& rng, float pt_scale = 1.f) {
  const size_t pixels = size_t(kWidth) * kHeight;
  std::exponential_distribution<float> moment(float(1.0 / kMoment));
  plan.begin_probe(0.1f);
  for (size_t p = 0; p < pixels; ++p) {
    AdaptivePlan::CandidateSums sums;  // r = s0 = s1 = 0: the moment is d
    for (float& d : sums.d) d = moment(rng);
    sums.d[0] *= pt_scale;
    sums.estimate = 1.f;  // the probe's own estimate: the mean (the square the moment loses)
    plan.pixel_end(p, sums);
  }
  ProbeWork w;
  w.light_paths = double(pixels);
  w.light_vertices = 2.0 * double(pixels);
  w.camera_vertices = w.nondelta_camera_vertices = 2.0 * double(pixels);
  w.stop_camera_vertices = 20.0 * double(pixels);
  return w;
}

// `probes` synthetic probes: per pixel and candidate an independent second moment drawn from an
// exponential distribution of mean kMoment, with the work of two camera vertices and one light
// path per pixel, no connections or merge queries (so that merging costs nothing extra and the
// core and the core with merging tie), and photon mapping ten times as dear (left out of the
// per-pixel mix).
// price_all: cross-fit every candidate (AdaptivePlan::price_every_candidate); pt_scale: as
// record_synthetic_probe's.
nlohmann::json synthetic_choice(int probes, uint32_t seed, bool price_all = true,
                                float pt_scale = 1.f) {
  AdaptivePlan plan(kWidth, kHeight, /*measured_costs=*/false, /*probe_every_iteration=*/false,
                    /*probe_stride=*/1);
  plan.price_every_candidate(price_all);
  const std::vector<float> means(size_t(kWidth) * kHeight, 1.f);
  std::mt19937 rng(seed);
  for (int probe = 0; probe < probes; ++probe) {
    const ProbeWork w = record_synthetic_probe(plan, rng, pt_scale);
    plan.finish_probe(w, probe == 0 ? std::vector<float>{} : means);
  }
  nlohmann::json stats;
  plan.report(stats);
  return stats["adaptive"]["history"].back();
}

}  // namespace

TEST(AdaptiveChoice, TheMixIsPricedOnProbesThatDidNotChooseIt) {
  for (int probes : {2, 4, 8}) {
    const nlohmann::json choice = synthetic_choice(probes, 11 + uint32_t(probes));
    int rows = 0;
    for (const auto& c : choice["candidates"]) {
      if (c["light_path_factor"].get<double>() == 0) continue;  // path tracing: no choice
      ++rows;
      const double in_sample = c["relative_variance_mixed_in_sample"].get<double>();
      const double cross = c["relative_variance_cross_fitted"].get<double>();
      const double no_merge = c["relative_variance_no_merge"].get<double>();
      if (rows == 1)
        std::printf(
            "[ adaptive ] %d probes: truth %.4f, core everywhere %.4f, mix in sample %.4f, "
            "cross-fitted %.4f, scored %.4f\n",
            probes, kTruth, no_merge, in_sample, cross, c["relative_variance_mixed"].get<double>());
      // Every pixel in one mode: no selection, no bias (65536 pixels: the mean's standard error
      // is 0.8% with one probe).
      EXPECT_NEAR(no_merge, kTruth, 0.03 * kTruth) << probes;
      // The mix chosen and priced on the same probes looks better than anything is ...
      EXPECT_LT(in_sample, 0.95 * kTruth) << probes;
      // ... and priced on the other half of the probes it is what it is.
      EXPECT_NEAR(cross, kTruth, 0.03 * kTruth) << probes;
      // What the choice scores, the whole's mix plus the optimism of half of the probes / sqrt(2),
      // is near the truth.
      const double scored = c["relative_variance_mixed"].get<double>();
      EXPECT_NEAR(scored, kTruth, 0.03 * kTruth) << probes;
    }
    // (light paths, connections) pairs, each without and with merging
    EXPECT_EQ(rows, int(AdaptivePlan::kCoreCandidates - 1) / 2) << probes;
  }
}

// Cross-fitting only raises a mix's price, so a candidate that loses to the best so far at its
// in-sample price is not cross-fitted: the choice and every cross-fitted row are those of pricing
// every candidate, the other rows say null, and their score is the lower bound. Path tracing's
// moments are ten times the others' here, so that a light-path candidate wins.
TEST(AdaptiveChoice, CandidatesThatCannotWinAreNotCrossFitted) {
  for (int probes : {2, 4}) {
    const nlohmann::json all = synthetic_choice(probes, 3 + uint32_t(probes), true, 10.f);
    const nlohmann::json lazy = synthetic_choice(probes, 3 + uint32_t(probes), false, 10.f);
    EXPECT_GT(all["light_path_factor"].get<double>(), 0) << probes;
    for (const char* key : {"light_path_factor", "connections", "variant", "merge_fraction",
                            "path_trace_fraction", "stop_fraction"})
      EXPECT_EQ(all[key], lazy[key]) << key << ", " << probes << " probes";
    ASSERT_EQ(all["candidates"].size(), lazy["candidates"].size());
    int skipped = 0, crossed = 0;
    for (size_t i = 0; i < all["candidates"].size(); ++i) {
      const nlohmann::json& a = all["candidates"][i];
      const nlohmann::json& b = lazy["candidates"][i];
      if (a["light_path_factor"].get<double>() == 0) continue;  // path tracing: no mix
      ASSERT_FALSE(a["relative_variance_cross_fitted"].is_null());
      if (b["relative_variance_cross_fitted"].is_null()) {
        ++skipped;
        EXPECT_TRUE(b["relative_variance_mixed_halves"].is_null());
        EXPECT_EQ(b["relative_variance_mixed"], b["relative_variance_mixed_in_sample"]);
        EXPECT_LE(b["score_mixed"].get<double>(), a["score_mixed"].get<double>());
        EXPECT_EQ(b["relative_variance_mixed_in_sample"], a["relative_variance_mixed_in_sample"]);
      } else {
        ++crossed;
        EXPECT_EQ(a, b);
      }
    }
    std::printf("[ adaptive ] %d probes: %d of %d mixes cross-fitted\n", probes, crossed,
                crossed + skipped);
    // The light-path candidates here differ only in cost: the dearer ones are left out.
    EXPECT_GT(skipped, 0) << probes;
    EXPECT_GT(crossed, 0) << probes;
  }
}

namespace {

// The candidates' predicted relative variance (every candidate's: the probes' samples are made by
// one technique) after `probes` synthetic probes of a w x h image whose every pixel has one
// sample per probe, exponential with mean 1 (variance 1, heavy-tailed as a light transport
// estimate): the variance it predicts per iteration divided by (mean^2 + 0.01). The film's mean
// before each probe is that of the probes before it, as when the integrator probes every
// iteration before its first choice.
double predicted_from_exponential_samples(int probes, uint32_t seed) {
  const int w = 64, h = 64;
  AdaptivePlan plan(w, h, /*measured_costs=*/false, /*probe_every_iteration=*/true,
                    /*probe_stride=*/1);
  const size_t pixels = size_t(w) * h;
  MisCounts counts;
  counts.light_trace = float(pixels);
  counts.connect = 2;
  counts.merge = 1;
  std::mt19937 rng(seed);
  std::exponential_distribution<float> sample(1.f);
  std::vector<double> sums(pixels, 0.0);
  for (int probe = 0; probe < probes; ++probe) {
    std::vector<float> means;
    if (probe > 0)
      for (double s : sums) means.push_back(float(s / probe));
    plan.begin_probe(0.1f);
    for (size_t p = 0; p < pixels; ++p) {
      AdaptivePlan::CandidateSums c = plan.pixel_start(p);
      const float v = sample(rng);
      plan.add(c, v, nullptr, counts);
      plan.pixel_end(p, c);
      sums[p] += v;
    }
    ProbeWork work;
    work.light_paths = double(pixels);
    work.light_vertices = work.camera_vertices = work.nondelta_camera_vertices = 2.0 * pixels;
    plan.finish_probe(work, means);
  }
  nlohmann::json stats;
  plan.report(stats);
  return stats["adaptive"]["history"].back()["candidates"][1]["relative_variance_no_merge"];
}

}  // namespace

// At the first choice the film holds one iteration, and its per-pixel mean is as noisy as one
// sample. Its square taken for mu^2 made every variance too low by a whole sample's variance
// (the numerator, commit 9a49891: here about 0), and 1 / (m^2 + 0.01) of that one sample is far
// above 1 / (mu^2 + 0.01) on average (the denominator: here several times the truth). The plan
// subtracts the product of independent estimates and divides by the film's mean shrunk toward
// its 7 x 7 pooled value where they differ by less than the mean's noise
// (AdaptivePlan::denominators), so two probes price the variance close to the truth, and more
// probes do no worse.
TEST(AdaptiveChoice, TheFirstChoiceIsPricedWithoutTheNoiseOfTheFilmsMean) {
  const double truth = 1.0 / (1.0 + 0.01);
  for (int probes : {2, 3, 8}) {
    const double predicted = predicted_from_exponential_samples(probes, 7 + uint32_t(probes));
    std::printf("[ adaptive ] %d probes: predicted %.4f, truth %.4f\n", probes, predicted, truth);
    EXPECT_NEAR(predicted / truth, 1.0, 0.1) << probes;
  }
}

namespace {

// synthetic_choice's probes, three of them, whose film means are `means` from the second on;
// before the third, the segment since the second rendered 20 iterations of the choice (path
// tracing everywhere: every candidate alike, it is the cheapest) and showed the per-iteration
// variance `measured` (per pixel; empty: no segment). force_mode: as AdaptivePlan's. Returns the
// report's "adaptive".
nlohmann::json after_a_segment(const std::vector<float>& means, const std::vector<double>& measured,
                               int force_mode = -1) {
  AdaptivePlan plan(kWidth, kHeight, /*measured_costs=*/false, /*probe_every_iteration=*/false,
                    /*probe_stride=*/1, force_mode);
  std::mt19937 rng(5);
  for (int probe = 0; probe < 3; ++probe) {
    const ProbeWork w = record_synthetic_probe(plan, rng);
    if (probe < 2)
      plan.finish_probe(w, probe == 0 ? std::vector<float>{} : means);
    else
      plan.finish_probe(w, means, measured, /*iterations=*/20, /*thread_seconds=*/1);
  }
  nlohmann::json stats;
  plan.report(stats);
  return stats["adaptive"];
}

}  // namespace

// An event no probe sampled (mirror-caustic: a camera path that reaches a small light through
// specular bounces) shows in the segments that render a choice: here one pixel's variance is
// 10^4 times its neighbours', and the event raised its film mean from 1 to 20. Measured against
// that mean it would look like a variance of 25, pooled over 7 x 7 to about half the
// prediction; against the mean shrunk by the segment's own variance (about 1.4, its 7 x 7 pool)
// it is thousands. What the prediction missed by more than 3x is added to every candidate's
// variance, as each iteration's camera paths make the event whatever the configuration; a
// segment that shows what was predicted adds next to nothing.
TEST(AdaptiveChoice, AFireflyThatNoProbeSawIsPricedIntoEveryCandidate) {
  const size_t pixels = size_t(kWidth) * kHeight;
  const size_t firefly = 100 * kWidth + 100;
  const std::vector<float> ones(pixels, 1.f);
  std::vector<float> means = ones;
  means[firefly] = 20.f;
  const std::vector<double> flat(pixels, kMoment - 1.0);  // the estimates' true variance
  std::vector<double> spiked = flat;
  spiked[firefly] = 1e4;
  const nlohmann::json none = after_a_segment(ones, {});
  const nlohmann::json same = after_a_segment(ones, flat);
  const nlohmann::json none_fire = after_a_segment(means, {});
  const nlohmann::json fire = after_a_segment(means, spiked);
  ASSERT_EQ(same["history"][0]["light_path_factor"].get<double>(), 0.0);  // path tracing
  ASSERT_EQ(same["checks"].size(), 1u);
  ASSERT_EQ(fire["checks"].size(), 1u);
  const double unseen = fire["checks"][0]["unseen_relative_variance"].get<double>();
  const double noise = same["checks"][0]["unseen_relative_variance"].get<double>();
  std::printf("[ adaptive ] unseen relative variance per pixel %.4f, without the firefly %.6f\n",
              unseen, noise);
  // About 49 pixels of 1e4 / (1.4^2 + 0.01) / 49 each, over 65536 pixels.
  EXPECT_GT(unseen, 0.05);
  EXPECT_LT(unseen, 0.12);
  // Without it, only the few pixels whose prediction from two probes fell below a third of the
  // truth (15 here, predicted 0.10-0.33).
  EXPECT_LT(noise, 0.01 * unseen);
  int rows = 0;
  for (const auto& [a, b, added] :
       {std::tuple{&none, &same, noise}, std::tuple{&none_fire, &fire, unseen}}) {
    const auto& before = (*a)["history"].back()["candidates"];
    const auto& after = (*b)["history"].back()["candidates"];
    ASSERT_EQ(after.size(), before.size());
    for (size_t i = 0; i < before.size(); ++i)
      for (const char* key : {"relative_variance_no_merge", "relative_variance_all_merge",
                              "relative_variance_all_stop"}) {
        const double base = before[i][key].get<double>();
        if (base < 0) continue;  // path tracing has no photon-mapping option
        ++rows;
        EXPECT_NEAR(after[i][key].get<double>() - base, added, 0.02 * added) << i << key;
      }
  }
  EXPECT_EQ(rows, 2 * (3 * int(AdaptivePlan::kCoreCandidates - 1) / 2 + 2));
  // Where a pixel connects to light paths (every one here, forced), light-tracing splats and
  // connections reach its estimate too: what a segment shows there may be the light paths'
  // events, so it adds nothing. (Priced into every candidate's iterations, such an excess on
  // veach-bidir chose fewer connections: relMSE 0.0171 against 0.0020 at 60 s, seed 0.)
  const int bidir = int(PixelMode::Bidirectional);
  const nlohmann::json bidir_none = after_a_segment(means, {}, bidir);
  const nlohmann::json bidir_fire = after_a_segment(means, spiked, bidir);
  EXPECT_EQ(bidir_fire["checks"][0]["unseen_relative_variance"].get<double>(), 0.0);
  EXPECT_EQ(bidir_fire["history"].back()["candidates"], bidir_none["history"].back()["candidates"]);
}
