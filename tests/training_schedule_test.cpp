// The passes of path guiding's training: passes combine by inverse variance (with the error of
// each pass's variance, and exactly over processes), and the training schedule
// (guiding/training_schedule.h, after Müller et al. 2017) doubles their length, gives the last
// pass the rest of a sample budget, stops learning when it stops paying and, under a time budget,
// decides by trials whether guiding pays at all.
#include "guiding/training_schedule.h"

#include <gtest/gtest.h>

#include <cmath>
#include <span>
#include <string>
#include <tuple>

#include "core/math.h"
#include "image/inverse_variance.h"

using namespace caustica;

// Passes combine by inverse variance: a pass with four times the variance gets a quarter of the
// weight; a pass of one sample per pixel has no estimate and no weight.
TEST(Guiding, InverseVarianceCombinationWeightsPasses) {
  InverseVarianceCombiner c(1, 2);
  c.add(0, Rgb(100.f));  // one sample per pixel: ignored
  c.add(1, Rgb(100.f));
  c.end_iteration();
  EXPECT_TRUE(c.image().empty()) << "no variance estimate yet";
  c.end_pass();
  // Pass 1: samples 0 and 2 (mean 1, variance of the mean 1); pass 2: 0 and 4 (mean 2, 4).
  for (float v : {0.f, 2.f}) {
    c.add(0, Rgb(v));
    c.add(1, Rgb(v));
    c.end_iteration();
  }
  c.end_pass();
  for (float v : {0.f, 4.f}) {
    c.add(0, Rgb(v));
    c.add(1, Rgb(v));
    c.end_iteration();
  }
  const Image image = c.image();
  ASSERT_FALSE(image.empty());
  // (1 / 1 + 2 / 4) / (1 / 1 + 1 / 4) = 1.2
  EXPECT_NEAR(image[0].r, 1.2f, 1e-5f);
  EXPECT_NEAR(image[1].g, 1.2f, 1e-5f);
  const auto passes = c.passes();
  ASSERT_EQ(passes.size(), 3u);
  EXPECT_LT(passes[0].variance, 0);
  EXPECT_NEAR(passes[1].variance, 1.0, 1e-9);
  EXPECT_NEAR(passes[2].variance, 4.0, 1e-9);
}

// A pass's variance comes with its standard error as a mean over pixels: pixel variances of the
// mean 1 and 4 (samples 0, 2 and 0, 4) give V = 2.5 and an error of sqrt(4.5 / 2) = 1.5 (their
// unbiased spread 4.5 over two pixels); equal pixels give 0, one sample per pixel none.
TEST(Guiding, InverseVarianceReportsTheErrorOfAPassVariance) {
  InverseVarianceCombiner c(2, 1);
  c.add(0, Rgb(0.f));
  c.add(1, Rgb(0.f));
  c.end_iteration();
  EXPECT_LT(c.passes().back().variance_error, 0);
  c.add(0, Rgb(2.f));
  c.add(1, Rgb(4.f));
  c.end_iteration();
  EXPECT_NEAR(c.passes().back().variance, 2.5, 1e-9);
  EXPECT_NEAR(c.passes().back().variance_error, 1.5, 1e-9);
  c.end_pass();
  for (float v : {0.f, 2.f}) {
    c.add(0, Rgb(v));
    c.add(1, Rgb(v));
    c.end_iteration();
  }
  EXPECT_NEAR(c.passes().back().variance_error, 0.0, 1e-12);
  EXPECT_NEAR(c.passes().front().variance_error, 1.5, 1e-9);
}

// The current pass split over two processes (each rendered some of its iterations) and summed
// exactly gives one process's combination bit for bit (MPI ranks: sums_over_ranks). Values
// chosen so that a double sum in another order rounds differently; a firefly far above the
// fixed-point clamp of a single value (2^31) keeps its square in the variance.
TEST(Guiding, InverseVarianceCurrentPassSumsOverProcessesExactly) {
  const float samples[6][2] = {{0.1f, 3e4f},  {1e-3f, 0.7f}, {1e7f, 0.3f},
                               {0.2f, 1e-5f}, {0.3f, 2.f},   {1e-7f, 5.f}};
  InverseVarianceCombiner one(2, 1), a(2, 1), b(2, 1);
  auto add = [](InverseVarianceCombiner& c, const float* v) {
    c.add(0, Rgb(v[0]));
    c.add(1, Rgb(v[1], v[0], 1.f));
    c.end_iteration();
  };
  for (int i = 0; i < 6; ++i) {
    add(one, samples[i]);
    add(i % 2 ? b : a, samples[i]);
  }
  const std::span<FixedSum> sa = a.current_sums(), sb = b.current_sums();
  ASSERT_EQ(sa.size(), 2 * InverseVarianceCombiner::kSumsPerPixel + 1);
  for (size_t i = 0; i < sa.size(); ++i) sa[i] += sb[i];
  const Image x = one.image(), y = a.image();
  ASSERT_FALSE(x.empty());
  for (size_t i = 0; i < x.pixel_count(); ++i) EXPECT_TRUE(x[i] == y[i]) << i;
  ASSERT_EQ(a.passes().size(), 1u);
  EXPECT_EQ(a.passes()[0].samples, 6u);
  EXPECT_EQ(a.passes()[0].variance, one.passes()[0].variance);
  // Pixel 0's variance of the mean is about (1e14 - 1e14 / 6) / 5 / 6 (the 1e7 sample), pixel
  // 1's 0.7152^2 of that (the 1e7 in green), the pass's their mean (with the squares clamped at
  // 2^31 it came out 0).
  const double pixel0 = (1e14 - 1e14 / 6) / 5 / 6;
  EXPECT_NEAR(one.passes()[0].variance, 0.5 * (1 + 0.7152 * 0.7152) * pixel0, 0.01 * pixel0);
  a.clear_current();
  EXPECT_TRUE(a.passes().empty());
}

// Without a budget, passes double forever: two unguided iterations, then iteration i >= 2 in
// pass floor(log2(i)).
TEST(TrainingSchedule, PassesDoubleInLength) {
  TrainingSchedule s;
  const int expected[] = {0, 0, 1, 1, 2, 2, 2, 2, 3, 3, 3, 3, 3, 3, 3, 3, 4};
  for (uint32_t i = 0; i < 17; ++i) {
    if (s.starts_pass(i, 0.0)) s.end_pass(1.0 / double(i));
    EXPECT_EQ(s.pass(), expected[i]) << i;
    EXPECT_TRUE(s.learning());
    EXPECT_EQ(s.guided(), i >= 2);
  }
}

// A sample budget: the last pass takes the rest rather than leaving a sliver (64 spp: 2 + 2 + 4
// + 8 + 16 training, then 32 in the final pass), records nothing and is guided.
TEST(TrainingSchedule, LastPassTakesTheRestOfASampleBudget) {
  for (auto [spp, final_from, passes] :
       {std::tuple{64, 32, 5}, std::tuple{16, 8, 3}, std::tuple{5, 2, 1}, std::tuple{2, -1, 0}}) {
    TrainingSchedule s(spp, 0);
    for (uint32_t i = 0; i < uint32_t(spp); ++i)
      if (s.starts_pass(i, 0.0)) s.end_pass(1.0 / sqr(double(i)));  // falls: keeps learning
    EXPECT_EQ(s.rendering_from(), final_from) << spp;
    EXPECT_EQ(s.pass(), passes) << spp;
    if (final_from >= 0) {
      EXPECT_STREQ(s.reason(), "budget");
      EXPECT_FALSE(s.learning());
      EXPECT_TRUE(s.guided());
    }
  }
}

// Training stops when the predicted final variance V^_k = V_k B_k / R_k rises (Müller 2017, sec.
// 5.2) twice in a row, from pass 5 on: with 1000 spp and guided passes whose per-sample variance
// stops falling after pass 4, pass 6 (V^_6 > V^_5 > V^_4) is the last to learn and rendering
// starts with pass 7 at iteration 128. The unguided pass 0 is not a point of the curve.
TEST(TrainingSchedule, StopsLearningWhenItStopsPaying) {
  TrainingSchedule s(1000, 0);
  const double per_sample[] = {1, 16, 8, 4, 2, 2, 2, 2, 2, 2};
  const uint32_t length[] = {2, 2, 4, 8, 16, 32, 64, 128, 256, 512};
  for (uint32_t i = 0; i < 1000; ++i)
    if (s.starts_pass(i, 0.0)) {
      const int k = s.pass() - 1;  // the pass that ended
      s.end_pass(per_sample[k] / double(length[k]));
    }
  EXPECT_STREQ(s.reason(), "variance");
  EXPECT_EQ(s.rendering_from(), 128);
  const auto& v = s.predicted_final_variances();
  ASSERT_EQ(v.size(), 7u);
  EXPECT_LT(v[0], 0);
  EXPECT_LT(v[4], v[3]);
  EXPECT_GT(v[5], v[4]);
  EXPECT_GT(v[6], v[5]);
  EXPECT_TRUE(s.guided());
}

// A time budget: after training pass 3 a trial renders a guided and an unguided pass of equal
// length, and variance x seconds decides. Guided passes with 1.2x lower variance per sample that
// take 1.5x the time lose: rendering goes on unguided at once. At equal cost guiding wins,
// training goes on, and the render stays guided.
TEST(TrainingSchedule, TimeBudgetSwitchesGuidingOffWhenItDoesNotPay) {
  for (const double guided_cost : {1.5, 1.0}) {
    TrainingSchedule s(0, 10.0);
    double t = 0;
    uint32_t start = 0, trial_length[2] = {0, 0};
    for (uint32_t i = 0; !s.final_pass() && i < 100000; ++i) {
      const bool was_guided = s.guided(), was_trial = s.in_trial();
      if (s.starts_pass(i, t)) {
        if (was_trial) trial_length[was_guided] = i - start;
        s.end_pass((was_guided ? 1.0 : 1.2) / double(i - start));
        start = i;
      }
      t += s.guided() ? 0.001 * guided_cost : 0.001;  // seconds per iteration
    }
    ASSERT_TRUE(s.final_pass()) << guided_cost;
    EXPECT_EQ(trial_length[1], 8u);
    EXPECT_EQ(trial_length[0], 8u);
    EXPECT_EQ(s.guided(), guided_cost == 1.0) << guided_cost;
    EXPECT_GT(s.trial_guided_tau(), 0);
    EXPECT_GT(s.trial_unguided_tau(), 0);
    if (guided_cost > 1) {
      EXPECT_STREQ(s.reason(), "trial");
      EXPECT_EQ(s.rendering_from(), 32);  // training 2 + 2 + 4 + 8, trial 8 + 8
      EXPECT_EQ(s.training_passes(), 4);
    } else {
      EXPECT_STREQ(s.reason(), "variance");  // no gain per sample after the trial
      EXPECT_EQ(s.training_passes(), 6);
    }
  }
}

// A time budget of `seconds` whose iterations take 1 ms guided or not, plus `delay(s)` seconds
// after each (and `after_learning` after a training pass ends, while the field learns), and
// whose passes report the per-sample variance `per_sample(guided, round)` (round: the trial
// round the pass belongs to, -1 outside trials) with a relative standard error `rel_error`
// (negative: none): the finished schedule.
template <typename PerSample, typename Delay>
TrainingSchedule drive_schedule(PerSample&& per_sample, double rel_error, double seconds,
                                Delay&& delay, double after_learning = 0) {
  TrainingSchedule s(0, seconds);
  double t = 0;
  int round = 0;
  for (uint32_t i = 0, start = 0; !s.final_pass() && i < 100000; ++i) {
    const bool was_guided = s.guided(), was_trial = s.in_trial();
    if (s.starts_pass(i, t)) {
      if (s.ended_learning()) t += after_learning;
      const double v = per_sample(was_guided, was_trial ? round : -1) / double(i - start);
      s.end_pass(v, rel_error < 0 ? -1.0 : rel_error * v);
      if (was_trial && !was_guided) ++round;
      start = i;
    }
    t += 0.001 + delay(s);
  }
  return s;
}

// Guided iterations as costly as unguided ones with 1.2x lower variance, no errors, and the
// delays as above.
template <typename Delay>
TrainingSchedule schedule_with_delays(Delay&& delay, double after_learning = 0) {
  return drive_schedule([](bool guided, int) { return guided ? 1.0 : 1.2; }, -1, 10.0, delay,
                        after_learning);
}

// Per-sample variances and their errors as above, no delays.
template <typename PerSample>
TrainingSchedule schedule_with_variances(PerSample&& per_sample, double rel_error,
                                         double seconds = 10) {
  return drive_schedule(per_sample, rel_error, seconds,
                        [](const TrainingSchedule&) { return 0.0; });
}

// A trial pass's seconds are its median iteration's times its iterations, so guiding that pays
// wins its trial although (a) building the field after a training pass takes as long as 20
// iterations, time the clock gives to the first iteration of the next pass (for the early
// trial: its guided pass), or (b) one iteration of the guided trial pass stalls for as long as
// 40 (on door-ajar at 60 s a guided trial pass once took 3.1x its unguided one, 1.6x in the
// next run). Timed by the passes' wall seconds, guiding lost both.
TEST(TrainingSchedule, TrialIsNotDecidedByABuildOrAStalledIteration) {
  bool stalled = false;
  const TrainingSchedule stall = schedule_with_delays([&](const TrainingSchedule& s) {
    if (stalled || !s.in_trial() || !s.guided()) return 0.0;
    stalled = true;
    return 0.04;
  });
  const TrainingSchedule build = schedule_with_delays([](const TrainingSchedule&) { return 0.0; },
                                                      /*after_learning=*/0.02);
  ASSERT_TRUE(stalled);
  for (const TrainingSchedule* s : {&stall, &build}) {
    ASSERT_TRUE(s->final_pass());
    EXPECT_TRUE(s->guided());
    EXPECT_LT(s->trial_guided_tau(), s->trial_unguided_tau());
    EXPECT_STRNE(s->reason(), "trial");
  }
}

// A trial is a sequential test. A difference of 2x against errors of 10% decides in one round;
// a near tie (5%, well inside twice the ratio's error) renders the four rounds. An early trial
// that found no clear difference (a tie) trains on, and the trial after training (the same
// variances here) decides by the pooled rounds. Without errors the first round decides; without
// the time for another round (a 150 ms budget: 118 ms, less than eight rounds of 16 ms, would be
// left) the first round is a tie, and the trial after training decides.
TEST(TrainingSchedule, NearTiesRenderMoreTrialRounds) {
  for (const auto& [guided, unguided, rel_error, seconds, rounds, verdict] :
       {std::tuple{1.0, 2.0, 0.1, 10.0, 1, "won"}, std::tuple{2.0, 1.0, 0.1, 10.0, 1, "lost"},
        std::tuple{1.0, 1.05, 0.1, 10.0, 4, "tie"}, std::tuple{1.05, 1.0, 0.1, 10.0, 4, "tie"},
        std::tuple{1.0, 1.05, -1.0, 10.0, 1, "won"}, std::tuple{1.05, 1.0, -1.0, 10.0, 1, "lost"},
        std::tuple{1.0, 1.05, 0.1, 0.15, 1, "tie"}}) {
    const TrainingSchedule s = schedule_with_variances(
        [&](bool g, int) { return g ? guided : unguided; }, rel_error, seconds);
    const std::string what = std::to_string(guided) + " " + std::to_string(unguided) + " " +
                             std::to_string(rel_error) + " " + std::to_string(seconds);
    ASSERT_TRUE(s.final_pass()) << what;
    EXPECT_STREQ(s.early_trial(), verdict) << what;
    EXPECT_EQ(s.trial_rounds(), rounds) << what;  // of the last trial
    EXPECT_EQ(s.guided(), guided < unguided) << what;
    EXPECT_NEAR(s.trial_guided_tau(), guided * 0.001, 1e-12) << what;
    EXPECT_NEAR(s.trial_unguided_tau(), unguided * 0.001, 1e-12) << what;
    if (std::string(verdict) == "lost") {
      EXPECT_STREQ(s.reason(), "trial") << what;
      EXPECT_EQ(s.rendering_from(), 16 + 16 * rounds) << what;  // training 16, then the rounds
    } else {
      EXPECT_STRNE(s.reason(), "trial") << what;  // training went on
      EXPECT_GT(s.training_passes(), 4) << what;
    }
  }
}

// The rounds pool: a first round where guiding looks 1.2x worse per sample (at equal cost), then
// rounds where it is 0.6x: after three rounds the pooled variances (0.8 against 1) differ by more
// than twice the ratio's error (0.22 against 0.17 in the log) and guiding wins. The first round
// alone (no errors) switches it off. A schedule that kept only the last round's variance would
// decide after the second (2 x 0.14 < 0.51) with tau 0.6 ms.
TEST(TrainingSchedule, TrialRoundsArePooled) {
  auto per_sample = [](bool g, int round) { return g ? (round <= 0 ? 1.2 : 0.6) : 1.0; };
  const TrainingSchedule pooled = schedule_with_variances(per_sample, 0.1);
  EXPECT_EQ(pooled.trial_rounds(), 3);
  EXPECT_TRUE(pooled.guided());
  EXPECT_NEAR(pooled.trial_guided_tau(), 0.8 * 0.001, 1e-12);
  EXPECT_NEAR(pooled.trial_log_ratio_error(),
              0.1 * std::hypot(std::sqrt(1.44 + 0.36 + 0.36) / 2.4, 1 / std::sqrt(3.0)), 1e-9);
  const TrainingSchedule first = schedule_with_variances(per_sample, -1);
  EXPECT_EQ(first.trial_rounds(), 1);
  EXPECT_FALSE(first.guided());
  EXPECT_STREQ(first.reason(), "trial");
}
