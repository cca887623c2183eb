#include <gtest/gtest.h>

#include "io/builtin_scenes.h"
#include "test_scenes.h"

using namespace caustica;
using namespace caustica::test;

TEST(PathTracer, FurnaceMatchesAnalyticRadiance) {
  for (float albedo : {0.3f, 0.5f, 0.8f}) {
    FurnaceParams p;
    p.albedo = albedo;
    p.emission = 1.5f;
    auto scene = make_furnace_scene(p, 32, 32);
    IntegratorSettings s;
    s.max_depth = 1000;
    const auto r = render_with(*scene, "pt", 16, s);
    const PixelStats st = pixel_stats(r.image);
    EXPECT_NEAR(st.mean, p.expected_radiance(), 3 * st.standard_error + 1e-6)
        << "albedo " << albedo << " mean " << st.mean << " se " << st.standard_error;
    EXPECT_LT(st.standard_error, 0.02 * p.expected_radiance());  // the test has power
    EXPECT_EQ(r.nonfinite, 0u);
  }
}

TEST(PathTracer, FurnaceMatchesWithBalanceHeuristicToo) {
  auto scene = make_furnace_scene(FurnaceParams{}, 32, 32);
  IntegratorSettings s;
  s.max_depth = 1000;
  s.mis = MisHeuristic::Balance;
  const auto r = render_with(*scene, "pt", 16, s);
  const PixelStats st = pixel_stats(r.image);
  EXPECT_NEAR(st.mean, 2.0, 3 * st.standard_error);
}

TEST(PathTracer, EnvironmentFurnaceIsInvisible) {
  auto scene = make_builtin_scene("env-furnace", 32, 32);
  const auto r = render_with(*scene, "pt", 64);
  const PixelStats st = pixel_stats(r.image);
  EXPECT_NEAR(st.mean, 1.0, 3 * st.standard_error + 1e-6);
  // Every pixel, not just the mean: an albedo-1 object under uniform light is invisible. The
  // per-pixel standard deviation at 64 spp measures about 0.04 here; 0.2 is 5 sigma.
  for (size_t i = 0; i < r.image.pixel_count(); ++i)
    ASSERT_NEAR(r.image[i].average(), 1.0, 0.2) << "pixel " << i;
}

TEST(PathTracer, MaxDepthOneIsDirectLightOnly) {
  // In the furnace, depth 1 sees emission (Le) plus one bounce of it (a * Le).
  FurnaceParams p;
  auto scene = make_furnace_scene(p, 16, 16);
  IntegratorSettings s;
  s.max_depth = 1;
  const auto r = render_with(*scene, "pt", 32, s);
  const PixelStats st = pixel_stats(r.image);
  EXPECT_NEAR(st.mean, p.emission * (1 + p.albedo), 3 * st.standard_error + 1e-6);
}

TEST(PathTracer, BitIdenticalForOneAndTwoThreads) {
  auto scene = make_builtin_scene("cornell-glass", 48, 48);
  const auto a = render_with(*scene, "pt", 4, {}, 1);
  const auto b = render_with(*scene, "pt", 4, {}, 2);
  ASSERT_EQ(a.image.pixel_count(), b.image.pixel_count());
  for (size_t i = 0; i < a.image.pixel_count(); ++i)
    ASSERT_EQ(a.image[i], b.image[i]) << "pixel " << i;
}

TEST(PathTracer, DifferentSeedsGiveDifferentNoise) {
  auto scene = make_builtin_scene("cornell", 16, 16);
  IntegratorSettings s1, s2;
  s2.seed = 1;
  const auto a = render_with(*scene, "pt", 2, s1), b = render_with(*scene, "pt", 2, s2);
  int differ = 0;
  for (size_t i = 0; i < a.image.pixel_count(); ++i) differ += !(a.image[i] == b.image[i]);
  EXPECT_GT(differ, 100);
}

TEST(PathTracer, CornellGlassHasNoNonFiniteSamplesAndSeesTheLight) {
  auto scene = make_builtin_scene("cornell-glass", 64, 64);
  const auto r = render_with(*scene, "pt", 8);
  EXPECT_EQ(r.nonfinite, 0u);
  // The light quad is visible near the top centre of the image at its full radiance 25.
  float brightest = 0;
  for (int x = 24; x < 40; ++x)
    for (int y = 0; y < 10; ++y) brightest = std::max(brightest, r.image.at(x, y).average());
  EXPECT_NEAR(brightest, 25.0333f, 0.5f);
  const PixelStats st = pixel_stats(r.image);
  EXPECT_GT(st.mean, 0.1);
}
