// The command line as a user meets it: outputs, statistics, exit codes and error messages.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>

#include "cli_util.h"
#include "image/image_io.h"

using cli_test::CliRun;
using cli_test::fresh_dir;
using cli_test::only_stderr_file;
using cli_test::run;
namespace fs = std::filesystem;

TEST(Cli, RenderWritesExrPngAndJsonStatistics) {
  const fs::path d = fresh_dir("render");
  const CliRun r = run("render cornell --spp 2 --resolution 24x16 --seed 3 --outfile out", d);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const caustica::Image exr = caustica::read_image((d / "out.exr").string());
  EXPECT_EQ(exr.width(), 24);
  EXPECT_EQ(exr.height(), 16);
  EXPECT_TRUE(fs::exists(d / "out.png"));
  std::ifstream f(d / "out.json");
  const nlohmann::json j = nlohmann::json::parse(f);
  EXPECT_EQ(j["integrator"], "adaptive-vcm");  // the default without a scene-named one
  EXPECT_EQ(j["spp"], 2);
  EXPECT_EQ(j["resolution"], nlohmann::json({24, 16}));
  EXPECT_EQ(j["seed"], 3);
  EXPECT_GT(j["rays"].get<uint64_t>(), 24u * 16u * 2u);
  EXPECT_GT(j["rays_per_second"].get<double>(), 0.0);
  EXPECT_EQ(j["nonfinite_samples_discarded"], 0);
  for (const char* key : {"seconds", "iterations", "threads", "max_depth", "scene"})
    EXPECT_TRUE(j.contains(key)) << key;
  EXPECT_GT(j["peak_memory_mb"].get<double>(), 1.0);
  EXPECT_LT(j["peak_memory_mb"].get<double>(), 4096.0);
}

TEST(Cli, UnknownNamesListTheValidOnesAndExitWith2) {
  const fs::path d = fresh_dir("names");
  CliRun r = run("render no-such-scene --spp 1", d);
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("cornell-glass"), std::string::npos) << r.err;
  r = run("render cornell --integrator nope --spp 1", d);
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("vcm"), std::string::npos) << r.err;
  r = run("render cornell --no-such-flag", d);
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_TRUE(only_stderr_file(d)) << "no output for bad input";
}

TEST(Cli, MalformedSceneFileGivesOneLocatedErrorAndNoImage) {
  const fs::path d = fresh_dir("malformed");
  std::ofstream(d / "bad.pbrt")
      << "LookAt 0 0 0  0 1 0  0 0 1\nCamera \"perspective\" \"float fov\" [ 45 ]\n"
         "WorldBegin\nShape \"sphere\" \"float radius\" [ oops ]\n";
  const CliRun r = run("render bad.pbrt --spp 1 --outfile out", d);
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("bad.pbrt:4:"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("error"), std::string::npos) << r.err;
  EXPECT_FALSE(fs::exists(d / "out.exr"));
  EXPECT_FALSE(fs::exists(d / "out.png"));
  fs::remove(d / "bad.pbrt");
  EXPECT_TRUE(only_stderr_file(d));
}

// --merge-mis correlation-aware keeps each subpath's merges one by one, at most 128: a deeper
// render is refused before anything is loaded into a film, and the option's values are checked.
TEST(Cli, CorrelationAwareMisRefusesDepthsItCannotHoldAndUnknownValues) {
  const fs::path d = fresh_dir("merge_mis");
  CliRun r =
      run("render cornell --integrator vcm --merge-mis correlation-aware --max-depth 129 "
          "--spp 1 --outfile out",
          d);
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("at most 128"), std::string::npos) << r.err;
  EXPECT_TRUE(only_stderr_file(d)) << "no output for bad input";
  r = run("render cornell --integrator vcm --merge-mis power --spp 1 --outfile out", d);
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("correlation-aware"), std::string::npos) << r.err;
  r =
      run("render cornell --integrator vcm --merge-mis correlation-aware --max-depth 6 --spp 1 "
          "--resolution 16x16 --outfile out",
          d);
  EXPECT_EQ(r.exit_code, 0) << r.err;
  EXPECT_TRUE(fs::exists(d / "out.exr"));
  std::ifstream f(d / "out.json");
  const nlohmann::json j = nlohmann::json::parse(f);
  EXPECT_EQ(j["bidir"]["merge_mis"], "correlation-aware");
  EXPECT_GT(j["bidir"]["correlation_track_bytes"].get<double>(), 0.0);
}

TEST(Cli, MissingFileIsAnErrorNamingIt) {
  const fs::path d = fresh_dir("missing");
  const CliRun r = run("render nothere.pbrt --spp 1", d);
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("nothere.pbrt"), std::string::npos) << r.err;
  EXPECT_TRUE(only_stderr_file(d));
}

TEST(Cli, HelpExistsForEverySubcommand) {
  const fs::path d = fresh_dir("help");
  for (const char* sub : {"render", "compare", "reference", "scenes"}) {
    const CliRun r = run(std::string(sub) + " --help", d);
    EXPECT_EQ(r.exit_code, 0) << sub;
  }
}

// A reference that shares the runs' random numbers makes the integrators that sample like it
// look better than they are: `reference` defaults to a seed other than the runs' 0, and
// `compare` warns when its --reference's metadata names the runs' seed.
TEST(Cli, ReferenceDoesNotShareTheSeedOfTheRunsItJudges) {
  const fs::path d = fresh_dir("reference_seed");
  CliRun r =
      run("reference cornell --time 0.2 --resolution 16x12 --integrator pt --outfile ref", d);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  std::ifstream f(d / "ref.json");
  const nlohmann::json j = nlohmann::json::parse(f);
  EXPECT_NE(j["seed"].get<uint64_t>(), 0u);
  const std::string compare =
      "compare cornell --time 0.2 --resolution 16x12 --integrators pt --reference ref.exr --out ";
  r = run(compare + "c1", d);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_EQ(r.err.find("warning"), std::string::npos) << r.err;
  r = run(compare + "c2 --seed " + std::to_string(j["seed"].get<uint64_t>()), d);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.err.find("was rendered with seed"), std::string::npos) << r.err;
}

// `compare --runs 3`: every integrator renders with seeds --seed .. --seed + 2, taking turns;
// results.json lists every run's relMSE beside the median run's errors, runs.csv every run with
// the shown one marked; a reference whose seed is one of the runs' is warned about.
TEST(Cli, CompareWithSeveralRunsReportsEveryRunAndTheMedian) {
  const fs::path d = fresh_dir("compare_runs");
  CliRun r =
      run("reference cornell --time 0.3 --resolution 16x12 --integrator pt --outfile ref", d);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const std::string compare =
      "compare cornell --time 0.15 --resolution 16x12 --integrators pt,pt --reference ref.exr "
      "--threads 1 --runs 3 --out ";
  r = run(compare + "c --seed 10", d);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_EQ(r.err.find("warning"), std::string::npos) << r.err;
  std::ifstream f(d / "c" / "results.json");
  const nlohmann::json j = nlohmann::json::parse(f);
  EXPECT_EQ(j["runs_per_integrator"], 3);
  ASSERT_EQ(j["summary"].size(), 2u);
  for (const auto& row : j["summary"]) {
    EXPECT_EQ(row["seeds"], nlohmann::json({10, 11, 12}));
    EXPECT_EQ(row["errors"]["relmse"], row["relmse_median"]);
  }
  std::ifstream csv(d / "c" / "runs.csv");
  std::string line;
  int lines = 0, shown = 0;
  while (std::getline(csv, line))
    if (lines++ > 0) shown += line.back() == '1';
  EXPECT_EQ(lines, 7);  // the header and 2 x 3 runs
  EXPECT_EQ(shown, 2);
  // The reference's seed 7919 is the second run's of --seed 7918.
  r = run(compare + "c2 --seed 7918", d);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.err.find("was rendered with seed 7919"), std::string::npos) << r.err;
  r = run("compare cornell --time 0.1 --resolution 16x12 --reference ref.exr --runs 0 --out c3", d);
  EXPECT_EQ(r.exit_code, 2) << r.err;
  EXPECT_NE(r.err.find("--runs"), std::string::npos) << r.err;
  EXPECT_FALSE(fs::exists(d / "c3"));
}
