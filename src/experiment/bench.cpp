#include "experiment/bench.h"

#include <tbb/global_control.h>

#if defined(__GLIBC__)
#include <malloc.h>
#endif

#include <algorithm>
#include <cstdio>
#include <fstream>
#include <stdexcept>

#include "experiment/build_info.h"
#include "integrators/registry.h"
#include "io/scene_loader.h"
#include "render/renderer.h"
#include "scene/ray_bench.h"
#include "scene/scene.h"

namespace caustica {

namespace {

double median(std::vector<double> v) {
  if (v.empty()) return 0;
  std::sort(v.begin(), v.end());
  const size_t m = v.size() / 2;
  return v.size() % 2 ? v[m] : 0.5 * (v[m - 1] + v[m]);
}

// Linux resets a process's peak resident set (VmHWM) when "5" is written to clear_refs
// (proc(5), since 4.0); then VmHWM after a render is that render's peak. Returns false where
// that is not allowed, and the caller falls back to the process's peak so far. Memory freed
// before (the raw-ray buffers, earlier renders) is first handed back to the system where the
// C library keeps it (glibc), so that the peak is the render's and not what was freed before.
bool reset_peak_memory() {
#if defined(__GLIBC__)
  malloc_trim(0);
#endif
  std::ofstream f("/proc/self/clear_refs");
  f << "5";
  f.flush();
  return bool(f);
}

// A field of /proc/self/status in bytes ("VmHWM:" the peak, "VmRSS:" now), or 0.
uint64_t status_bytes(const char* field) {
  std::ifstream status("/proc/self/status");
  const std::string key = field;
  for (std::string line; std::getline(status, line);)
    if (line.rfind(key, 0) == 0) return std::stoull(line.substr(key.size())) * 1024;  // in kB
  return 0;
}

// The samples of one (scene, integrator, threads) cell over the runs.
struct Samples {
  std::vector<double> ms_per_iteration, rays_per_second, paths_per_second, embree_intersect,
      embree_occluded, embree_bound, ratio, peak_mb, render_mb, grid_build_ms;
  nlohmann::json last_report;
  bool peak_is_per_render = true;
};

nlohmann::json summarize(const Samples& s, int threads) {
  nlohmann::json j;
  j["threads"] = threads;
  j["ms_per_iteration"] = median(s.ms_per_iteration);
  j["ms_per_iteration_runs"] = s.ms_per_iteration;
  j["rays_per_second"] = median(s.rays_per_second);
  j["paths_per_second"] = median(s.paths_per_second);
  j["embree_intersect_rays_per_second"] = median(s.embree_intersect);
  j["embree_occluded_rays_per_second"] = median(s.embree_occluded);
  j["embree_bound_rays_per_second"] = median(s.embree_bound);
  j["ratio_to_embree"] = median(s.ratio);
  j["peak_memory_mb"] = median(s.peak_mb);
  j["render_memory_mb"] = median(s.render_mb);
  j["peak_memory_scope"] = s.peak_is_per_render ? "render" : "process";
  if (!s.grid_build_ms.empty()) j["hash_grid_build_ms"] = median(s.grid_build_ms);
  return j;
}

}  // namespace

nlohmann::json run_bench(const BenchConfig& config, const BenchProgress& progress) {
  if (config.runs < 1 || config.iterations < 1 || config.threads.empty())
    throw std::invalid_argument("bench needs at least one run, iteration and thread count");
  nlohmann::json out = build_and_machine_json();
  out["settings"] = {{"iterations", config.iterations}, {"runs", config.runs},
                     {"threads", config.threads},       {"seed", config.seed},
                     {"bound_rays", config.bound_rays}, {"statistic", "median over runs"}};
  out["results"] = nlohmann::json::array();
  const double total_steps = double(config.scenes.size() * config.integrators.size() * config.runs *
                                    config.threads.size());
  double steps = 0;

  for (const std::string& scene_name : config.scenes) {
    std::unique_ptr<Scene> scene = load_scene(scene_name);
    if (config.width > 0) scene->override_resolution(config.width, config.height);
    const std::vector<Ray> bound_rays =
        make_incoherent_rays(*scene, config.bound_rays, config.seed);
    IntegratorSettings settings;
    const int scene_depth = scene->settings().max_depth;
    settings.max_depth =
        config.max_depth >= 0 ? config.max_depth : (scene_depth > 0 ? scene_depth : 10);
    settings.seed = config.seed;
    const double pixels = double(scene->camera().pixel_count());

    for (const std::string& integrator_name : config.integrators) {
      std::vector<Samples> cells(config.threads.size());
      // Runs outermost: each run visits every thread count, so slow drifts of the machine's
      // load spread over all of them instead of favouring one.
      for (int run = 0; run < config.runs; ++run)
        for (size_t ti = 0; ti < config.threads.size(); ++ti) {
          const int threads = config.threads[ti];
          Samples& s = cells[ti];
          tbb::global_control limit(tbb::global_control::max_allowed_parallelism, size_t(threads));
          const RayBenchResult bound = measure_raw_rays(*scene, bound_rays);

          auto integrator = make_integrator(integrator_name, settings);
          if (!integrator) throw std::runtime_error("unknown integrator '" + integrator_name + "'");
          s.peak_is_per_render = reset_peak_memory() && s.peak_is_per_render;
          const uint64_t resident_before = status_bytes("VmRSS:");
          const uint64_t occlusion_before = scene->occlusion_rays_traced();
          RenderBudget budget;
          budget.spp = config.iterations;
          RenderCallbacks quiet;
          quiet.quiet = true;
          const RenderResult r = render(*scene, *integrator, budget, quiet);
          const uint64_t occlusion = scene->occlusion_rays_traced() - occlusion_before;
          nlohmann::json report;
          integrator->report(report);

          const double seconds = std::max(r.seconds, 1e-9);
          const double rays_per_second = double(r.rays) / seconds;
          const double light_paths = report.contains("bidir")
                                         ? report["bidir"].value("light_paths_per_iteration", 0.0)
                                         : 0.0;
          const double bound_mixed =
              bound.mixed_rays_per_second(r.rays ? double(occlusion) / double(r.rays) : 0.0);
          s.ms_per_iteration.push_back(1e3 * seconds / r.iterations);
          s.rays_per_second.push_back(rays_per_second);
          s.paths_per_second.push_back((pixels + light_paths) * r.iterations / seconds);
          s.embree_intersect.push_back(bound.intersect_rays_per_second);
          s.embree_occluded.push_back(bound.occluded_rays_per_second);
          s.embree_bound.push_back(bound_mixed);
          s.ratio.push_back(bound_mixed > 0 ? rays_per_second / bound_mixed : 0.0);
          uint64_t peak = status_bytes("VmHWM:");
          if (!s.peak_is_per_render || peak == 0) peak = peak_memory_bytes();
          s.peak_mb.push_back(double(peak) / (1024 * 1024));
          s.render_mb.push_back(double(peak > resident_before ? peak - resident_before : 0) /
                                (1024 * 1024));
          if (report.contains("bidir") &&
              report["bidir"].contains("hash_grid_build_ms_per_iteration"))
            s.grid_build_ms.push_back(report["bidir"]["hash_grid_build_ms_per_iteration"]);
          s.last_report = report;
          steps += 1;
          if (progress) progress(steps / total_steps, rays_per_second * 1e-6);
        }

      nlohmann::json row;
      row["scene"] = scene_name;
      row["integrator"] = integrator_name;
      row["resolution"] = {scene->camera().width(), scene->camera().height()};
      row["triangles"] = scene->triangle_count();
      row["max_depth"] = settings.max_depth;
      row["per_thread_count"] = nlohmann::json::array();
      double ms_one_thread = 0;
      for (size_t ti = 0; ti < config.threads.size(); ++ti) {
        nlohmann::json cell = summarize(cells[ti], config.threads[ti]);
        if (config.threads[ti] == 1) ms_one_thread = cell["ms_per_iteration"];
        row["per_thread_count"].push_back(cell);
      }
      for (auto& cell : row["per_thread_count"])
        if (ms_one_thread > 0)
          cell["speedup_vs_1_thread"] = ms_one_thread / cell["ms_per_iteration"].get<double>();
      // The bidirectional statistics do not depend on the thread count (same paths).
      if (const nlohmann::json& rep = cells.back().last_report; rep.contains("bidir")) {
        const nlohmann::json& b = rep["bidir"];
        for (const char* key :
             {"light_paths_per_iteration", "light_vertices_per_iteration", "bytes_per_light_vertex",
              "light_vertex_buffer_bytes", "hash_grid_bytes"})
          if (b.contains(key)) row[key] = b[key];
      }
      out["results"].push_back(row);
    }
  }
  return out;
}

std::string bench_table(const nlohmann::json& result) {
  std::string text;
  char line[512];
  std::snprintf(
      line, sizeof line, "# %s, %u logical cores; %s build, commit %s; median of %d runs\n",
      result["machine"]["cpu"].get<std::string>().c_str(),
      result["machine"]["logical_cores"].get<unsigned>(),
      result["build"]["build_type"].get<std::string>().c_str(),
      result["build"]["commit"].get<std::string>().c_str(), result["settings"]["runs"].get<int>());
  text += line;
  // The integrator column is as wide as the longest name measured (adaptive-vcm, guided-pt).
  int width = 10;
  for (const auto& row : result["results"])
    width = std::max(width, int(row["integrator"].get<std::string>().size()));
  std::snprintf(line, sizeof line, "%-16s %-*s %3s %10s %9s %9s %9s %7s %8s %8s %8s %8s\n", "scene",
                width, "integrator", "thr", "ms/iter", "Mrays/s", "Membree", "Mpaths/s", "ratio",
                "speedup", "peak MB", "+MB", "grid ms");
  text += line;
  for (const auto& row : result["results"])
    for (const auto& c : row["per_thread_count"]) {
      std::snprintf(line, sizeof line,
                    "%-16s %-*s %3d %10.2f %9.2f %9.2f %9.3f %7.3f %8.2f %8.1f %8.1f %8.2f\n",
                    row["scene"].get<std::string>().c_str(), width,
                    row["integrator"].get<std::string>().c_str(), c["threads"].get<int>(),
                    c["ms_per_iteration"].get<double>(), c["rays_per_second"].get<double>() * 1e-6,
                    c["embree_bound_rays_per_second"].get<double>() * 1e-6,
                    c["paths_per_second"].get<double>() * 1e-6, c["ratio_to_embree"].get<double>(),
                    c.value("speedup_vs_1_thread", 0.0), c["peak_memory_mb"].get<double>(),
                    c["render_memory_mb"].get<double>(), c.value("hash_grid_build_ms", 0.0));
      text += line;
    }
  return text;
}

}  // namespace caustica
