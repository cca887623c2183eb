// Equal-time comparisons with several runs per integrator: which run is the median, and that
// run_comparison renders each integrator once per seed, keeps the median run and lists all.
#include "experiment/comparison.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <set>

#include "experiment/report.h"
#include "integrators/registry.h"
#include "io/builtin_scenes.h"
#include "render/renderer.h"
#include "scene/scene.h"

namespace caustica {
namespace {

TEST(Comparison, MedianRunIsTheMiddleOneAndTheLowerOfTwo) {
  EXPECT_EQ(median_run_index({0.3, 0.1, 0.2}), 2u);
  EXPECT_EQ(median_run_index({0.5}), 0u);
  // Sorted 0.1 0.2 0.3 0.4: the lower middle one (a run that happened), at index 3.
  EXPECT_EQ(median_run_index({0.4, 0.1, 0.3, 0.2}), 3u);
  // A NaN sorts last: never the median of good runs.
  EXPECT_EQ(median_run_index({std::nan(""), 5.0, 1.0}), 1u);
  EXPECT_EQ(median_run_index({1.0, 1.0, 1.0}), 1u);  // ties: in run order

  IntegratorRun run;
  for (double v : {0.4, 0.1, 0.3, 0.2}) {
    RepeatRun x;
    x.errors.rel_mse = v;
    run.repeats.push_back(x);
  }
  EXPECT_DOUBLE_EQ(median_rel_mse(run), 0.25);  // the mean of the middle two
  run.repeats.pop_back();
  EXPECT_DOUBLE_EQ(median_rel_mse(run), 0.3);
}

// Three runs each of two integrators: seeds 5, 6, 7 in order; the kept run is the median of its
// integrator's by relMSE; different seeds give different noise; the summary lists every run.
TEST(Comparison, EachIntegratorRunsOncePerSeedAndKeepsItsMedianRun) {
  auto scene = make_builtin_scene("cornell", 24, 24);
  ASSERT_TRUE(scene);
  IntegratorSettings ref_settings;
  ref_settings.seed = 99;
  auto pt = make_integrator("pt", ref_settings);
  RenderBudget budget;
  budget.spp = 64;
  RenderCallbacks quiet;
  quiet.quiet = true;
  const Image reference = render(*scene, *pt, budget, quiet).image;

  ComparisonConfig config;
  config.integrators = {"pt", "pt"};  // the same integrator twice: each keeps its own runs
  const auto names = integrator_names();
  if (std::find(names.begin(), names.end(), "lt") != names.end()) config.integrators[1] = "lt";
  config.seconds = 0.15;
  config.threads = 1;
  config.runs = 3;
  config.settings.seed = 5;
  const ComparisonResult result = run_comparison(*scene, reference, config);
  ASSERT_EQ(result.runs.size(), 2u);
  EXPECT_FALSE(result.interrupted);
  for (const IntegratorRun& r : result.runs) {
    ASSERT_EQ(r.repeats.size(), 3u) << r.integrator;
    std::vector<double> rel;
    std::set<double> distinct;
    for (size_t i = 0; i < 3; ++i) {
      EXPECT_EQ(r.repeats[i].seed, 5u + i);
      EXPECT_GT(r.repeats[i].iterations, 0u);
      rel.push_back(r.repeats[i].errors.rel_mse);
      distinct.insert(r.repeats[i].errors.rel_mse);
    }
    EXPECT_EQ(distinct.size(), 3u) << "the seeds did not change the noise";
    const size_t m = median_run_index(rel);
    EXPECT_EQ(r.seed, r.repeats[m].seed);
    EXPECT_EQ(r.snapshots.back().errors.rel_mse, rel[m]);
    EXPECT_EQ(r.iterations, r.repeats[m].iterations);
    EXPECT_DOUBLE_EQ(median_rel_mse(r), rel[m]);
  }
  const nlohmann::json summary = comparison_summary(result);
  ASSERT_EQ(summary.size(), 2u);
  for (const auto& row : summary) {
    EXPECT_EQ(row["runs"], 3);
    EXPECT_EQ(row["seeds"], nlohmann::json({5, 6, 7}));
    ASSERT_EQ(row["relmse_runs"].size(), 3u);
    EXPECT_EQ(row["errors"]["relmse"].get<double>(), row["relmse_median"].get<double>());
    EXPECT_LE(row["relmse_min"].get<double>(), row["relmse_median"].get<double>());
    EXPECT_GE(row["relmse_max"].get<double>(), row["relmse_median"].get<double>());
  }
  EXPECT_EQ(comparison_json(result)["runs_per_integrator"], 3);
}

TEST(Comparison, OneRunPerIntegratorByDefault) {
  auto scene = make_builtin_scene("cornell", 16, 16);
  ComparisonConfig config;
  config.integrators = {"pt"};
  config.seconds = 0.05;
  config.threads = 1;
  config.settings.seed = 3;
  const Image reference(16, 16);
  const ComparisonResult result = run_comparison(*scene, reference, config);
  ASSERT_EQ(result.runs.size(), 1u);
  ASSERT_EQ(result.runs[0].repeats.size(), 1u);
  EXPECT_EQ(result.runs[0].seed, 3u);
  const nlohmann::json row = comparison_summary(result)[0];
  EXPECT_EQ(row["runs"], 1);
  EXPECT_FALSE(row.contains("relmse_runs"));
  config.runs = 0;
  EXPECT_THROW(run_comparison(*scene, reference, config), std::invalid_argument);
}

}  // namespace
}  // namespace caustica
