// adaptive-vcm's probes in the image: ProbeFilm (integrators/bidir/probe_film.h) keeps the
// probes' exact sums beside the film and weights them against the other iterations;
// AdaptivePlan::probe_weight says by how much, from the spread of the probes' own estimates
// against the variance that the segments between them showed.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <random>
#include <vector>

#include "film/film.h"
#include "integrators/bidir/adaptive_plan.h"
#include "integrators/bidir/probe_film.h"

using namespace caustica;
using namespace caustica::bidir;

namespace {

// Iteration `value` added to every pixel of `film` (pixel i gets value * (i + 1)).
void render_flat(Film& film, float value) {
  for (int y = 0; y < film.height(); ++y)
    for (int x = 0; x < film.width(); ++x)
      film.add_sample(x, y, Rgb(value * float(y * film.width() + x + 1)));
}

}  // namespace

// Four iterations, the first and third probes (10 and 30 per unit), the others 1 and 3: the
// image is (w (10 + 30) + (1 + 3)) / (2 w + 2) per unit. Weight 1 is the film's plain average
// bit for bit, and a probe that another rank keeps in its film (rendered here into a scratch
// film, as a rank that does not own the iteration does) still counts once.
TEST(ProbeFilm, WeightsTheProbesAgainstTheOtherIterations) {
  Film film(3, 2);
  ProbeFilm probes;
  probes.reset(film.pixel_count());
  const float values[4] = {10, 1, 30, 3};
  for (int i = 0; i < 4; ++i) {
    const bool probe = i % 2 == 0;
    if (probe) probes.begin_probe(film);
    render_flat(film, values[i]);
    if (probe) probes.end_probe(film);
    film.end_iteration();
  }
  const Image plain = film.image();
  const Image same = probes.image(film, 2, 1.0);
  for (size_t p = 0; p < film.pixel_count(); ++p) EXPECT_TRUE(same[p] == plain[p]) << p;
  for (double w : {0.0, 0.25, 0.5}) {
    const Image weighted = probes.image(film, 2, w);
    for (size_t p = 0; p < film.pixel_count(); ++p) {
      const double expected = (w * 40 + 4) / (2 * w + 2) * double(p + 1);
      EXPECT_NEAR(weighted[p].r, expected, 1e-6 * expected) << w << " " << p;
      EXPECT_EQ(weighted[p].r, weighted[p].b);
    }
  }
  // A film of probes alone has nothing to weigh them against.
  Film only(3, 2);
  ProbeFilm only_probes;
  only_probes.reset(only.pixel_count());
  only_probes.begin_probe(only);
  render_flat(only, 5);
  only_probes.end_probe(only);
  only.end_iteration();
  EXPECT_TRUE(only_probes.image(only, 1, 0.1)[0] == only.image()[0]);

  // Two "ranks": rank 0 owns iterations 0 and 2 (a probe and a plain one), rank 1 iterations
  // 1 and 3 and renders the probe 0 into a scratch film. Every rank holds the probes whole;
  // rank 1's are cleared before the sum (BidirIntegrator::sums_over_ranks), so the summed
  // probes and films give the one-process image.
  Film rank0(3, 2), rank1(3, 2), scratch(3, 2);
  ProbeFilm probes0, probes1;
  probes0.reset(6);
  probes1.reset(6);
  probes0.begin_probe(rank0);
  render_flat(rank0, 10);
  probes0.end_probe(rank0);
  rank0.end_iteration();
  probes1.begin_probe(scratch);
  render_flat(scratch, 10);
  probes1.end_probe(scratch);
  render_flat(rank1, 1);
  rank1.end_iteration();
  render_flat(rank0, 30);  // not a probe here
  rank0.end_iteration();
  render_flat(rank1, 3);
  rank1.end_iteration();
  probes1.clear();
  rank0.add(rank1);
  for (size_t i = 0; i < probes0.sums().size(); ++i) probes0.sums()[i] += probes1.sums()[i];
  const Image split = probes0.image(rank0, 1, 0.5);
  for (size_t p = 0; p < 6; ++p) {
    const double expected = (0.5 * 10 + 34) / 3.5 * double(p + 1);
    EXPECT_NEAR(split[p].g, expected, 1e-6 * expected) << p;
  }
}

namespace {

constexpr int kWidth = 128, kHeight = 128;

// A plan after `probes` synthetic probes whose own pixel estimates are exponential with mean 1
// (variance 1), and, with the last probe, a segment of `iterations` iterations that showed
// `rendered` as every pixel's variance per iteration (none: empty). The film's means are 1.
AdaptivePlan plan_after(int probes, double rendered, double iterations, uint32_t seed) {
  AdaptivePlan plan(kWidth, kHeight, /*measured_costs=*/false, /*probe_every_iteration=*/false,
                    /*probe_stride=*/1);
  const size_t pixels = size_t(kWidth) * kHeight;
  const std::vector<float> means(pixels, 1.f);
  std::mt19937 rng(seed);
  std::exponential_distribution<float> estimate(1.f), moment(0.5f);
  for (int probe = 0; probe < probes; ++probe) {
    plan.begin_probe(0.1f);
    for (size_t p = 0; p < pixels; ++p) {
      AdaptivePlan::CandidateSums sums;
      for (float& d : sums.d) d = moment(rng);
      sums.estimate = estimate(rng);
      plan.pixel_end(p, sums);
    }
    ProbeWork w;
    w.light_paths = double(pixels);
    w.light_vertices = w.camera_vertices = w.nondelta_camera_vertices = 2.0 * double(pixels);
    const bool last = probe == probes - 1 && iterations > 0;
    plan.finish_probe(w, probe == 0 ? std::vector<float>{} : means,
                      last ? std::vector<double>(pixels, rendered) : std::vector<double>{},
                      last ? iterations : 0.0, /*thread_seconds=*/1);
  }
  return plan;
}

}  // namespace

// The probes' estimates spread with variance 1 about their mean 1: a relative variance of
// 1 / (1 + 0.01) per probe. Iterations that rendered 0.1 per iteration make the probes worth
// a tenth of one of them (the inverse-variance weight of the group); iterations noisier than
// the probes leave the plain average (the weight is at most 1), and so does a render without a
// measured segment.
TEST(ProbeWeight, IsTheRenderedIterationsVarianceOverTheProbes) {
  const std::vector<float> means(size_t(kWidth) * kHeight, 1.f);
  const AdaptivePlan::ProbeWeight quiet = plan_after(6, 0.1, 10, 3).probe_weight(means);
  std::printf("[ probes ] probe %.4f, rendered %.4f per iteration: weight %.4f\n",
              quiet.probe_relative_variance, quiet.rendered_relative_variance, quiet.weight);
  // 16384 pixels, each an unbiased variance from 6 probes: the mean within a few percent.
  EXPECT_NEAR(quiet.probe_relative_variance, 1 / 1.01, 0.04);
  EXPECT_NEAR(quiet.rendered_relative_variance, 0.1 / 1.01, 0.002);
  EXPECT_NEAR(quiet.weight, 0.1, 0.005);
  EXPECT_EQ(plan_after(6, 3.0, 10, 3).probe_weight(means).weight, 1.0);
  EXPECT_EQ(plan_after(6, 0.1, 0, 3).probe_weight(means).weight, 1.0);
}
