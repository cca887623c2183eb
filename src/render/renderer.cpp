#include "render/renderer.h"

#include <sys/resource.h>

#include <chrono>
#include <stdexcept>

#include "film/film.h"
#include "render/progress.h"
#include "scene/scene.h"

namespace caustica {

uint64_t peak_memory_bytes() {
  struct rusage usage {};
  getrusage(RUSAGE_SELF, &usage);
  return uint64_t(usage.ru_maxrss) * 1024;  // Linux reports kilobytes
}

RenderResult render(const Scene& scene, Integrator& integrator, const RenderBudget& budget,
                    const RenderCallbacks& callbacks) {
  if (budget.spp <= 0 && budget.seconds <= 0)
    throw std::invalid_argument("render budget needs spp or seconds");
  Film film(scene.camera().width(), scene.camera().height());
  ProgressBar progress(callbacks.progress_label, callbacks.quiet);
  const auto start = std::chrono::steady_clock::now();
  const uint64_t rays_before = scene.rays_traced();
  double paused = 0;  // seconds spent in callbacks, not counted as render time
  auto elapsed = [&] {
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count() - paused;
  };

  integrator.prepare(scene, film);
  bool interrupted = false;
  for (uint32_t it = 0;; ++it) {
    if (budget.spp > 0 && it >= uint32_t(budget.spp)) break;
    if (budget.seconds > 0 && it > 0 && elapsed() >= budget.seconds) break;
    // After the budget checks, so a stop that arrives during the last iteration is not
    // reported as an interruption of a render that was complete anyway.
    if (it > 0 && callbacks.stop && callbacks.stop->load()) {
      interrupted = true;
      break;
    }
    integrator.render_iteration(scene, it, film);
    film.end_iteration();
    const double t = elapsed();
    const double frac_spp = budget.spp > 0 ? double(it + 1) / budget.spp : 0;
    const double frac_time = budget.seconds > 0 ? t / budget.seconds : 0;
    const double mrays = t > 0 ? double(scene.rays_traced() - rays_before) / t * 1e-6 : 0;
    progress.update(std::max(frac_spp, frac_time), mrays, "Mrays/s");
    if (callbacks.on_iteration) {
      const auto before = std::chrono::steady_clock::now();
      const bool go_on = callbacks.on_iteration(film, it + 1, t);
      paused += std::chrono::duration<double>(std::chrono::steady_clock::now() - before).count();
      if (!go_on) break;
    }
  }
  integrator.finish(scene, film);
  const double total = elapsed();
  if (!interrupted)
    progress.update(1.0, total > 0 ? double(scene.rays_traced() - rays_before) / total * 1e-6 : 0,
                    "Mrays/s");
  progress.finish();

  RenderResult r;
  r.seconds = elapsed();
  r.image = film.image();
  r.iterations = film.iterations();
  r.rays = scene.rays_traced() - rays_before;
  r.nonfinite = film.nonfinite_count();
  r.interrupted = interrupted;
  return r;
}

}  // namespace caustica
