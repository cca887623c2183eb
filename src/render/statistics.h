// The JSON statistics of a render, assembled in one place for `render`, `reference` and each
// integrator of `compare`: what ran (scene, integrator, settings, threads), what it did
// (iterations, time, rays, discarded samples, peak memory) and the integrator's own report
// (e.g. light vertices and bytes each for the bidirectional family).
#pragma once

#include <nlohmann/json.hpp>
#include <string>

#include "integrators/integrator.h"
#include "render/renderer.h"

namespace caustica {

class Scene;

struct RunDescription {
  std::string scene;       // as the user named it
  std::string integrator;  // registry name
  IntegratorSettings settings;
  int threads = 0;         // worker threads used
  double time_budget = 0;  // seconds; 0 = none
  double scene_load_seconds = 0;
};

nlohmann::json render_statistics(const Scene& scene, const Integrator& integrator,
                                 const RenderResult& result, const RunDescription& run);

}  // namespace caustica
