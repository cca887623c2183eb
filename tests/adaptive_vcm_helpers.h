// Helpers shared by the adaptive-vcm tests (adaptive_vcm_test.cpp,
// adaptive_vcm_prediction_test.cpp).
#pragma once

#include <nlohmann/json.hpp>

#include "film/film.h"
#include "integrators/registry.h"
#include "scene/scene.h"

namespace caustica::test {

// The statistics of adaptive-vcm after `iterations` iterations on the scene.
// budget: the iterations the plan is told it has (default: those rendered; 0: none known).
inline nlohmann::json adaptive_stats(const Scene& scene, const IntegratorSettings& s,
                                     int iterations, int budget = -1) {
  auto in = make_integrator("adaptive-vcm", s);
  // As render() does: the probes' schedule and path tracing's bias weight read it.
  in->set_budget(budget < 0 ? iterations : budget, 0);
  Film film(scene.camera().width(), scene.camera().height());
  in->prepare(scene, film);
  for (int i = 0; i < iterations; ++i) {
    in->render_iteration(scene, uint32_t(i), film);
    film.end_iteration();
  }
  nlohmann::json stats;
  in->report(stats);
  return stats;
}

}  // namespace caustica::test
