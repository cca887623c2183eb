// adaptive-vcm (integrators/bidir/adaptive_plan.h): what it chooses and reports (merging and
// light paths for caustics, path tracing's own estimator elsewhere, the chosen candidate in the
// report), when it probes (spaced by their predicted cost; one pixel per block on large images,
// tracing the chosen light paths), and that what it renders stays right (the furnace with
// photon-mapping pixels, sparse probes against pt, one thread against two). The variance it
// predicts against rendering: adaptive_vcm_prediction_test.cpp.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <nlohmann/json.hpp>
#include <string>

#include "adaptive_vcm_helpers.h"
#include "experiment/adaptive_view.h"
#include "integrators/bidir/adaptive_plan.h"
#include "io/builtin_scenes.h"
#include "io/scene_loader.h"
#include "test_scenes.h"

using namespace caustica;
using namespace caustica::test;

// A pixel that maps photons alone (PixelMode::Stop) renders ppm's estimator: the emission its
// camera ray sees and the photons at its first diffuse vertex, nothing else (no next event
// estimation, connections or light-tracing splats, each of which would count the light
// again). Inside the closed furnace sphere (radiance Le / (1 - a) everywhere, no merging bias:
// RegistryOracle.FurnaceMatchesAnalyticRadiance) with every pixel forced to photon mapping
// after each choice: 11 of 16 iterations (the others are probes) render it.
TEST(AdaptiveVcm, PhotonMappingPixelsRenderTheFurnace) {
  FurnaceParams p;
  p.albedo = 0.5f;
  p.emission = 1.5f;
  auto scene = make_furnace_scene(p, 24, 24);
  IntegratorSettings s;
  s.max_depth = 200;
  s.bidir.radius = 0.1f;
  s.bidir.force_pixel_mode = int(bidir::PixelMode::Stop);
  const int spp = 16;
  const SeedStats st = over_seeds(6, [&](uint64_t seed) {
    s.seed = seed;
    const RenderResult r = render_with(*scene, "adaptive-vcm", spp, s);
    EXPECT_EQ(r.nonfinite, 0u);
    return pixel_stats(r.image).mean;
  });
  s.seed = 1;
  const nlohmann::json stats = adaptive_stats(*scene, s, spp);
  EXPECT_EQ(stats["adaptive"]["stop_fraction"].get<double>(), 1.0);
  EXPECT_GT(stats["adaptive"]["light_paths_per_iteration"].get<uint64_t>(), 0u);
  const double bias = 0.01 * std::pow(double(spp), s.bidir.radius_alpha - 1.0) *
                      p.expected_radiance();  // as the registry's furnace test
  std::printf(
      "[ adaptive ] furnace with photon-mapping pixels: mean %.5f se %.5f (expected %.5f)\n",
      st.mean, st.standard_error, p.expected_radiance());
  EXPECT_NEAR(st.mean, p.expected_radiance(), 3 * st.standard_error + bias + 1e-5);
  EXPECT_LT(st.standard_error, 0.01 * p.expected_radiance()) << "the test has power";
}

// The probes are spaced by their predicted cost: where the choice (path tracing on the diffuse
// Cornell box) costs a ninth of a probe (full VCM with two connections, recorded), probes at
// 3, 7, 15, 31, ... would be most of the time; they come once the path tracing since the last
// probe has cost what everything before did (k + 1 times that after a choice that repeated the
// one before k times in a row, as path tracing does here), and only while they stay within a
// tenth of the budget's predicted time beyond the iterations they replace (divided by k + 1 as
// well). Each choice reports when the next probe comes, and the probes come then.
TEST(AdaptiveVcm, ProbesAreSpacedByTheirPredictedCost) {
  auto scene = make_builtin_scene("cornell", 32, 32);
  IntegratorSettings s;
  s.max_depth = 4;
  s.seed = 1;
  const int spp = 2048;
  const nlohmann::json stats = adaptive_stats(*scene, s, spp);
  const auto& a = stats["adaptive"];
  const auto& probes = a["probe_iterations"];  // from the second probe on
  const auto& history = a["history"];
  ASSERT_EQ(history.size(), probes.size());
  ASSERT_GE(probes.size(), 3u);
  EXPECT_EQ(probes[0].get<int>(), 1);
  double spent = 2 * history[0]["predicted_probe_us_per_pixel"].get<double>();
  double excess = 0;
  for (size_t i = 0; i < history.size(); ++i) {
    const auto& h = history[i];
    EXPECT_EQ(h["light_path_factor"].get<double>(), 0.0);  // path tracing
    const int settled = h["settled_choices"].get<int>();
    EXPECT_EQ(settled, int(i));  // every choice after the first repeats the one before
    double choice = -1;
    for (const auto& c : h["candidates"])
      if (c["light_path_factor"] == h["light_path_factor"] && c["connections"] == h["connections"])
        choice = c["cost_us_per_pixel"].get<double>();
    const double probe = h["predicted_probe_us_per_pixel"].get<double>();
    ASSERT_GT(choice, 0);
    EXPECT_GT(probe, 5 * choice);
    if (i == 0) excess = 2 * (probe - choice);
    if (i + 1 < probes.size()) {
      const uint64_t next = probes[i + 1].get<uint64_t>();
      EXPECT_EQ(h["next_probe"].get<uint64_t>(), next);
      const double gap = double(next - probes[i].get<uint64_t>() - 1);
      // The iterations after a probe, up to the next, cost at least settled + 1 times what
      // everything up to it did (the probe excluded), and one iteration fewer would not have.
      const double wait = double(settled + 1) * (spent - probe);
      // (The table's cost of the choice and the plan's differ in their last digits.)
      EXPECT_GE(gap * choice, wait * (1 - 1e-4)) << i;
      EXPECT_LT((gap - 1) * choice, wait * (1 + 1e-4)) << i;
      spent += gap * choice + probe;
      excess += probe - choice;
      // ... and the probes' excess stayed within a tenth of the budget's predicted cost, over
      // settled + 1.
      EXPECT_LE(excess, 0.1 / (settled + 1) * (spent + double(spp - int(next) - 1) * choice)) << i;
    } else if (!h["next_probe"].is_null()) {
      EXPECT_GE(h["next_probe"].get<int>(), spp);  // none within the budget
    }
  }
  // Fewer than the 12 probes at 0, 1, 3, 7, ..., 2047: 6 (at 0, 1, 11, 64, 325, 1749).
  EXPECT_LE(a["probes"].get<int>(), 6);
}

// On the Cornell box with a glass sphere under a small area light, path tracing alone renders
// the caustic with huge variance: adaptive-vcm keeps light paths and merges where the caustic
// is; the report carries the choice, its history and the merge mask.
TEST(AdaptiveVcm, KeepsMergingForCausticsAndReportsWhy) {
  auto scene = make_builtin_scene("cornell-glass", 48, 48);
  IntegratorSettings s;
  s.max_depth = 8;
  const nlohmann::json stats = adaptive_stats(*scene, s, 16);
  const auto& a = stats["adaptive"];
  ASSERT_FALSE(a["history"].empty());
  EXPECT_EQ(a["probes"].get<size_t>(), 1 + a["probe_iterations"].size());  // 0, and those
  EXPECT_GT(a["light_paths_per_iteration"].get<uint64_t>(), 0u);
  // It merges at least where the caustic is (a block on the glass sphere's lower half, which
  // shows the floor and its caustic through the glass: 1.2-2.4% of the pixels while the
  // relative variance divided by the film's one-iteration mean^2). Since the denominators shrink
  // that mean toward its neighbours' (AdaptivePlan::denominators) it merges everywhere: merging
  // is priced 4x better than not on average (0.157 against 0.688), and the per-pixel mix,
  // cross-fitted on one probe per half, no better than that. At equal time (1 s, 8 seeds each,
  // 48 x 48) `vcm` rendered 0.84x the median relMSE of the mixed choices before.
  EXPECT_GT(a["merge_fraction"].get<double>(), 0.005);
  const auto& mask = a["merge_mask"];
  EXPECT_EQ(mask["width"].get<int>() * mask["block"].get<int>(), 48);
  EXPECT_EQ(mask["fraction"].size(), size_t(mask["width"].get<int>() * mask["height"].get<int>()));
  double masked = 0;  // the mask's blocks are whole here (48 = width x block): their mean
  for (const auto& f : mask["fraction"]) masked += f.get<double>();
  EXPECT_NEAR(masked / double(mask["fraction"].size()), a["merge_fraction"].get<double>(), 1e-9);
  // The candidate table prices path tracing far worse than what was chosen: it misses the
  // energy of paths it cannot make in more pixels, or scores at least twice as high.
  const auto& table = a["history"].back()["candidates"];
  EXPECT_EQ(table[0]["light_path_factor"].get<double>(), 0.0);
  double fewest_missing = 1e300, best = 1e300;
  for (const auto& c : table) {
    const double missing = c["pixels_missing_energy"].get<double>();
    if (missing < fewest_missing) fewest_missing = missing, best = 1e300;
    if (missing == fewest_missing && c["score"].is_number())
      best = std::min(best, c["score"].get<double>());
  }
  const double pt_missing = table[0]["pixels_missing_energy"].get<double>();
  EXPECT_TRUE(pt_missing > fewest_missing || table[0]["score"].get<double>() > 2 * best);
}

// sun-glass: the sun's caustic under a glass ball is made only by light paths (a delta light
// seen through a specular surface); the rest is path tracing's easy case. adaptive-vcm keeps
// light paths and merges at the caustic, and lets most pixels path trace alone (pt's estimator,
// no light-tracing splats) instead of making every pixel pay for the bidirectional core. Before,
// one pixel whose variance was infinite for every candidate without merging (the caustic seen
// through the ball) made every score NaN (inf - inf in the 7 x 7 pooling), and the choice fell
// back to path tracing, which misses the caustic: the image converged to the wrong value.
// That is the choice without a budget (an unbounded render: missed energy rules path tracing
// out). Told it has 32 iterations, the plan instead prices path tracing's bias for 32
// iterations (PathTracingsBiasIsWeighedAgainstTheBudget): the caustic's missed energy is seen
// and priced, not counted as pixels missing energy.
TEST(AdaptiveVcm, KeepsLightPathsForACausticOnlyTheyMakeAndPathTracesElsewhere) {
  auto scene = load_scene(std::string(CAUSTICA_SCENES) + "/sun-glass.pbrt");
  // The sun's light paths start on a disk as wide as the 100 x 100 ground: one in about 5000
  // reaches the ball, so the probes need the file's 160 x 120 light paths to see the caustic.
  IntegratorSettings s;
  s.max_depth = 8;
  {
    const nlohmann::json budgeted = adaptive_stats(*scene, s, 32);
    for (const auto& h : budgeted["adaptive"]["history"]) {
      SCOPED_TRACE(h["after_probe"].get<int>());
      EXPECT_EQ(h["path_tracing_bias_iterations"].get<double>(), 32.0);
      EXPECT_GT(h["path_tracing_relative_bias"].get<double>(), 0.0);
      EXPECT_EQ(h["candidates"][0]["pixels_missing_energy"].get<double>(), 0.0);
    }
  }
  const nlohmann::json stats = adaptive_stats(*scene, s, 32, /*budget=*/0);
  const auto& a = stats["adaptive"];
  ASSERT_GE(a["history"].size(), 1u);  // a choice after each probe from the second on
  for (const auto& h : a["history"]) {
    SCOPED_TRACE(h["after_probe"].get<int>());
    EXPECT_GT(h["light_path_factor"].get<double>(), 0.0);
    EXPECT_GT(h["path_trace_fraction"].get<double>(), 0.5);
    EXPECT_GT(h["merge_fraction"].get<double>(), 0.0);
    const auto& pt = h["candidates"][0];
    EXPECT_GT(pt["pixels_missing_energy"].get<double>(), 0.0);
    EXPECT_GT(h["path_tracing_relative_bias"].get<double>(), 0.0);  // reported, though not priced
    EXPECT_TRUE(h["path_tracing_bias_iterations"].is_null());
  }
  EXPECT_TRUE(a.contains("path_trace_mask"));
}

// On the diffuse Cornell box path tracing wins: every iteration that is not a probe is rendered
// by pt's own estimator (cheaper than the core's camera subpaths), and the report says so. That
// the image still agrees with pt is RegistryAgreement's test (same scene, 26 of 32 iterations).
TEST(AdaptiveVcm, PathTracingIterationsRunPathTracersEstimator) {
  auto scene = make_builtin_scene("cornell", 32, 32);
  IntegratorSettings s;
  s.max_depth = 5;
  const nlohmann::json stats = adaptive_stats(*scene, s, 32);
  const auto& a = stats["adaptive"];
  EXPECT_EQ(a["light_paths_per_iteration"].get<uint64_t>(), 0u);
  const int probes = a["probes"].get<int>();
  EXPECT_GE(probes, 2);
  EXPECT_EQ(a["path_tracer_iterations"].get<int>(), 32 - probes);
  const auto& costs = a["history"].back()["costs_us"];
  EXPECT_LT(costs["path_tracing_vertex"].get<double>(), costs["camera_vertex"].get<double>());
  // The core's work is averaged over the iterations it rendered (the probes) only.
  const auto& work = stats["bidir"]["work_per_iteration"];
  EXPECT_GT(work["light_paths"].get<double>(), 1000.0);
  // Every light vertex was a ray's hit; a path's last ray, which hit nothing or went past the
  // maximum depth, is not a vertex.
  EXPECT_GT(work["light_rays"].get<double>(), work["light_vertices"].get<double>());
  // The probes take more than their share of the iterations in time: each renders the core
  // with two connections per camera vertex and prices every candidate; the others path trace.
  const double probe_share = a["probe_time_fraction"].get<double>();
  EXPECT_GT(probe_share, probes / 32.0);
  EXPECT_LE(probe_share, 1.0);
  EXPECT_GT(a["probe_seconds"].get<double>(), 0.0);
}

// The report's table shows the candidate the plan chose, not the one of lowest score: path
// tracing can score lowest over the pixels it renders while missing energy in others (its
// score is then not comparable), as on sun-glass.
TEST(AdaptiveVcm, ReportShowsTheChosenCandidateNotTheLowestScore) {
  nlohmann::json history = {{"after_probe", 2},
                            {"light_path_factor", 0.5},
                            {"connections", 1},
                            {"merge_fraction", 0.01},
                            {"path_trace_fraction", 0.7},
                            {"candidates",
                             {{{"light_path_factor", 0.0},
                               {"connections", 0},
                               {"score", 1.0},
                               {"pixels_missing_energy", 150.0},
                               {"relative_variance", 0.111},
                               {"cost_us_per_pixel", 0.5}},
                              {{"light_path_factor", 0.5},
                               {"connections", 1},
                               {"score", 2.0},
                               {"pixels_missing_energy", 0.0},
                               {"relative_variance", 0.222},
                               {"cost_us_per_pixel", 0.9}}}}};
  ComparisonResult result;
  IntegratorRun run;
  run.integrator = "adaptive-vcm";
  run.integrator_stats["adaptive"]["history"] = nlohmann::json::array({history});
  result.runs.push_back(run);
  const std::string html = adaptive_choices_html(result);
  EXPECT_NE(html.find("0.222"), std::string::npos) << html;
  EXPECT_EQ(html.find("0.111"), std::string::npos) << html;
  EXPECT_NE(html.find("70.0%"), std::string::npos) << html;  // the path-traced share
}

// The stride follows the image's size, and what a probe of every second pixel does: the probed
// pixels merge and make the probe's two connections; the others take the last choice, with
// the probe's light paths; the image is the same for one and two threads.
TEST(AdaptiveVcm, ProbesOfLargeImagesRecordOnePixelPerBlock) {
  EXPECT_EQ(bidir::AdaptivePlan(160, 120, false).probe_stride(), 1);
  EXPECT_EQ(bidir::AdaptivePlan(512, 512, false).probe_stride(), 2);
  EXPECT_EQ(bidir::AdaptivePlan(640, 480, false).probe_stride(), 2);
  EXPECT_EQ(bidir::AdaptivePlan(1920, 1080, false).probe_stride(), 7);
  EXPECT_EQ(bidir::AdaptivePlan(3, 400000, false).probe_stride(), 3);  // at most the narrow side

  auto scene = make_builtin_scene("cornell-glass", 30, 24);
  IntegratorSettings s;
  s.max_depth = 6;
  s.seed = 3;
  s.bidir.probe_stride = 3;
  bidir::AdaptivePlan plan(30, 24, false, false, 3);
  const bidir::IterationPlan probe = plan.plan(0);
  EXPECT_TRUE(probe.probe);
  EXPECT_EQ(probe.light_paths, 720u);
  int recorded = 0;
  for (size_t p = 0; p < 720; ++p) {
    const bool r = probe.records(p);
    recorded += r;
    EXPECT_EQ(r, (p % 30) % 3 == 1 && (p / 30) % 3 == 1) << p;
    EXPECT_TRUE(probe.merges(p));  // before a choice: full VCM everywhere
    EXPECT_FALSE(probe.path_traces(p));
    EXPECT_EQ(probe.connections_at(p), r ? 2 : 1);
  }
  EXPECT_EQ(recorded, 10 * 8);

  const RenderResult one = test::render_with(*scene, "adaptive-vcm", 16, s, 1);
  const RenderResult two = test::render_with(*scene, "adaptive-vcm", 16, s, 2);
  size_t differing = 0;
  for (size_t i = 0; i < one.image.pixel_count(); ++i)
    if (!(one.image[i] == two.image[i])) ++differing;
  EXPECT_EQ(differing, 0u);
  // The choice was made on the 10 x 8 grid and covers every pixel.
  const nlohmann::json stats = adaptive_stats(*scene, s, 16);
  EXPECT_EQ(stats["adaptive"]["probe_stride"].get<int>(), 3);
  const auto& mask = stats["adaptive"]["merge_mask"];
  EXPECT_EQ(mask["width"].get<int>() * mask["block"].get<int>(), 30);
}

// After the first choice a sparse probe traces the chosen light paths (at least half a path and
// at most one per pixel), not always one per pixel: its other pixels render the choice as it is.
// Every iteration a probe of one pixel per 3 x 3 block; the choice after probe k is what iteration
// k traces.
TEST(AdaptiveVcm, SparseProbesTraceTheChosenLightPaths) {
  auto scene = make_builtin_scene("cornell-glass", 30, 24);
  IntegratorSettings s;
  s.max_depth = 6;
  s.seed = 3;
  s.bidir.probe_stride = 3;
  s.bidir.probe_every_iteration = true;
  constexpr int kIterations = 16;
  constexpr double kPixels = 720;
  const nlohmann::json stats = adaptive_stats(*scene, s, kIterations);
  double expected = 2 * kPixels;  // probes 0 and 1, before any choice
  int fewer = 0;                  // probes after a choice of fewer light paths than pixels
  for (const auto& h : stats["adaptive"]["history"]) {
    const int after = h["after_probe"].get<int>();
    if (after >= kIterations) continue;  // a choice no iteration rendered
    const double chosen = std::llround(h["light_path_factor"].get<double>() * kPixels);
    expected += std::clamp(chosen, kPixels / 2, kPixels);
    fewer += chosen < kPixels;
  }
  EXPECT_GT(fewer, 0);  // else this test could not tell the probes' light paths from one each
  EXPECT_DOUBLE_EQ(stats["bidir"]["work_per_iteration"]["light_paths"].get<double>(),
                   expected / kIterations);
}

// Sparse probes keep the image unbiased: every pixel, probed or not, weights its techniques by
// its own counts. As RegistryAgreement.AgreesWithPathTracing (registry_oracles_test.cpp), on the
// glossy Cornell box with every iteration a probe of one pixel per 2 x 2 block: the average of
// two renders differs from pt's by no more than their noise explains.
TEST(AdaptiveVcm, SparseProbesAgreeWithPathTracing) {
  auto scene = make_builtin_scene("cornell-glossy", 32, 32);
  IntegratorSettings s;
  s.max_depth = 5;
  s.bidir.radius = 0.01f;
  auto render_seed = [&](const std::string& name, int n, uint64_t seed, bool sparse) {
    IntegratorSettings t = s;
    t.seed = seed;
    if (sparse) {
      t.bidir.probe_stride = 2;
      t.bidir.probe_every_iteration = true;
    }
    return test::render_with(*scene, name, n, t).image;
  };
  auto normalised_diff = [](const Image& a, const Image& b, const Image& ref) {
    double sum = 0;
    for (size_t i = 0; i < a.pixel_count(); ++i)
      for (int c = 0; c < 3; ++c)
        sum += std::pow(double(a[i][c]) - b[i][c], 2) / (std::pow(double(ref[i][c]), 2) + 0.01);
    return sum / (3.0 * a.pixel_count());
  };
  auto average = [](const Image& a, const Image& b) {
    Image out = a;
    for (size_t i = 0; i < out.pixel_count(); ++i) out[i] = (a[i] + b[i]) * 0.5f;
    return out;
  };
  const Image pt_a = render_seed("pt", 128, 1, false), pt_b = render_seed("pt", 128, 2, false);
  const Image x_a = render_seed("adaptive-vcm", 32, 3, true),
              x_b = render_seed("adaptive-vcm", 32, 4, true);
  const Image pt_avg = average(pt_a, pt_b), x_avg = average(x_a, x_b);
  const double expected =
      (normalised_diff(pt_a, pt_b, pt_avg) + normalised_diff(x_a, x_b, pt_avg)) / 4;
  const double diff = normalised_diff(x_avg, pt_avg, pt_avg);
  std::printf("[ adaptive ] sparse probes against pt: diff %.5f, expected from noise %.5f\n", diff,
              expected);
  EXPECT_LT(diff, 1.5 * expected);
}
