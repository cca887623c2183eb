#include "render/statistics.h"

#include <ctime>

#include "scene/scene.h"

namespace caustica {

namespace {
std::string iso_time_now() {
  const std::time_t t = std::time(nullptr);
  char buf[32];
  std::strftime(buf, sizeof buf, "%Y-%m-%dT%H:%M:%SZ", std::gmtime(&t));
  return buf;
}
}  // namespace

nlohmann::json render_statistics(const Scene& scene, const Integrator& integrator,
                                 const RenderResult& r, const RunDescription& run) {
  nlohmann::json s;
  s["scene"] = run.scene;
  s["integrator"] = run.integrator;
  s["resolution"] = {scene.camera().width(), scene.camera().height()};
  s["iterations"] = r.iterations;
  s["spp"] = r.iterations;
  s["interrupted"] = r.interrupted;
  s["seconds"] = r.seconds;
  s["scene_load_seconds"] = run.scene_load_seconds;
  s["rays"] = r.rays;
  s["rays_per_second"] = r.seconds > 0 ? double(r.rays) / r.seconds : 0.0;
  s["nonfinite_samples_discarded"] = r.nonfinite;
  s["peak_memory_mb"] = double(peak_memory_bytes()) / (1024 * 1024);
  s["threads"] = run.threads;  // per rank
  s["ranks"] = r.ranks;
  // What each rank sends in the film reduction: 3 channels x 16-byte fixed-point sums.
  s["film_reduce_bytes_per_rank"] =
      r.ranks > 1 ? 48.0 * scene.camera().width() * scene.camera().height() : 0.0;
  s["seed"] = run.settings.seed;
  s["max_depth"] = run.settings.max_depth;
  s["mis"] = !run.settings.mis                          ? "default"
             : *run.settings.mis == MisHeuristic::Power ? "power"
                                                        : "balance";
  s["time_budget_seconds"] = run.time_budget;
  s["finished_at"] = iso_time_now();
  integrator.report(s);
  return s;
}

}  // namespace caustica
