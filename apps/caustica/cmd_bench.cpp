// `caustica bench`: integrators' cost per scene against the raw Embree bound, as a table on
// stdout and optionally JSON (experiment/bench.h says what each number is).
#include <cstdio>
#include <fstream>
#include <limits>
#include <memory>
#include <string>

#include "commands.h"
#include "experiment/bench.h"
#include "integrators/registry.h"
#include "io/scene_loader.h"
#include "options.h"
#include "render/progress.h"

namespace caustica::cli {

namespace {

struct BenchOptions {
  std::string scenes = "cornell-glass", integrators = "pt,vcm", threads = "1,2";
  int width = 0, height = 0;
  int iterations = 4, runs = 3, max_depth = -1;
  uint64_t seed = 0;
  uint64_t bound_rays = uint64_t(1) << 20;
  std::string json;
  bool quiet = false;
};

int run_bench_command(const BenchOptions& o, const CheckedOptions& checks) {
  if (!checks.check()) return 2;
  BenchConfig config;
  config.scenes = split_list(o.scenes);
  config.integrators = split_list(o.integrators);
  if (config.scenes.empty() || config.integrators.empty()) {
    print_error("--scenes and --integrators need at least one name each");
    return 2;
  }
  for (const auto& name : config.integrators)
    if (!check_name("integrator", name, integrator_names())) return 2;
  config.threads.clear();
  for (const auto& t : split_list(o.threads)) {
    char* end = nullptr;
    const long n = std::strtol(t.c_str(), &end, 10);
    if (*end != '\0' || n < 1 || n > 1024) {
      print_error("--threads: " + excerpt(t) + " is not a thread count in 1..1024");
      return 2;
    }
    config.threads.push_back(int(n));
  }
  if (config.threads.empty()) {
    print_error("--threads needs at least one thread count");
    return 2;
  }
  config.width = o.width;
  config.height = o.height;
  config.iterations = o.iterations;
  config.runs = o.runs;
  config.max_depth = o.max_depth;
  config.seed = o.seed;
  config.bound_rays = size_t(o.bound_rays);

  ProgressBar progress("bench", o.quiet);
  nlohmann::json result;
  try {
    result = run_bench(config, [&](double fraction, double mrays) {
      progress.update(fraction, mrays, "Mrays/s");
    });
  } catch (const UnknownSceneError& e) {
    print_error(e.what());
    return 2;
  } catch (const SceneLoadError& e) {
    std::fprintf(stderr, "%s\n", e.what());
    return 2;
  }
  progress.finish();
  std::fputs(bench_table(result).c_str(), stdout);
  if (!o.json.empty()) {
    std::ofstream f(o.json);
    f << result.dump(2) << "\n";
    if (!f) {
      print_error("--json: could not write " + excerpt(o.json));
      return 1;
    }
  }
  return 0;
}

}  // namespace

Runner add_bench_command(CLI::App& app) {
  auto opts = std::make_shared<BenchOptions>();
  CLI::App* cmd = app.add_subcommand(
      "bench",
      "Measure integrators per scene (ms/iteration, rays/s, paths/s, memory, thread "
      "scaling) against the raw Embree bound of the same scene, median of several runs");
  auto checks = std::make_shared<CheckedOptions>(cmd);
  cmd->add_option("--scenes", opts->scenes,
                  "Comma-separated scene names or files (default cornell-glass)");
  cmd->add_option("--integrators", opts->integrators,
                  "Comma-separated integrators (default pt,vcm)");
  cmd->add_option("--threads", opts->threads,
                  "Comma-separated thread counts to compare (default 1,2)");
  checks->resolution("--resolution", &opts->width, &opts->height,
                     "Film resolution WxH (default: each scene's)");
  checks->integer("--iterations", &opts->iterations, 1, 1 << 20,
                  "Iterations (samples per pixel) per run (default 4)");
  checks->integer("--runs", &opts->runs, 1, 1000,
                  "Runs per measurement; the median is reported "
                  "(default 3)");
  checks->integer("--max-depth", &opts->max_depth, 0, 255,
                  "Maximum scattering vertices (default: the scene's, else 10)");
  checks->integer("--seed", &opts->seed, uint64_t(0), std::numeric_limits<uint64_t>::max(),
                  "Random seed (default 0)");
  checks->integer("--bound-rays", &opts->bound_rays, uint64_t(1), uint64_t(1) << 26,
                  "Rays per raw Embree measurement (default 2^20)");
  cmd->add_option("--json", opts->json, "Also write the results as JSON to this file");
  cmd->add_flag("--quiet,-q", opts->quiet, "No progress bar");
  return [opts, checks](Ranks&) { return run_bench_command(*opts, *checks); };
}

}  // namespace caustica::cli
