// The accumulation that makes a render split over MPI ranks bit-identical to one process
// (core/fixed_sum.h, film.h) and the render loop's dealing of iterations (render/ranks.h),
// checked without MPI.
#include "render/ranks.h"

#include <gtest/gtest.h>

#include <barrier>
#include <cstdlib>
#include <nlohmann/json.hpp>
#include <thread>
#include <vector>

#include "film/film.h"
#include "io/builtin_scenes.h"
#include "io/scene_loader.h"
#include "test_scenes.h"

namespace caustica {
namespace {

// How many pixels of two images of one size differ (bit for bit).
size_t pixels_differing(const Image& a, const Image& b) {
  size_t n = 0;
  for (size_t i = 0; i < a.pixel_count(); ++i)
    if (!(a[i] == b[i])) ++n;
  return n;
}

TEST(FixedSum, ConvertsExactlyAboveTheResolutionAndClampsTheRange) {
  for (double v : {0.1, -0.1, 1234.5678, 1.0 / 4096, -3e5})
    EXPECT_EQ(from_fixed(to_fixed(v)), v) << v;
  EXPECT_EQ(from_fixed(to_fixed(1e12)), kFixedSumMaxValue);
  EXPECT_EQ(from_fixed(to_fixed(-1e12)), -kFixedSumMaxValue);
  // Below 2^-64 nothing is left; above it, the error is under 2^-64.
  EXPECT_EQ(to_fixed(1e-20), FixedSum(0));
  EXPECT_NEAR(from_fixed(to_fixed(1e-15)), 1e-15, 0x1p-64);
}

// The two-part conversion is the plain one, FixedSum(v 2^64) truncated toward zero, bit for bit,
// over magnitudes from below the resolution to just under the clamp (2^-68 .. 2^31), both signs.
TEST(FixedSum, ConversionIsTheTruncatedScaledValue) {
  uint64_t state = 777;
  for (int i = 0; i < 20000; ++i) {
    state = state * 6364136223846793005ull + 1442695040888963407ull;
    const double mantissa = 1 + double(state >> 11) * 0x1p-53;
    const double v = std::ldexp(mantissa, int(state % 99) - 68) * (i % 2 ? -1 : 1);
    __extension__ const FixedSum plain = FixedSum(v * 0x1p64);
    ASSERT_TRUE(to_fixed(v) == plain) << v;
  }
  for (double v : {0.0, -0.0, 1.0, -1.0, 0x1p31, -0x1p31, 0x1p31 - 0.5, 0x1p-64, -0x1p-65})
    EXPECT_TRUE(to_fixed(v) == FixedSum(v * 0x1p64)) << v;
}

// Values of many magnitudes, where double addition in two groupings gives two answers.
std::vector<double> awkward_values() {
  std::vector<double> v;
  uint64_t state = 12345;
  for (int i = 0; i < 64; ++i) {
    state = state * 6364136223846793005ull + 1442695040888963407ull;
    const double u = double(state >> 11) * 0x1p-53;
    v.push_back((i % 3 == 0 ? 1e5 : 1e-3) * u);
  }
  return v;
}

TEST(FilmSum, IterationsSplitOverTwoFilmsSumBitIdenticallyToOneFilm) {
  const std::vector<double> values = awkward_values();
  Film one(1, 1), even(1, 1), odd(1, 1);
  double sequential = 0, sum_even = 0, sum_odd = 0;
  for (size_t i = 0; i < values.size(); ++i) {
    const Rgb v(float(values[i]), float(values[i] * 0.5), float(-values[i]));
    one.add_sample(0, 0, v);
    one.end_iteration();
    Film& part = i % 2 ? odd : even;
    part.add_sample(0, 0, v);
    part.end_iteration();
    sequential += float(values[i]);
    (i % 2 ? sum_odd : sum_even) += float(values[i]);
  }
  // The data must be able to tell the schemes apart: plain doubles give two answers.
  ASSERT_NE(sequential, sum_even + sum_odd);
  Film total(1, 1);
  total.add(odd);  // the order of the parts does not matter either
  total.add(even);
  EXPECT_EQ(total.iterations(), one.iterations());
  for (int c = 0; c < 3; ++c) EXPECT_TRUE(total.sums()[c] == one.sums()[c]) << c;
  EXPECT_EQ(total.image()[0], one.image()[0]);
}

TEST(FilmSum, EstimatesOfOneIterationAddExactlyInAnyOrder) {
  // A splat and a camera sample 2^40 apart: their double sum would round; the film's does not.
  Image splats(1, 1);
  splats[0] = Rgb(1.f, -1.f, 0.f);
  const Rgb sample(0x1p-40f, 0x1p-40f, 0x1p-40f);
  Film a(1, 1), b(1, 1);
  a.add_image(splats);
  a.add_sample(0, 0, sample);
  a.end_iteration();
  b.add_sample(0, 0, sample);
  b.add_image(splats);
  b.end_iteration();
  for (int c = 0; c < 3; ++c) EXPECT_TRUE(a.sums()[c] == b.sums()[c]) << c;
  EXPECT_TRUE(a.sums()[0] == to_fixed(1.0) + to_fixed(0x1p-40)) << "exact, no rounding";
}

TEST(FilmSum, RejectsAFilmOfAnotherSize) {
  Film a(2, 2), b(2, 3);
  EXPECT_THROW(a.add(b), std::invalid_argument);
}

// What the pretend ranks below share: progress rounds report that the other ranks finish when
// this one does, and the ranks agree on this rank's own status.
class LoneRounds : public Ranks {
 public:
  LoneRounds(int rank, int size) : rank_(rank), size_(size) {}
  int rank() const override { return rank_; }
  int size() const override { return size_; }
  void start_round(const RoundState& mine) override { round_ = mine; }
  bool poll_round(RoundState* totals, bool) override {
    *totals = round_;
    totals->finished *= uint64_t(size_);
    return true;
  }
  int agree(int status, const std::string&, std::string* message) override {
    message->clear();
    return status;
  }
  void wait_all() override {}
  [[noreturn]] void abort(int code) override { std::_Exit(code); }

 protected:
  int rank_, size_;

 private:
  RoundState round_;
};

// Rank `rank` of `size`, alone: its film goes to the test instead of a reduction.
class PretendRank final : public LoneRounds {
 public:
  PretendRank(int rank, int size, Film* film_out) : LoneRounds(rank, size), out_(film_out) {}
  void sum_films(const Film& mine, Film*) override { out_->add(mine); }
  bool all_sum_films(const Film&, Film*, bool) override {
    ADD_FAILURE() << "a lone pretend rank cannot sum films with the others";
    return true;
  }
  bool any_stops(bool) override {
    ADD_FAILURE() << "a lone pretend rank cannot meet the others";
    return true;
  }
  void sum_to_root(std::span<FixedSum>) override {
    ADD_FAILURE() << "a lone pretend rank cannot sum with the others";
  }
  void all_sum(std::span<FixedSum>) override {
    ADD_FAILURE() << "a lone pretend rank cannot sum with the others";
  }

 private:
  Film* out_;
};

TEST(RanksRender, TwoRanksIterationsGiveTheOneProcessImageBitForBit) {
  auto scene = make_builtin_scene("cornell-glass", 24, 20);
  for (const char* name : {"pt", "bpt", "vcm", "ppm"}) {
    IntegratorSettings settings;
    settings.seed = 7;
    const RenderResult single = test::render_with(*scene, name, 5, settings);
    Film total(24, 20);
    uint32_t iterations[2] = {0, 0};
    for (int rank = 0; rank < 2; ++rank) {
      PretendRank pretend(rank, 2, &total);
      auto integrator = make_integrator(name, settings);
      RenderBudget budget;
      budget.spp = 5;
      RenderCallbacks cb;
      cb.quiet = true;
      cb.ranks = &pretend;
      iterations[rank] = render(*scene, *integrator, budget, cb).local_iterations;
    }
    EXPECT_EQ(iterations[0], 3u) << name;  // iterations 0, 2, 4
    EXPECT_EQ(iterations[1], 2u) << name;  // iterations 1, 3
    const Image image = total.image();
    EXPECT_EQ(pixels_differing(image, single.image), 0u) << name;
  }
}

// Two ranks as two threads of this process, for what needs the ranks to meet: all_sum_films
// is a real sum over both (a barrier on each side of it), while progress rounds are
// LoneRounds'. A ThreadRank's stop_at_sum: the shared sums (counted from 0) at which it asks
// to stop (-1: never).
struct ThreadPair {
  explicit ThreadPair(int width, int height) : meet(2), total(width, height) {}
  std::barrier<> meet;
  const Film* films[2] = {nullptr, nullptr};
  bool stops[2] = {false, false};
  Film total;             // the final films' sum
  int sums = 0;           // shared sums of films made (rank 0 counts)
  int meetings = 0;       // meetings without films (any_stops; rank 0 counts)
  int learning_sums = 0;  // all_sum calls (rank 0 counts)
  std::span<FixedSum> own_sums[2];
};

class ThreadRank final : public LoneRounds {
 public:
  ThreadRank(int rank, ThreadPair* pair, int stop_at_sum = -1)
      : LoneRounds(rank, 2), pair_(pair), stop_at_sum_(stop_at_sum) {}
  // A reduction onto rank 0, whose sum is also kept as the pair's total.
  void sum_films(const Film& mine, Film* root_total) override {
    pair_->films[rank_] = &mine;
    pair_->meet.arrive_and_wait();
    if (rank_ == 0) {
      for (Film* f : {root_total, &pair_->total}) {
        f->set_counts(0, 0);
        for (FixedSum& x : f->sums()) x = 0;
        f->add(*pair_->films[0]);
        f->add(*pair_->films[1]);
      }
    }
    pair_->meet.arrive_and_wait();
  }
  bool all_sum_films(const Film& mine, Film* total, bool stop) override {
    pair_->films[rank_] = &mine;
    pair_->stops[rank_] = stop || sums_ == stop_at_sum_;
    ++sums_;
    pair_->meet.arrive_and_wait();  // both films are in place and stay unchanged
    total->set_counts(0, 0);
    for (FixedSum& f : total->sums()) f = 0;
    total->add(*pair_->films[0]);
    total->add(*pair_->films[1]);
    const bool any = pair_->stops[0] || pair_->stops[1];
    if (rank_ == 0) ++pair_->sums;
    pair_->meet.arrive_and_wait();  // both have read before either renders on
    return any;
  }
  bool any_stops(bool stop) override {
    pair_->stops[rank_] = stop || meetings_ == stop_at_sum_;
    ++meetings_;
    pair_->meet.arrive_and_wait();
    const bool any = pair_->stops[0] || pair_->stops[1];
    if (rank_ == 0) ++pair_->meetings;
    pair_->meet.arrive_and_wait();
    return any;
  }
  void sum_to_root(std::span<FixedSum> sums) override {
    pair_->own_sums[rank_] = sums;
    pair_->meet.arrive_and_wait();
    if (rank_ == 0) {
      EXPECT_EQ(pair_->own_sums[1].size(), sums.size());
      for (size_t i = 0; i < sums.size(); ++i) sums[i] += pair_->own_sums[1][i];
    }
    pair_->meet.arrive_and_wait();  // rank 1's sums stay until rank 0 has read them
  }
  void all_sum(std::span<FixedSum> sums) override {
    std::vector<FixedSum> mine(sums.begin(), sums.end());
    pair_->own_sums[rank_] = mine;
    pair_->meet.arrive_and_wait();  // both copies are in place
    EXPECT_EQ(pair_->own_sums[1 - rank_].size(), sums.size());
    for (size_t i = 0; i < sums.size(); ++i) sums[i] += pair_->own_sums[1 - rank_][i];
    if (rank_ == 0) ++pair_->learning_sums;
    pair_->meet.arrive_and_wait();  // both have read before either copy goes
  }

 private:
  ThreadPair* pair_;
  int stop_at_sum_;  // also the meeting (any_stops) at which it asks to stop
  int sums_ = 0, meetings_ = 0;
};

// Renders `spp` iterations of `name` on two thread ranks; the sum of their films.
struct PairResult {
  Image image;
  uint32_t iterations[2] = {0, 0};
  bool interrupted[2] = {false, false};
  int sums = 0, meetings = 0, learning_sums = 0;
};
PairResult render_on_thread_pair(const Scene& scene, const char* name,
                                 const IntegratorSettings& settings, int spp,
                                 int rank1_stops_at_sum = -1) {
  const int w = scene.camera().width(), h = scene.camera().height();
  ThreadPair pair(w, h);
  PairResult result;
  auto run = [&](int rank) {
    ThreadRank me(rank, &pair, rank == 1 ? rank1_stops_at_sum : -1);
    auto integrator = make_integrator(name, settings);
    RenderBudget budget;
    budget.spp = spp;
    RenderCallbacks cb;
    cb.quiet = true;
    cb.ranks = &me;
    const RenderResult r = render(scene, *integrator, budget, cb);
    result.iterations[rank] = r.local_iterations;
    result.interrupted[rank] = r.interrupted;
    if (rank == 0) result.image = r.image;
  };
  std::thread other(run, 1);
  run(0);
  other.join();
  result.sums = pair.sums;
  result.meetings = pair.meetings;
  result.learning_sums = pair.learning_sums;
  return result;
}

// adaptive-vcm's statistics of a render in one process (its probes' schedule).
nlohmann::json adaptive_report(const Scene& scene, const IntegratorSettings& settings, int spp) {
  auto integrator = make_integrator("adaptive-vcm", settings);
  RenderBudget budget;
  budget.spp = spp;
  RenderCallbacks cb;
  cb.quiet = true;
  render(scene, *integrator, budget, cb);
  nlohmann::json stats;
  integrator->report(stats);
  return stats["adaptive"];
}

// adaptive-vcm learns from its probes (iterations 0, 1, then as their predicted cost allows; at
// least four in 128 iterations here): every rank renders each of them, and the means that normalise
// their variances come from the film summed over the ranks, so the choices, the schedule of the
// probes and the image are those of one process.
TEST(RanksRender, AdaptiveVcmOnTwoRanksGivesTheOneProcessImageBitForBit) {
  auto scene = make_builtin_scene("cornell-glass", 24, 20);
  IntegratorSettings settings;
  settings.seed = 7;
  const int spp = 128;
  const RenderResult single = test::render_with(*scene, "adaptive-vcm", spp, settings);
  const PairResult pair = render_on_thread_pair(*scene, "adaptive-vcm", settings, spp);
  EXPECT_EQ(pair.iterations[0], 64u);  // its own: 0, 2, ..., 126
  EXPECT_EQ(pair.iterations[1], 64u);
  const int probes = adaptive_report(*scene, settings, spp)["probes"].get<int>();
  EXPECT_GE(probes, 4);
  EXPECT_EQ(pair.sums, probes) << "one sum of the films before each probe";
  // ... and of the pixel moments of the iterations between probes, whose measured variance
  // the report sets against the prediction for the choice.
  EXPECT_EQ(pair.learning_sums, probes);
  EXPECT_EQ(pixels_differing(pair.image, single.image), 0u);
  // A different seed changes the image, or the comparison proves nothing.
  settings.seed = 8;
  const RenderResult other = test::render_with(*scene, "adaptive-vcm", spp, settings);
  EXPECT_GT(pixels_differing(other.image, single.image), 0u);
}

// The same with probes of one pixel in each 2 x 2 block (the stride of images of more than
// AdaptivePlan::kProbePixels pixels), whose other pixels render the last choice.
TEST(RanksRender, AdaptiveVcmWithSparseProbesOnTwoRanksGivesTheOneProcessImage) {
  auto scene = make_builtin_scene("cornell-glass", 24, 20);
  IntegratorSettings settings;
  settings.seed = 7;
  settings.bidir.probe_stride = 2;
  const int spp = 12;
  const RenderResult single = test::render_with(*scene, "adaptive-vcm", spp, settings);
  const PairResult pair = render_on_thread_pair(*scene, "adaptive-vcm", settings, spp);
  EXPECT_EQ(pixels_differing(pair.image, single.image), 0u);
  settings.bidir.probe_stride = 1;  // and the stride changes the image
  const RenderResult dense = test::render_with(*scene, "adaptive-vcm", spp, settings);
  EXPECT_GT(pixels_differing(dense.image, single.image), 0u);
}

// The probes weighted against the other iterations in the image (probe_film.h): every rank
// holds every probe's sums, rank 0's are summed with the others' cleared, and the weight comes
// from the plan that every rank shares. On corner at 48 x 36 the probes are noisier than the
// choice (weight about 0.44), so the image is not the film's plain average.
TEST(RanksRender, AdaptiveVcmWithWeightedProbesOnTwoRanksGivesTheOneProcessImageBitForBit) {
  auto scene = load_scene(std::string(CAUSTICA_SCENES) + "/corner.pbrt");
  scene->override_resolution(48, 36);
  IntegratorSettings settings;
  settings.seed = 7;
  const int spp = 64;
  const double weight = adaptive_report(*scene, settings, spp)["probe_weight"].get<double>();
  EXPECT_LT(weight, 0.8);
  EXPECT_GT(weight, 0.0);
  const RenderResult single = test::render_with(*scene, "adaptive-vcm", spp, settings);
  const PairResult pair = render_on_thread_pair(*scene, "adaptive-vcm", settings, spp);
  EXPECT_EQ(pixels_differing(pair.image, single.image), 0u);
}

// The guided integrators' training passes are shared: every rank renders them, so every rank
// learns the same fields and decides the same schedule; only the final pass is split. guided-pt
// weights its passes by their inverse variance, so rank 0 adds the ranks' sums of its final
// pass (sums_over_ranks) and combines as one process does.
TEST(RanksRender, GuidedIntegratorsOnTwoRanksGiveTheOneProcessImageBitForBit) {
  auto scene = make_builtin_scene("cornell-glass", 24, 20);
  for (const char* name : {"guided-pt", "guided-bpt", "guided-vcm"}) {
    IntegratorSettings settings;
    settings.seed = 7;
    settings.guiding.spatial_threshold = 50;  // leaves split at this small resolution
    // Training passes 0-1, 2-3, 4-7; then 8 more would leave less than 16: the final pass
    // renders iterations 8-19.
    const int spp = 20;
    const RenderResult single = test::render_with(*scene, name, spp, settings);
    const PairResult pair = render_on_thread_pair(*scene, name, settings, spp);
    EXPECT_EQ(pair.iterations[0], 10u) << name;  // 0, 2, 4, 6, then 8, 10, ..., 18
    EXPECT_EQ(pair.iterations[1], 10u) << name;
    EXPECT_EQ(pair.meetings, 8) << name << ": one meeting before each training iteration";
    EXPECT_EQ(pair.sums, 0) << name << ": the films are not summed before them";
    EXPECT_EQ(pixels_differing(pair.image, single.image), 0u) << name;
    settings.seed = 8;  // a different seed changes the image, or the comparison proves nothing
    const RenderResult other = test::render_with(*scene, name, spp, settings);
    EXPECT_GT(pixels_differing(other.image, single.image), 0u) << name;
  }
}

// A stop asked for on one rank reaches the other at the next shared sums: both end there,
// interrupted, instead of one waiting for the other forever.
TEST(RanksRender, AStopOnOneRankEndsBothAtTheNextSharedSums) {
  auto scene = make_builtin_scene("cornell-glass", 24, 20);
  IntegratorSettings settings;
  settings.seed = 7;
  // Rank 1 asks to stop at the third sums (before the third probe, iteration 5 here).
  const PairResult pair = render_on_thread_pair(*scene, "adaptive-vcm", settings, 64, 2);
  const uint64_t third =
      adaptive_report(*scene, settings, 64)["probe_iterations"][1].get<uint64_t>();
  EXPECT_TRUE(pair.interrupted[0]);
  EXPECT_TRUE(pair.interrupted[1]);
  EXPECT_EQ(pair.sums, 3);
  EXPECT_EQ(pair.iterations[0], (third + 1) / 2);  // its own before the third probe: 0, 2, ...
  EXPECT_EQ(pair.iterations[1], third / 2);        // 1, 3, ...
}

}  // namespace
}  // namespace caustica
