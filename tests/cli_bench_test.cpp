// `caustica bench`: it runs, and its JSON has every documented field, positive. No timing
// assertions (the numbers depend on the machine); only that they were measured.
#include <gtest/gtest.h>

#include <fstream>
#include <nlohmann/json.hpp>

#include "cli_util.h"

using cli_test::CliRun;
using cli_test::fresh_dir;
using cli_test::run;

TEST(CliBench, WritesJsonWithEveryMeasurementPositive) {
  const auto d = fresh_dir("bench");
  const CliRun r =
      run("bench --scenes cornell --integrators pt,vcm --resolution 32x32 --iterations 1 --runs 1 "
          "--bound-rays 20000 --json out.json",
          d);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  std::ifstream f(d / "out.json");
  const nlohmann::json j = nlohmann::json::parse(f);
  EXPECT_FALSE(j["machine"]["cpu"].get<std::string>().empty());
  EXPECT_GT(j["machine"]["logical_cores"].get<int>(), 0);
  EXPECT_FALSE(j["build"]["build_type"].get<std::string>().empty());
  EXPECT_FALSE(j["build"]["commit"].get<std::string>().empty());
  ASSERT_EQ(j["results"].size(), 2u);
  for (const auto& row : j["results"]) {
    EXPECT_EQ(row["scene"], "cornell");
    EXPECT_EQ(row["resolution"], nlohmann::json({32, 32}));
    const auto& cells = row["per_thread_count"];
    ASSERT_EQ(cells.size(), 2u) << "1 and 2 threads by default";
    for (const auto& c : cells) {
      for (const char* key : {"ms_per_iteration", "rays_per_second", "paths_per_second",
                              "embree_intersect_rays_per_second", "embree_occluded_rays_per_second",
                              "embree_bound_rays_per_second", "ratio_to_embree", "peak_memory_mb",
                              "speedup_vs_1_thread"})
        EXPECT_GT(c[key].get<double>(), 0.0) << row["integrator"] << " " << key;
      EXPECT_GE(c["render_memory_mb"].get<double>(), 0.0);
    }
    if (row["integrator"] == "vcm") {
      EXPECT_GT(row["light_vertices_per_iteration"].get<double>(), 0.0);
      EXPECT_EQ(row["bytes_per_light_vertex"], 40);
      EXPECT_GT(row["hash_grid_bytes"].get<double>(), 0.0);
      for (const auto& c : cells) EXPECT_GT(c["hash_grid_build_ms"].get<double>(), 0.0);
    } else {
      EXPECT_FALSE(row.contains("light_vertices_per_iteration"));
    }
  }
}

TEST(CliBench, UnknownNamesAndBadThreadCountsExitWith2) {
  const auto d = fresh_dir("bench_bad");
  EXPECT_EQ(run("bench --scenes no-such-scene --runs 1 --iterations 1", d).exit_code, 2);
  EXPECT_EQ(run("bench --integrators nope", d).exit_code, 2);
  EXPECT_EQ(run("bench --threads 0", d).exit_code, 2);
  EXPECT_EQ(run("bench --runs 0", d).exit_code, 2);
}
