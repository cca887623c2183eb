// `caustica reference` and `caustica compare`: long reference renders and equal-time
// comparisons of integrators with error curves and an HTML report.
#include <tbb/global_control.h>
#include <tbb/info.h>

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <optional>
#include <sstream>

#include "commands.h"
#include "experiment/comparison.h"
#include "experiment/report.h"
#include "image/image_io.h"
#include "integrators/registry.h"
#include "interrupt.h"
#include "preflight.h"
#include "ranks_cli.h"
#include "render/output.h"
#include "render/progress.h"
#include "render/renderer.h"
#include "render/statistics.h"
#include "scene/scene.h"
#include "scene_setup.h"

namespace caustica::cli {

std::vector<std::string> split_list(const std::string& s) {
  std::vector<std::string> out;
  std::stringstream ss(s);
  std::string item;
  while (std::getline(ss, item, ','))
    if (!item.empty()) out.push_back(item);
  return out;
}

namespace {

// A reference's default seed, and the offset compare adds to --seed for the reference it renders
// itself: a reference must not share its random numbers with the runs it judges. Rendered with
// the runs' seed, a vcm reference repeats the first iterations of a vcm or bpt run exactly (the
// same camera and light paths), their errors cancel, and those integrators look better than
// they are (measured on cornell-box 160x160, 20 s runs against 60 s vcm references: bpt's relMSE
// 0.000148 against the seed-0 reference and 0.000733 against an independent one, 5x too low).
constexpr uint64_t kReferenceSeedOffset = 7919;
// The most runs per integrator: below kReferenceSeedOffset, so that the runs' seeds never reach
// the seed of a reference compare renders itself.
constexpr int kMaxCompareRuns = 1000;

struct ReferenceOptions : SharedOptions {
  ReferenceOptions() { seed = kReferenceSeedOffset; }
  std::string integrator = "pt";
  std::string outfile;
  double checkpoint_seconds = 60;
  bool quiet = false;
};

int run_reference(const ReferenceOptions& o, const CheckedOptions& checks, Ranks& ranks) {
  OutputPaths paths;
  std::unique_ptr<Scene> scene;
  IntegratorSettings settings;
  const int prepared = prepare_on_all_ranks(ranks, [&] {
    if (!checks.check()) return 2;
    if (!check_name("integrator", o.integrator, integrator_names())) return 2;
    const std::string out =
        o.outfile.empty() ? std::filesystem::path(o.scene).stem().string() + "-ref" : o.outfile;
    paths = output_paths_for(out);
    if (ranks.is_root()) {  // only rank 0 writes
      FileSection probing;  // the writability probe creates a file
      if (std::string problem = output_problem(paths); !problem.empty()) {
        print_error("--outfile: " + problem);
        return 2;
      }
    }
    return load_configured_scene(o, &scene, &settings);
  });
  if (prepared != 0) return prepared;
  const int threads = o.threads > 0 ? o.threads : tbb::info::default_concurrency();
  tbb::global_control limit(tbb::global_control::max_allowed_parallelism, size_t(threads));
  auto integrator = make_integrator(o.integrator, settings);
  RenderBudget budget;
  budget.seconds = o.seconds;
  RenderCallbacks cb;
  cb.progress_label = "reference " + o.integrator;
  cb.quiet = o.quiet;
  cb.stop = stop_flag();
  cb.ranks = &ranks;
  if (ranks.size() > 1) {
    cb.checkpoint_seconds = o.checkpoint_seconds;
    cb.on_checkpoint = [&](const Image& image, uint32_t iterations, double seconds) {
      const nlohmann::json partial = {{"kind", "reference"}, {"checkpoint", true},
                                      {"scene", o.scene},    {"integrator", o.integrator},
                                      {"seconds", seconds},  {"iterations", iterations},
                                      {"seed", o.seed},      {"ranks", ranks.size()}};
      FileSection writing;
      write_render_outputs(image, partial, paths, 0.f);
    };
  }
  arm_graceful_stop();
  const RenderResult r = render(*scene, *integrator, budget, cb);
  if (!ranks.is_root()) return exit_code_after_signals(0);  // rank 0 writes
  RunDescription run;
  run.scene = o.scene;
  run.integrator = o.integrator;
  run.settings = settings;
  run.threads = threads;
  run.time_budget = o.seconds;
  nlohmann::json meta = render_statistics(*scene, *integrator, r, run);
  meta["kind"] = "reference";
  {
    FileSection writing;
    write_render_outputs(r.image, meta, paths, 0.f);
  }
  std::fprintf(stderr, "reference: %u iterations of %s in %.1f s -> %s (+ .png, .json)\n",
               r.iterations, o.integrator.c_str(), r.seconds, paths.exr.c_str());
  return exit_code_after_signals(0);
}

// The seed in the JSON metadata `caustica reference` writes beside REF.exr (REF.json), if any.
std::optional<uint64_t> reference_seed(const std::string& reference) {
  const std::filesystem::path meta = std::filesystem::path(reference).replace_extension(".json");
  std::error_code ec;
  if (!std::filesystem::is_regular_file(meta, ec)) return std::nullopt;
  try {
    std::ifstream in(meta);
    const nlohmann::json j = nlohmann::json::parse(in);
    if (j.contains("seed") && j["seed"].is_number_unsigned()) return j["seed"].get<uint64_t>();
  } catch (const std::exception&) {
  }
  return std::nullopt;  // unreadable metadata says nothing: the reference itself was checked
}

// runs: the runs use seeds seed, seed + 1, ..., seed + runs - 1.
void warn_if_reference_shares_seed(const std::string& reference, uint64_t seed, int runs) {
  const std::optional<uint64_t> ref_seed = reference_seed(reference);
  if (!ref_seed || *ref_seed - seed >= uint64_t(runs)) return;  // unsigned: also below seed
  std::fprintf(stderr,
               "compare: warning: %s was rendered with seed %llu, a seed of these runs: "
               "integrators that sample like the reference's share its noise and their errors "
               "are underestimated; pass another --seed here or to `caustica reference`\n",
               excerpt(reference).c_str(), static_cast<unsigned long long>(*ref_seed));
}

// The summary on stdout, one line per integrator; with several runs its errors are the median
// run's, and the least and largest relMSE of its runs follow.
void print_summary(const nlohmann::json& summary, int runs) {
  std::printf("%-12s %10s %8s %12s %12s %8s %10s%s\n", "", "iterations", "Mrays/s",
              runs > 1 ? "relMSE(med)" : "relMSE", "relMSE-trim", "SSIM", "vs pt",
              runs > 1 ? "   relMSE min - max (runs)" : "");
  for (const auto& row : summary) {
    const auto& e = row["errors"];
    const bool has = row.contains("speedup_vs_pt") && row["speedup_vs_pt"].is_number();
    std::printf("%-12s %10u %8.2f %12.4g %12.4g %8.4f %9.2fx",
                row["integrator"].get<std::string>().c_str(), row["iterations"].get<uint32_t>(),
                row["rays_per_second"].get<double>() * 1e-6, e["relmse"].get<double>(),
                e["relmse_trimmed"].get<double>(), e["ssim"].get<double>(),
                has ? row["speedup_vs_pt"].get<double>() : 0.0);
    if (row.contains("relmse_min"))
      std::printf("   %.4g - %.4g (%zu)", row["relmse_min"].get<double>(),
                  row["relmse_max"].get<double>(), row["runs"].get<size_t>());
    std::printf("\n");
  }
}

struct CompareOptions : SharedOptions {
  std::string integrators = std::string(kDefaultIntegrator) + ",pt,bpt,vcm,ppm";
  std::string reference;
  std::string out_dir;
  std::string reference_integrator = "";
  double reference_seconds = 0;
  int runs = 1;
};

int run_compare(const CompareOptions& o, const CheckedOptions& checks, Ranks& ranks) {
  // Under mpirun rank 0 runs the whole comparison; the other ranks check their options (so that
  // a bad one ends all of them with one message) and then wait, sleeping, for rank 0.
  if (ranks.size() > 1) {
    int rc = prepare_on_all_ranks(ranks, [&] { return checks.check() ? 0 : 2; });
    if (rc != 0) return rc;
    if (!ranks.is_root()) {
      arm_graceful_stop();  // a signal must not end this rank while rank 0 writes the report
      ranks.wait_all();
      return exit_code_after_signals(0);
    }
    std::fprintf(stderr, "compare: runs on rank 0 only; the other %d ranks wait\n",
                 ranks.size() - 1);
    SingleProcess alone;
    rc = run_compare(o, checks, alone);
    ranks.wait_all();
    return rc;
  }
  if (!checks.check()) return 2;
  std::vector<std::string> names = split_list(o.integrators);
  if (names.empty()) {
    print_error("--integrators is empty");
    return 2;
  }
  for (const auto& n : names)
    if (!check_name("integrator", n, integrator_names())) return 2;
  if (!o.reference_integrator.empty() &&
      !check_name("integrator", o.reference_integrator, integrator_names()))
    return 2;
  const std::string dir =
      o.out_dir.empty() ? std::filesystem::path(o.scene).stem().string() + "-compare" : o.out_dir;
  {
    FileSection probing;  // the writability probe creates a file
    if (std::string problem = output_dir_problem(dir); !problem.empty()) {
      print_error("--out: " + problem);
      return 2;
    }
  }
  Image reference;
  if (!o.reference.empty()) {
    if (std::string problem = reference_problem(o.reference, &reference); !problem.empty()) {
      print_error(problem);
      return 2;
    }
  }
  std::unique_ptr<Scene> scene;
  IntegratorSettings settings;
  if (int rc = load_configured_scene(o, &scene, &settings)) return rc;
  const int width = scene->camera().width(), height = scene->camera().height();
  if (!o.reference.empty() && (reference.width() != width || reference.height() != height)) {
    print_error("--reference " + excerpt(o.reference) + " is " + std::to_string(reference.width()) +
                "x" + std::to_string(reference.height()) + " but the scene renders " +
                std::to_string(width) + "x" + std::to_string(height) + " (see --resolution)");
    return 2;
  }
  const int threads = o.threads > 0 ? o.threads : tbb::info::default_concurrency();
  arm_graceful_stop();

  std::string ref_description;
  if (!o.reference.empty()) {
    ref_description = o.reference;
    warn_if_reference_shares_seed(o.reference, settings.seed, o.runs);
  } else {
    // No reference given: render one first, 4x the per-integrator time, with the most robust
    // integrator available.
    std::string ref_integrator = o.reference_integrator;
    if (ref_integrator.empty()) {
      ref_integrator = "pt";
      for (const auto& n : integrator_names())
        if (n == "vcm") ref_integrator = "vcm";
    }
    const double seconds = o.reference_seconds > 0 ? o.reference_seconds : 4 * o.seconds;
    std::fprintf(stderr, "compare: no --reference given; rendering one with %s for %.0f s first\n",
                 ref_integrator.c_str(), seconds);
    tbb::global_control limit(tbb::global_control::max_allowed_parallelism, size_t(threads));
    IntegratorSettings ref_settings = settings;
    ref_settings.seed = settings.seed + kReferenceSeedOffset;  // independent of the runs' noise
    auto integrator = make_integrator(ref_integrator, ref_settings);
    RenderBudget budget;
    budget.seconds = seconds;
    RenderCallbacks cb;
    cb.progress_label = "reference " + ref_integrator;
    cb.stop = stop_flag();
    const RenderResult r = render(*scene, *integrator, budget, cb);
    if (r.interrupted) {
      // Errors against a reference cut short would measure the reference's noise.
      std::fprintf(stderr, "compare: interrupted while rendering the reference; nothing written\n");
      return exit_code_after_signals(0);
    }
    reference = r.image;
    std::ostringstream d;
    d << ref_integrator << ", " << r.iterations << " iterations, " << int(r.seconds + 0.5)
      << " s, rendered by compare";
    ref_description = d.str();
  }

  ComparisonConfig config;
  config.integrators = names;
  config.seconds = o.seconds;
  config.runs = o.runs;
  config.threads = threads;
  config.settings = settings;
  config.stop = stop_flag();
  ProgressBar bar("compare");
  ComparisonResult result =
      run_comparison(*scene, reference, config, [&](double f, const std::string& name) {
        (void)name;
        bar.update(f, f * config.seconds * double(names.size()) * config.runs, "s rendered");
      });
  bar.finish();
  if (result.runs.empty()) {
    std::fprintf(stderr, "compare: interrupted before any integrator completed; nothing written\n");
    return exit_code_after_signals(0);
  }
  result.scene = o.scene;
  result.reference_description = ref_description;
  {
    FileSection writing;
    write_comparison_report(result, reference, dir);
  }
  print_summary(comparison_summary(result), config.runs);
  if (result.interrupted)
    std::fprintf(stderr, "compare: interrupted; the report holds the %zu integrators completed\n",
                 result.runs.size());
  std::fprintf(stderr, "compare: report in %s/index.html\n", dir.c_str());
  return exit_code_after_signals(0);
}

}  // namespace

Runner add_reference_command(CLI::App& app) {
  auto o = std::make_shared<ReferenceOptions>();
  CLI::App* cmd =
      app.add_subcommand("reference", "Render a long reference image (EXR + PNG + JSON metadata)");
  auto checks = std::make_shared<CheckedOptions>(cmd);
  cmd->footer(kInterruptHelp);
  cmd->add_option("scene", o->scene, "Scene name or file")->required();
  add_shared_options(*checks, o.get(), "Render time in seconds")->required();
  cmd->get_option("--seed")->description(
      "Random seed (default " + std::to_string(kReferenceSeedOffset) +
      ", not render's and compare's 0: a reference must not share the noise of the runs it "
      "judges)");
  cmd->add_option("--integrator", o->integrator, "Integrator (default pt)");
  cmd->add_option("--outfile", o->outfile,
                  "Output name (default SCENE-ref): NAME.exr, NAME.png, NAME.json; its folder must "
                  "exist and be writable");
  checks->number("--checkpoint", &o->checkpoint_seconds, 0, kMaxSeconds, false,
                 "Under mpirun with several ranks: every this many seconds combine the ranks' "
                 "images and write the outputs (default 60; 0: only at the end)");
  cmd->add_flag("--quiet,-q", o->quiet, "No progress bar");
  return [o, checks](Ranks& ranks) { return run_reference(*o, *checks, ranks); };
}

Runner add_compare_command(CLI::App& app) {
  auto o = std::make_shared<CompareOptions>();
  CLI::App* cmd = app.add_subcommand(
      "compare", "Equal-time comparison of integrators against a reference, with an HTML report");
  auto checks = std::make_shared<CheckedOptions>(cmd);
  cmd->footer(
      "Ctrl-C or SIGTERM: stop; the report holds the integrators that completed their time "
      "(exit 130 / 143); a second Ctrl-C quits at once.");
  cmd->add_option("scene", o->scene, "Scene name or file")->required();
  add_shared_options(*checks, o.get(), "Seconds per integrator")->required();
  cmd->add_option(
      "--integrators", o->integrators,
      "Comma-separated integrators (default adaptive-vcm,pt,bpt,vcm,ppm) of: " + integrator_help());
  cmd->add_option(
      "--reference", o->reference,
      "Reference image (EXR), the scene's resolution (default: render one first, 4x --time)");
  cmd->add_option("--reference-integrator", o->reference_integrator,
                  "Integrator for the reference render (default vcm, else pt)");
  checks->number("--reference-time", &o->reference_seconds, 0, kMaxSeconds, true,
                 "Seconds for the reference render (default 4x --time; at most 30 days)");
  cmd->add_option("--out", o->out_dir,
                  "Output directory (default SCENE-compare), created if missing");
  checks->integer("--runs", &o->runs, 1, kMaxCompareRuns,
                  "Runs per integrator, with seeds --seed, --seed + 1, ... (default 1; at most " +
                      std::to_string(kMaxCompareRuns) +
                      "): the integrators take turns in each round, so that a drift of the "
                      "machine's speed falls on all of them; the report shows each one's median "
                      "run by relMSE and lists every run's errors (runs.csv)");
  return [o, checks](Ranks& ranks) { return run_compare(*o, *checks, ranks); };
}

}  // namespace caustica::cli
