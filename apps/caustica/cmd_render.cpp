// `caustica render`: render a scene with one integrator to EXR, PNG and JSON.
#include <tbb/global_control.h>
#include <tbb/info.h>

#include <chrono>
#include <cstdio>
#include <ctime>
#include <limits>
#include <memory>
#include <string>

#include "commands.h"
#include "integrators/registry.h"
#include "interrupt.h"
#include "io/builtin_scenes.h"
#include "io/scene_loader.h"
#include "preflight.h"
#include "ranks_cli.h"
#include "render/output.h"
#include "render/renderer.h"
#include "render/statistics.h"
#include "scene/scene.h"
#include "scene_setup.h"

namespace caustica::cli {

namespace {

struct RenderOptions : SharedOptions {
  std::string scene_positional, scene_flag;
  std::string integrator;
  int spp = 0;
  std::string outfile = "caustica.exr";
  float exposure = 0;
  bool quiet = false;
  double checkpoint_seconds = 60;
};

std::string iso_time_now() {
  const std::time_t t = std::time(nullptr);
  char buf[32];
  std::strftime(buf, sizeof buf, "%Y-%m-%dT%H:%M:%SZ", std::gmtime(&t));
  return buf;
}

int run_render(const RenderOptions& o, const CheckedOptions& checks, Ranks& ranks) {
  std::string scene_name;
  const OutputPaths paths = output_paths_for(o.outfile);
  std::unique_ptr<Scene> scene;
  IntegratorSettings settings;
  double load_seconds = 0;
  std::string integrator_name;
  std::unique_ptr<Integrator> integrator;
  const int prepared = prepare_on_all_ranks(ranks, [&] {
    if (!checks.check()) return 2;
    if (!o.scene_positional.empty() && !o.scene_flag.empty() &&
        o.scene_positional != o.scene_flag) {
      print_error("give the scene once (positional or --scene)");
      return 2;
    }
    scene_name = !o.scene_flag.empty() ? o.scene_flag : o.scene_positional;
    if (scene_name.empty()) scene_name = default_scene_name();
    if (!o.integrator.empty() && !check_name("integrator", o.integrator, integrator_names()))
      return 2;
    if (ranks.size() > 1 && !o.bidir.techniques_dir.empty()) {
      print_error(
          "--techniques writes the images of one process's iterations; it is not "
          "supported with more than one MPI rank");
      return 2;
    }
    SceneSetup setup = o;  // the shared part of the options
    setup.scene = scene_name;
    if (ranks.is_root()) {  // only rank 0 writes
      FileSection probing;  // the writability probes create a file
      if (std::string problem = output_problem(paths); !problem.empty()) {
        print_error("--outfile: " + problem);
        return 2;
      }
      if (!o.bidir.techniques_dir.empty())
        if (std::string problem = output_dir_problem(o.bidir.techniques_dir); !problem.empty()) {
          print_error("--techniques: " + problem);
          return 2;
        }
    }
    if (int rc = load_configured_scene(setup, &scene, &settings, &load_seconds)) return rc;

    integrator_name = o.integrator;
    if (integrator_name.empty()) {  // the scene file's (the loader maps pbrt-v4's names), else
      integrator_name = kDefaultIntegrator;
      for (const auto& n : integrator_names())
        if (n == scene->settings().integrator) integrator_name = n;
    }
    integrator = make_integrator(integrator_name, settings);
    return 0;
  });
  if (prepared != 0) return prepared;

  RenderBudget budget;
  budget.spp = o.spp;
  budget.seconds = o.seconds;
  if (budget.spp == 0 && budget.seconds == 0)
    budget.spp = scene->settings().spp > 0 ? scene->settings().spp : 16;

  const int threads = o.threads > 0 ? o.threads : tbb::info::default_concurrency();
  tbb::global_control limit(tbb::global_control::max_allowed_parallelism, size_t(threads));
  RenderCallbacks callbacks;
  callbacks.quiet = o.quiet;
  callbacks.progress_label = integrator_name;
  callbacks.stop = stop_flag();
  callbacks.ranks = &ranks;
  nlohmann::json stats;
  if (ranks.size() > 1) {
    callbacks.checkpoint_seconds = o.checkpoint_seconds;
    callbacks.on_checkpoint = [&](const Image& image, uint32_t iterations, double seconds) {
      nlohmann::json partial = {{"scene", scene_name},   {"integrator", integrator_name},
                                {"checkpoint", true},    {"iterations", iterations},
                                {"spp", iterations},     {"seconds", seconds},
                                {"ranks", ranks.size()}, {"threads_per_rank", threads},
                                {"seed", o.seed},        {"finished_at", iso_time_now()}};
      FileSection writing;
      write_render_outputs(image, partial, paths, o.exposure);
    };
  }
  arm_graceful_stop();
  const RenderResult result = render(*scene, *integrator, budget, callbacks);
  if (!ranks.is_root()) return exit_code_after_signals(0);  // rank 0 writes

  stats["scene"] = scene_name;
  stats["integrator"] = integrator_name;
  stats["resolution"] = {scene->camera().width(), scene->camera().height()};
  stats["iterations"] = result.iterations;
  stats["interrupted"] = result.interrupted;
  stats["spp"] = result.iterations;
  stats["seconds"] = result.seconds;
  stats["scene_load_seconds"] = load_seconds;
  stats["rays"] = result.rays;
  stats["rays_per_second"] = result.seconds > 0 ? double(result.rays) / result.seconds : 0.0;
  stats["nonfinite_samples_discarded"] = result.nonfinite;
  stats["peak_memory_mb"] = double(peak_memory_bytes()) / (1024 * 1024);
  stats["threads"] = threads;  // per rank
  stats["ranks"] = result.ranks;
  // What each rank sends in the film reduction: 3 channels x 16-byte fixed-point sums.
  stats["film_reduce_bytes_per_rank"] =
      result.ranks > 1 ? 48.0 * scene->camera().width() * scene->camera().height() : 0.0;
  stats["seed"] = o.seed;
  stats["max_depth"] = settings.max_depth;
  stats["mis"] = o.mis.empty() ? "default" : o.mis;
  stats["time_budget_seconds"] = o.seconds;
  stats["finished_at"] = iso_time_now();
  integrator->report(stats);

  {
    FileSection writing;
    write_render_outputs(result.image, stats, paths, o.exposure);
  }
  if (!o.quiet)
    std::fprintf(stderr, "%s: %u spp in %.2f s (%.2f Mrays/s) -> %s, %s, %s\n",
                 integrator_name.c_str(), result.iterations, result.seconds,
                 result.seconds > 0 ? result.rays / result.seconds * 1e-6 : 0.0, paths.exr.c_str(),
                 paths.png.c_str(), paths.json.c_str());
  return exit_code_after_signals(0);
}

}  // namespace

bool check_name(const std::string& what, const std::string& value,
                const std::vector<std::string>& valid) {
  for (const auto& v : valid)
    if (v == value) return true;
  std::string list;
  for (const auto& v : valid) list += (list.empty() ? "" : ", ") + v;
  print_error("unknown " + what + " " + excerpt(value) + "; valid: " + list);
  return false;
}

Runner add_render_command(CLI::App& app) {
  auto opts = std::make_shared<RenderOptions>();
  CLI::App* cmd =
      app.add_subcommand("render", "Render a scene (built-in name, .pbrt or .gltf/.glb file)");
  auto checks = std::make_shared<CheckedOptions>(cmd);
  cmd->footer(kInterruptHelp);
  cmd->add_option("scene", opts->scene_positional, "Scene name or file (default: cornell-glass)");
  cmd->add_option("--scene", opts->scene_flag,
                  "Scene name or file (same as the positional argument)");
  cmd->add_option("--integrator", opts->integrator,
                  "Integrator (default: the scene's, else " + std::string(kDefaultIntegrator) +
                      "): " + integrator_help());
  checks->integer("--spp", &opts->spp, 1, std::numeric_limits<int>::max(),
                  "Samples (iterations) per pixel, at least 1 (default: the scene's, else 16)");
  add_shared_options(*checks, opts.get(), "Time budget in seconds (iterations until it is spent)");
  cmd->add_option("--outfile", opts->outfile,
                  "Output file; writes NAME.exr, NAME.png and NAME.json (default caustica.exr); "
                  "its folder must exist and be writable");
  checks->number("--exposure", &opts->exposure, -64, 64, false,
                 "PNG exposure in stops, -64..64 (EXR is never tone mapped)");
  cmd->add_flag("--quiet,-q", opts->quiet, "No progress bar or summary");
  checks->number("--checkpoint", &opts->checkpoint_seconds, 0, kMaxSeconds, false,
                 "Under mpirun with several ranks: every this many seconds combine the ranks' "
                 "images and write the outputs, so that a killed run leaves one (default 60; 0: "
                 "only at the end)");
  return [opts, checks](Ranks& ranks) { return run_render(*opts, *checks, ranks); };
}

std::string integrator_help() {
  std::string help;
  for (const IntegratorInfo& info : integrator_registry())
    help += "\n  " + info.name + ": " + info.description;
  return help;
}

Runner add_integrators_command(CLI::App& app) {
  app.add_subcommand("integrators", "List the integrators, what each is, and its capabilities");
  return [](Ranks&) {
    int width = 0;
    for (const IntegratorInfo& info : integrator_registry())
      width = std::max(width, int(info.name.size()));
    for (const IntegratorInfo& info : integrator_registry())
      std::printf("%-*s %-11s %-15s %-12s %s%s\n", width, info.name.c_str(),
                  info.unbiased ? "unbiased" : "consistent",
                  info.default_mis == MisHeuristic::Power ? "mis: power" : "mis: balance",
                  info.caustics_through_specular ? "SDS: merges" : "SDS: no",
                  info.description.c_str(),
                  info.name == kDefaultIntegrator ? " [the default]" : "");
    return 0;
  };
}

Runner add_scenes_command(CLI::App& app) {
  CLI::App* cmd = app.add_subcommand("scenes", "List the built-in scenes");
  (void)cmd;
  return [](Ranks& ranks) {
    if (!ranks.is_root()) return 0;  // one list under mpirun
    for (const auto& s : builtin_scenes())
      std::printf("%-16s %s\n", s.name.c_str(), s.description.c_str());
    return 0;
  };
}

}  // namespace caustica::cli
