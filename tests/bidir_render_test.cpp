// The bidirectional family rendered end to end: analytic furnaces, agreement with pt,
// determinism across thread counts, and per-technique images that add up to the image.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>

#include "image/image_io.h"
#include "image/metrics.h"
#include "io/builtin_scenes.h"
#include "test_scenes.h"

using namespace caustica;
using namespace caustica::test;

namespace {

// Mean image value over `runs` independent renders (seeds), and its standard error from the
// spread of the per-run means: valid even though bidirectional pixels share light paths.
struct RunStats {
  double mean = 0, standard_error = 0;
};
RunStats stats_over_seeds(const Scene& scene, const std::string& integrator, int spp,
                          IntegratorSettings s, int runs) {
  std::vector<double> means;
  for (int k = 0; k < runs; ++k) {
    s.seed = 1000 + k;
    const auto r = render_with(scene, integrator, spp, s);
    EXPECT_EQ(r.nonfinite, 0u) << integrator;
    means.push_back(pixel_stats(r.image).mean);
  }
  double m = 0, v = 0;
  for (double x : means) m += x;
  m /= runs;
  for (double x : means) v += (x - m) * (x - m);
  v /= (runs - 1);
  return {m, std::sqrt(v / runs)};
}

Image add(const Image& a, const Image& b) {
  Image out = a;
  for (size_t i = 0; i < out.pixel_count(); ++i) out[i] += b[i];
  return out;
}

}  // namespace

// lt validates the camera importance and the splatting; bpt and vcm the MIS over all techniques.
TEST(BidirFurnace, UnbiasedIntegratorsMatchAnalyticRadiance) {
  FurnaceParams p;
  p.albedo = 0.5f;
  p.emission = 1.5f;
  auto scene = make_furnace_scene(p, 24, 24);
  IntegratorSettings s;
  s.max_depth = 200;
  s.bidir.radius = 0.05f;  // the furnace sphere has radius 1
  for (const char* name : {"lt", "bpt", "vcm", "bpm"}) {
    const RunStats st = stats_over_seeds(*scene, name, 8, s, 6);
    std::printf("%s furnace mean %.5f se %.5f\n", name, st.mean, st.standard_error);
    EXPECT_NEAR(st.mean, p.expected_radiance(), 3 * st.standard_error + 1e-5)
        << name << " mean " << st.mean << " se " << st.standard_error;
    EXPECT_LT(st.standard_error, 0.01 * p.expected_radiance()) << name;  // the test has power
  }
}

// Merging on the furnace sphere has no curvature bias (a ball of radius r centred on a sphere
// cuts a cap of area exactly pi r^2, Archimedes), and the radiance is uniform, so ppm's
// density-estimation bias here is only the boundary-free kernel's: zero in expectation. The
// documented bound is 3 standard errors plus 1% * (r_i / r_1)^2 for the last iteration i, which
// shrinks as the radius does.
TEST(BidirFurnace, ProgressivePhotonMappingWithinShrinkingBiasBound) {
  FurnaceParams p;
  p.albedo = 0.5f;
  p.emission = 1.5f;
  auto scene = make_furnace_scene(p, 24, 24);
  IntegratorSettings s;
  s.max_depth = 200;
  s.bidir.radius = 0.1f;
  const int spp = 8;
  const RunStats st = stats_over_seeds(*scene, "ppm", spp, s, 6);
  const double shrink = std::pow(double(spp), s.bidir.radius_alpha - 1.0);  // (r_i / r_1)^2
  EXPECT_NEAR(st.mean, p.expected_radiance(),
              3 * st.standard_error + 0.01 * shrink * p.expected_radiance())
      << "mean " << st.mean << " se " << st.standard_error;
}

TEST(BidirFurnace, EnvironmentFurnaceIsInvisible) {
  auto scene = make_builtin_scene("env-furnace", 24, 24);
  IntegratorSettings s;
  s.max_depth = 200;
  for (const char* name : {"lt", "bpt", "vcm"}) {
    const RunStats st = stats_over_seeds(*scene, name, 4, s, 4);
    EXPECT_NEAR(st.mean, 1.0, 3 * st.standard_error + 1e-5) << name << " se " << st.standard_error;
  }
}

// Agreement with pt where no path is delta-only. The bound is derived from measured noise. With
// a common normalisation (the pt average as reference, eps 0.01 as rel_mse), d(a, b) = mean of
// (a - b)^2 / (ref^2 + eps) gives E[d(x1, x2)] = 2 v_x for two independent renders of an unbiased
// integrator with normalised variance v_x. Comparing the averages of two renders each,
// E[d(avg_x, avg_pt)] = v_x / 2 + v_pt / 2 + bias^2 = (n_x + n_pt) / 4 with n = d(render 1, render
// 2). The test requires d(avg_x, avg_pt) < 1.5 (n_x + n_pt) / 4: a bias adds to the left side only.
namespace {
double normalised_diff(const Image& a, const Image& b, const Image& ref) {
  double sum = 0;
  for (size_t i = 0; i < a.pixel_count(); ++i)
    for (int c = 0; c < 3; ++c)
      sum += sqr(double(a[i][c]) - b[i][c]) / (sqr(double(ref[i][c])) + 0.01);
  return sum / (3.0 * a.pixel_count());
}
}  // namespace

class BidirAgreement : public ::testing::TestWithParam<std::tuple<std::string, std::string>> {};

TEST_P(BidirAgreement, MatchesPathTracer) {
  const auto& [scene_name, integrator] = GetParam();
  auto scene = make_builtin_scene(scene_name, 32, 32);
  IntegratorSettings s;
  s.max_depth = 5;
  s.bidir.radius = 0.01f;
  int spp = 32;
  if (integrator == "ppm") {  // a consistent estimator: enough photons for its noise to be small
    s.bidir.radius = 0.03f;
    s.bidir.light_paths = 8192;
  }
  const int spp_pt = 128;
  auto render_seed = [&](const std::string& name, int n, uint64_t seed) {
    IntegratorSettings t = s;
    t.seed = seed;
    return render_with(*scene, name, n, t).image;
  };
  const Image pt_a = render_seed("pt", spp_pt, 1), pt_b = render_seed("pt", spp_pt, 2);
  const Image x_a = render_seed(integrator, spp, 3), x_b = render_seed(integrator, spp, 4);
  Image pt_avg = add(pt_a, pt_b), x_avg = add(x_a, x_b);
  for (Rgb& v : pt_avg.pixels()) v *= 0.5f;
  for (Rgb& v : x_avg.pixels()) v *= 0.5f;
  const double noise_pt = normalised_diff(pt_a, pt_b, pt_avg),
               noise_x = normalised_diff(x_a, x_b, pt_avg);
  const double diff = normalised_diff(x_avg, pt_avg, pt_avg);
  const double expected = (noise_pt + noise_x) / 4, bound = 1.5 * expected;
  std::printf(
      "[ agreement ] %-14s %-4s diff %.5f  expected from noise %.5f  (pt %.5f, %s %.5f); rel_mse "
      "%.5f\n",
      scene_name.c_str(), integrator.c_str(), diff, expected, noise_pt, integrator.c_str(), noise_x,
      rel_mse(x_avg, pt_avg));
  EXPECT_LT(diff, bound) << scene_name << " " << integrator;
}

INSTANTIATE_TEST_SUITE_P(Bidir, BidirAgreement,
                         ::testing::Combine(::testing::Values("cornell", "cornell-glossy"),
                                            ::testing::Values("lt", "bpt", "vcm", "ppm")),
                         [](const auto& info) {
                           std::string n = std::get<0>(info.param) + "_" + std::get<1>(info.param);
                           for (char& c : n)
                             if (c == '-') c = '_';
                           return n;
                         });

TEST(BidirDeterminism, BitIdenticalForOneAndTwoThreads) {
  auto scene = make_builtin_scene("cornell-glass", 40, 40);
  IntegratorSettings s;
  s.bidir.light_paths = 3000;  // not a multiple of the chunk size
  for (const char* name : {"lt", "bpt", "ppm", "vcm"}) {
    const auto a = render_with(*scene, name, 3, s, 1);
    const auto b = render_with(*scene, name, 3, s, 2);
    ASSERT_EQ(a.image.pixel_count(), b.image.pixel_count());
    size_t differing = 0;
    for (size_t i = 0; i < a.image.pixel_count(); ++i)
      if (!(a.image[i] == b.image[i])) ++differing;
    EXPECT_EQ(differing, 0u) << name;
  }
}

TEST(BidirTechniques, ImagesSumToTheFinalImage) {
  auto scene = make_builtin_scene("cornell-glass", 24, 24);
  for (const char* name : {"vcm", "bpt", "lt"}) {
    const auto dir =
        std::filesystem::temp_directory_path() / ("caustica_bidir_techniques_" + std::string(name));
    std::filesystem::remove_all(dir);
    IntegratorSettings s;
    s.max_depth = 6;
    s.bidir.techniques_dir = dir.string();
    const auto r = render_with(*scene, name, 3, s);
    Image sum(r.image.width(), r.image.height());
    int files = 0;
    for (const auto& entry : std::filesystem::directory_iterator(dir)) {
      sum = add(sum, read_image(entry.path().string()));
      ++files;
    }
    EXPECT_GT(files, 3) << name;
    double max_err = 0;
    for (size_t i = 0; i < sum.pixel_count(); ++i)
      for (int c = 0; c < 3; ++c)
        max_err = std::max(max_err, double(std::abs(sum[i][c] - r.image[i][c])) /
                                        (1e-3 + std::abs(r.image[i][c])));
    EXPECT_LT(max_err, 1e-4) << name;
    std::filesystem::remove_all(dir);
  }
}
