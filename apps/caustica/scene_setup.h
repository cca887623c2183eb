// What every rendering subcommand does before it renders: validate the shared options, load
// the scene, apply the resolution override and derive the integrator settings. Errors are
// printed here; the caller returns the exit code.
#pragma once

#include <cstdint>
#include <memory>
#include <string>

#include "integrators/integrator.h"
#include "scene/scene.h"

namespace caustica::cli {

struct SceneSetup {
  std::string scene;       // built-in name or file
  int camera = -1;         // glTF camera index (-1: the first)
  std::string resolution;  // "WxH" or empty
  int max_depth = -1;      // -1: the scene's, else 10
  uint64_t seed = 0;
  std::string mis;  // "", "balance" or "power"; empty: each integrator's default
};

// Returns 0 and fills *scene / *settings, or prints the problem and returns the exit code (2).
int load_configured_scene(const SceneSetup& setup, std::unique_ptr<Scene>* scene,
                          IntegratorSettings* settings, double* load_seconds = nullptr);

}  // namespace caustica::cli
