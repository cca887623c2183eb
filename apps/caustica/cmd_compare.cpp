// `caustica reference` and `caustica compare`: long reference renders and equal-time
// comparisons of integrators with error curves and an HTML report.
#include <tbb/global_control.h>
#include <tbb/info.h>

#include <cstdio>
#include <filesystem>
#include <sstream>

#include "commands.h"
#include "experiment/comparison.h"
#include "experiment/report.h"
#include "image/image_io.h"
#include "integrators/registry.h"
#include "render/output.h"
#include "render/progress.h"
#include "render/renderer.h"
#include "scene/scene.h"
#include "scene_setup.h"

namespace caustica::cli {

namespace {

struct CommonOptions : SceneSetup {
  double seconds = 0;
  int threads = 0;
};

void add_common(CLI::App* cmd, CommonOptions& o) {
  cmd->add_option("scene", o.scene, "Scene name or file")->required();
  cmd->add_option("--threads", o.threads, "Worker threads (default: all cores)");
  cmd->add_option("--max-depth", o.max_depth,
                  "Maximum scattering vertices (default: the scene's, else 10)");
  cmd->add_option("--seed", o.seed, "Random seed");
  cmd->add_option("--resolution", o.resolution, "Override the film resolution, WxH");
  cmd->add_option("--mis", o.mis, "MIS heuristic: balance or power (default: each integrator's)");
  cmd->add_option("--camera", o.camera, "glTF: which camera to use (default: the first)");
}

int prepare(const CommonOptions& o, std::unique_ptr<Scene>* scene, IntegratorSettings* settings) {
  if (o.seconds <= 0) {
    std::fprintf(stderr, "caustica: error: --time must be positive\n");
    return 2;
  }
  return load_configured_scene(o, scene, settings);
}

std::vector<std::string> split_list(const std::string& s) {
  std::vector<std::string> out;
  std::stringstream ss(s);
  std::string item;
  while (std::getline(ss, item, ','))
    if (!item.empty()) out.push_back(item);
  return out;
}

struct ReferenceOptions : CommonOptions {
  std::string integrator = "pt";
  std::string outfile;
};

int run_reference(const ReferenceOptions& o) {
  if (!check_name("integrator", o.integrator, integrator_names())) return 2;
  std::unique_ptr<Scene> scene;
  IntegratorSettings settings;
  if (int rc = prepare(o, &scene, &settings)) return rc;
  const int threads = o.threads > 0 ? o.threads : tbb::info::default_concurrency();
  tbb::global_control limit(tbb::global_control::max_allowed_parallelism, size_t(threads));
  auto integrator = make_integrator(o.integrator, settings);
  RenderBudget budget;
  budget.seconds = o.seconds;
  RenderCallbacks cb;
  cb.progress_label = "reference " + o.integrator;
  const RenderResult r = render(*scene, *integrator, budget, cb);
  const std::string out =
      o.outfile.empty() ? std::filesystem::path(o.scene).stem().string() + "-ref" : o.outfile;
  nlohmann::json meta = {{"kind", "reference"},
                         {"scene", o.scene},
                         {"integrator", o.integrator},
                         {"seconds", r.seconds},
                         {"iterations", r.iterations},
                         {"seed", o.seed},
                         {"threads", threads},
                         {"max_depth", settings.max_depth},
                         {"resolution", {scene->camera().width(), scene->camera().height()}},
                         {"rays", r.rays},
                         {"nonfinite_samples_discarded", r.nonfinite},
                         {"peak_memory_mb", double(peak_memory_bytes()) / (1024 * 1024)}};
  integrator->report(meta);
  const OutputPaths paths = output_paths_for(out);
  write_render_outputs(r.image, meta, paths, 0.f);
  std::fprintf(stderr, "reference: %u iterations of %s in %.1f s -> %s (+ .png, .json)\n",
               r.iterations, o.integrator.c_str(), r.seconds, paths.exr.c_str());
  return 0;
}

struct CompareOptions : CommonOptions {
  std::string integrators = "pt,bpt,vcm,ppm";
  std::string reference;
  std::string out_dir;
  std::string reference_integrator = "";
  double reference_seconds = 0;
};

int run_compare(const CompareOptions& o) {
  std::vector<std::string> names = split_list(o.integrators);
  if (names.empty()) {
    std::fprintf(stderr, "caustica compare: error: --integrators is empty\n");
    return 2;
  }
  for (const auto& n : names)
    if (!check_name("integrator", n, integrator_names())) return 2;
  std::unique_ptr<Scene> scene;
  IntegratorSettings settings;
  if (int rc = prepare(o, &scene, &settings)) return rc;
  const int threads = o.threads > 0 ? o.threads : tbb::info::default_concurrency();
  const std::string dir =
      o.out_dir.empty() ? std::filesystem::path(o.scene).stem().string() + "-compare" : o.out_dir;

  Image reference;
  std::string ref_description;
  if (!o.reference.empty()) {
    reference = read_image(o.reference, false);
    ref_description = o.reference;
  } else {
    // No reference given: render one first, 4x the per-integrator time, with the most robust
    // integrator available.
    std::string ref_integrator = o.reference_integrator;
    if (ref_integrator.empty()) {
      ref_integrator = "pt";
      for (const auto& n : integrator_names())
        if (n == "vcm") ref_integrator = "vcm";
    }
    if (!check_name("integrator", ref_integrator, integrator_names())) return 2;
    const double seconds = o.reference_seconds > 0 ? o.reference_seconds : 4 * o.seconds;
    std::fprintf(stderr, "compare: no --reference given; rendering one with %s for %.0f s first\n",
                 ref_integrator.c_str(), seconds);
    tbb::global_control limit(tbb::global_control::max_allowed_parallelism, size_t(threads));
    IntegratorSettings ref_settings = settings;
    ref_settings.seed = settings.seed + 7919;  // independent of the compared runs' noise
    auto integrator = make_integrator(ref_integrator, ref_settings);
    RenderBudget budget;
    budget.seconds = seconds;
    RenderCallbacks cb;
    cb.progress_label = "reference " + ref_integrator;
    const RenderResult r = render(*scene, *integrator, budget, cb);
    reference = r.image;
    std::ostringstream d;
    d << ref_integrator << ", " << r.iterations << " iterations, " << int(r.seconds + 0.5)
      << " s, rendered by compare";
    ref_description = d.str();
  }

  ComparisonConfig config;
  config.integrators = names;
  config.seconds = o.seconds;
  config.threads = threads;
  config.settings = settings;
  ProgressBar bar("compare");
  ComparisonResult result =
      run_comparison(*scene, reference, config, [&](double f, const std::string& name) {
        (void)name;
        bar.update(f, f * config.seconds * names.size(), "s rendered");
      });
  bar.finish();
  result.scene = o.scene;
  result.reference_description = ref_description;
  write_comparison_report(result, reference, dir);
  std::printf("%-8s %10s %8s %12s %12s %8s %10s\n", "", "iterations", "Mrays/s", "relMSE",
              "relMSE-trim", "SSIM", "vs pt");
  for (const auto& row : comparison_summary(result)) {
    const auto& e = row["errors"];
    const bool has = row.contains("speedup_vs_pt") && row["speedup_vs_pt"].is_number();
    std::printf("%-8s %10u %8.2f %12.4g %12.4g %8.4f %9.2fx\n",
                row["integrator"].get<std::string>().c_str(), row["iterations"].get<uint32_t>(),
                row["rays_per_second"].get<double>() * 1e-6, e["relmse"].get<double>(),
                e["relmse_trimmed"].get<double>(), e["ssim"].get<double>(),
                has ? row["speedup_vs_pt"].get<double>() : 0.0);
  }
  std::fprintf(stderr, "compare: report in %s/index.html\n", dir.c_str());
  return 0;
}

}  // namespace

Runner add_reference_command(CLI::App& app) {
  auto o = std::make_shared<ReferenceOptions>();
  CLI::App* cmd =
      app.add_subcommand("reference", "Render a long reference image (EXR + PNG + JSON metadata)");
  add_common(cmd, *o);
  cmd->add_option("--time", o->seconds, "Render time in seconds")->required();
  cmd->add_option("--integrator", o->integrator, "Integrator (default pt)");
  cmd->add_option("--outfile", o->outfile,
                  "Output name (default SCENE-ref): NAME.exr, NAME.png, NAME.json");
  return [o] { return run_reference(*o); };
}

Runner add_compare_command(CLI::App& app) {
  auto o = std::make_shared<CompareOptions>();
  CLI::App* cmd = app.add_subcommand(
      "compare", "Equal-time comparison of integrators against a reference, with an HTML report");
  add_common(cmd, *o);
  cmd->add_option("--time", o->seconds, "Seconds per integrator")->required();
  cmd->add_option("--integrators", o->integrators,
                  "Comma-separated integrators (default pt,bpt,vcm,ppm)");
  cmd->add_option("--reference", o->reference,
                  "Reference EXR (default: render one first, 4x --time)");
  cmd->add_option("--reference-integrator", o->reference_integrator,
                  "Integrator for the reference render (default vcm, else pt)");
  cmd->add_option("--reference-time", o->reference_seconds,
                  "Seconds for the reference render (default 4x --time)");
  cmd->add_option("--out", o->out_dir, "Output directory (default SCENE-compare)");
  return [o] { return run_compare(*o); };
}

}  // namespace caustica::cli
