// The oracles every integrator of the registry runs, without a test naming it by hand
// (DESIGN.md, test oracle 5): the analytic furnaces, agreement with pt where its capability
// flags say it can produce the paths, and bit-identical images for one and two threads. A new
// integrator in src/integrators/registry.cpp gets all of them.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>

#include "image/metrics.h"
#include "integrators/registry.h"
#include "io/builtin_scenes.h"
#include "pbrt_test_util.h"
#include "test_scenes.h"

using namespace caustica;
using namespace caustica::test;

namespace {

// Mean image value over `runs` independent renders (seeds 1000, 1001, ...) and its standard
// error (test_scenes.h).
SeedStats stats_over_seeds(const Scene& scene, const std::string& integrator, int spp,
                           IntegratorSettings s, int runs) {
  return over_seeds(
      runs,
      [&](uint64_t seed) {
        s.seed = seed;
        const auto r = render_with(scene, integrator, spp, s);
        EXPECT_EQ(r.nonfinite, 0u) << integrator;
        return pixel_stats(r.image).mean;
      },
      1000);
}

Image add(const Image& a, const Image& b) {
  Image out = a;
  for (size_t i = 0; i < out.pixel_count(); ++i) out[i] += b[i];
  return out;
}

std::string test_name(std::string n) {
  for (char& c : n)
    if (c == '-') c = '_';
  return n;
}

}  // namespace

class RegistryOracle : public ::testing::TestWithParam<std::string> {
 protected:
  const IntegratorInfo& info() const { return *find_integrator(GetParam()); }
};

// Inside a closed diffuse sphere of albedo a emitting Le everywhere, radiance is Le / (1 - a).
// Unbiased integrators: within 3 standard errors (over 6 seeds). Consistent ones (merging): the
// furnace sphere has no curvature bias for merging (a ball of radius r centred on a sphere cuts a
// cap of area exactly pi r^2, Archimedes) and the radiance is uniform, so the documented bound
// adds only 1% * (r_i / r_1)^2 for the last iteration i, which shrinks with the radius.
TEST_P(RegistryOracle, FurnaceMatchesAnalyticRadiance) {
  FurnaceParams p;
  p.albedo = 0.5f;
  p.emission = 1.5f;
  auto scene = make_furnace_scene(p, 24, 24);
  IntegratorSettings s;
  s.max_depth = 200;
  s.bidir.radius = info().unbiased ? 0.05f : 0.1f;
  const int spp = 8;
  const SeedStats st = stats_over_seeds(*scene, GetParam(), spp, s, 6);
  const double shrink = std::pow(double(spp), s.bidir.radius_alpha - 1.0);  // (r_i / r_1)^2
  const double bias = info().unbiased ? 0.0 : 0.01 * shrink * p.expected_radiance();
  std::printf("[ furnace ] %-4s mean %.5f se %.5f (expected %.5f)\n", GetParam().c_str(), st.mean,
              st.standard_error, p.expected_radiance());
  EXPECT_NEAR(st.mean, p.expected_radiance(), 3 * st.standard_error + bias + 1e-5);
  EXPECT_LT(st.standard_error, 0.01 * p.expected_radiance()) << "the test has power";
}

// Under a uniform environment of radiance 1, an albedo-1 diffuse object is invisible.
TEST_P(RegistryOracle, EnvironmentFurnaceIsInvisible) {
  auto scene = make_builtin_scene("env-furnace", 24, 24);
  IntegratorSettings s;
  s.max_depth = 200;
  s.bidir.radius = 0.05f;
  const SeedStats st = stats_over_seeds(*scene, GetParam(), 4, s, 4);
  EXPECT_NEAR(st.mean, 1.0, 3 * st.standard_error + (info().unbiased ? 1e-5 : 0.01))
      << " se " << st.standard_error;
}

// Agreement with pt where no path is delta-only (cornell, cornell-glossy, and cornell-absorbing,
// whose media every subpath, shadow ray, connection and merge crosses), for every integrator
// whose flags say it samples every such path. The bound is derived from measured noise. With a
// common normalisation (the pt average as reference, eps 0.01 as rel_mse), d(a, b) = mean of
// (a - b)^2 / (ref^2 + eps) gives E[d(x1, x2)] = 2 v_x for two independent renders of an unbiased
// integrator with normalised variance v_x. Comparing the averages of two renders each,
// E[d(avg_x, avg_pt)] = v_x / 2 + v_pt / 2 + bias^2 = (n_x + n_pt) / 4 with n = d(render 1, render
// 2). The test requires d(avg_x, avg_pt) < 1.5 (n_x + n_pt) / 4: a bias adds to the left side only.
class RegistryAgreement : public RegistryOracle {};

TEST_P(RegistryAgreement, AgreesWithPathTracing) {
  auto normalised_diff = [](const Image& a, const Image& b, const Image& ref) {
    double sum = 0;
    for (size_t i = 0; i < a.pixel_count(); ++i)
      for (int c = 0; c < 3; ++c)
        sum += sqr(double(a[i][c]) - b[i][c]) / (sqr(double(ref[i][c])) + 0.01);
    return sum / (3.0 * a.pixel_count());
  };
  for (const char* scene_name : {"cornell", "cornell-glossy", "cornell-absorbing"}) {
    auto scene = make_builtin_scene(scene_name, 32, 32);
    IntegratorSettings s;
    s.max_depth = 5;
    s.bidir.radius = 0.01f;
    int spp = 32;
    if (!info().unbiased) {  // merging: enough photons for its noise to be small
      s.bidir.radius = 0.03f;
      s.bidir.light_paths = 8192;
    }
    auto render_seed = [&](const std::string& name, int n, uint64_t seed) {
      IntegratorSettings t = s;
      t.seed = seed;
      return render_with(*scene, name, n, t).image;
    };
    const Image pt_a = render_seed("pt", 128, 1), pt_b = render_seed("pt", 128, 2);
    const Image x_a = render_seed(GetParam(), spp, 3), x_b = render_seed(GetParam(), spp, 4);
    Image pt_avg = add(pt_a, pt_b), x_avg = add(x_a, x_b);
    for (Rgb& v : pt_avg.pixels()) v *= 0.5f;
    for (Rgb& v : x_avg.pixels()) v *= 0.5f;
    const double noise_pt = normalised_diff(pt_a, pt_b, pt_avg),
                 noise_x = normalised_diff(x_a, x_b, pt_avg);
    const double diff = normalised_diff(x_avg, pt_avg, pt_avg);
    const double expected = (noise_pt + noise_x) / 4, bound = 1.5 * expected;
    std::printf("[ agreement ] %-14s %-4s diff %.5f  expected from noise %.5f; rel_mse %.5f\n",
                scene_name, GetParam().c_str(), diff, expected, rel_mse(x_avg, pt_avg));
    EXPECT_LT(diff, bound) << scene_name;
  }
}

// Beer-Lambert: the camera at the centre of a ball of absorbing medium of radius 1 (bounded by
// an interface, the camera inside through MediumInterface before Camera) under a uniform
// environment of radiance 1 sees exactly exp(-sigma_a) in every pixel and channel.
TEST_P(RegistryOracle, AbsorbingMediumIsBeerLambert) {
  auto scene = test::load_text(
      "MakeNamedMedium \"ink\" \"string type\" \"homogeneous\" \"rgb sigma_a\" [0.2 1 2.5] "
      "\"rgb sigma_s\" [0 0 0]\n"
      "MediumInterface \"\" \"ink\"\n"
      "LookAt 0 0 0  0 0 1  0 1 0\nCamera \"perspective\" \"float fov\" 60\n"
      "Film \"rgb\" \"integer xresolution\" 8 \"integer yresolution\" 8\n"
      "WorldBegin\nLightSource \"infinite\" \"rgb L\" [1 1 1]\n"
      "AttributeBegin\nMediumInterface \"ink\" \"\"\nMaterial \"interface\"\n"
      "Shape \"sphere\" \"float radius\" 1\nAttributeEnd\n");
  ASSERT_TRUE(scene->has_media());
  const auto r = render_with(*scene, GetParam(), 2);
  const Rgb expected(std::exp(-0.2f), std::exp(-1.f), std::exp(-2.5f));
  for (size_t i = 0; i < r.image.pixel_count(); ++i)
    for (int c = 0; c < 3; ++c) ASSERT_NEAR(r.image[i][c], expected[c], 1e-4f) << "pixel " << i;
}

// Random streams are keyed by pixel or path and iteration, never by thread.
TEST_P(RegistryOracle, BitIdenticalForOneAndTwoThreads) {
  auto scene = make_builtin_scene("cornell-glass", 40, 40);
  IntegratorSettings s;
  s.bidir.light_paths = 3000;  // not a multiple of the light-path chunk size
  const auto a = render_with(*scene, GetParam(), 3, s, 1);
  const auto b = render_with(*scene, GetParam(), 3, s, 2);
  ASSERT_EQ(a.image.pixel_count(), b.image.pixel_count());
  size_t differing = 0;
  for (size_t i = 0; i < a.image.pixel_count(); ++i)
    if (!(a.image[i] == b.image[i])) ++differing;
  EXPECT_EQ(differing, 0u);
}

INSTANTIATE_TEST_SUITE_P(Registry, RegistryOracle, ::testing::ValuesIn(integrator_names()),
                         [](const auto& info) { return test_name(info.param); });

// Agreement runs for every integrator but pt (the reference) whose flags say it samples every
// path without delta vertices.
std::vector<std::string> agreeing_integrators() {
  std::vector<std::string> names;
  for (const IntegratorInfo& info : integrator_registry())
    if (info.name != "pt" && info.every_path_without_delta) names.push_back(info.name);
  return names;
}
INSTANTIATE_TEST_SUITE_P(Registry, RegistryAgreement, ::testing::ValuesIn(agreeing_integrators()),
                         [](const auto& info) { return test_name(info.param); });

// The README's integrator table (the table headed "| name |" in its "## Integrators" section)
// lists exactly the registry, in its order.
TEST(Registry, ReadmeTableListsExactlyTheRegistry) {
  std::ifstream readme(std::filesystem::path(CAUSTICA_SCENES).parent_path() / "README.md");
  ASSERT_TRUE(readme) << "README.md not found";
  std::vector<std::string> rows;
  bool in_section = false, in_table = false, done = false;
  for (std::string line; !done && std::getline(readme, line);) {
    if (line.rfind("## ", 0) == 0) in_section = line == "## Integrators";
    if (!in_section) continue;
    if (line.rfind("| name |", 0) == 0) {
      in_table = true;
    } else if (in_table && line.rfind("| `", 0) == 0) {
      rows.push_back(line.substr(3, line.find('`', 3) - 3));
    } else if (in_table && line.rfind("|", 0) != 0) {
      done = true;  // the first line after the table
    }
  }
  EXPECT_EQ(rows, integrator_names());
}
