// What every rendering subcommand does before it renders: register and check the options they
// share, load the scene, apply the resolution override and derive the integrator settings.
// Errors are printed here (one line each); the caller returns the exit code.
#pragma once

#include <cstdint>
#include <memory>
#include <string>

#include "integrators/integrator.h"
#include "options.h"
#include "scene/scene.h"

namespace caustica::cli {

struct SceneSetup {
  std::string scene;          // built-in name or file
  int camera = -1;            // glTF camera index (-1: the first)
  int width = 0, height = 0;  // --resolution; 0: the scene's
  int max_depth = -1;         // -1: the scene's, else 10
  uint64_t seed = 0;
  std::string mis;  // "", "balance" or "power"; empty: each integrator's default
  // Integrator options (every rendering subcommand takes them; integrators that do not use one
  // ignore it).
  BidirSettings bidir;  // --light-paths, --radius, --radius-alpha, --techniques, --connections
  std::string adaptive_costs;  // --adaptive-costs: "", "model" or "measured"
  std::string merge_mis;       // --merge-mis: "", "balance" or "correlation-aware"
  // --guiding-spatial-threshold, --guiding-rho, --guiding-bsdf-fraction, --guiding-nee-floor;
  // the others below.
  GuidingSettings guiding;
  int guiding_max_mb = 32;                           // --guiding-max-mb
  std::string guiding_filter = "on";                 // --guiding-filter
  std::string guiding_target = "cosine";             // --guiding-target
  std::string guiding_subpaths = "both";             // --guiding-subpaths
  std::string guiding_radiance = "camera";           // --guiding-radiance
  std::string guiding_importance = "light";          // --guiding-importance
  std::string guiding_mis = "bsdf";                  // --guiding-mis
  std::string guiding_combine = "inverse-variance";  // --guiding-combine
};

// The options render, reference and compare share, with the ranges they all obey.
struct SharedOptions : SceneSetup {
  double seconds = 0;  // --time; 0: not given
  int threads = 0;     // 0: all cores
};

// Longest --time (and --reference-time) accepted: 30 days. A bound keeps a typo such as 1e30
// from becoming a render that never ends; a longer one is a checkpointing job we do not do.
constexpr double kMaxSeconds = 30 * 24 * 3600;

// Registers --time (with the command's help text; returned so it can be made required),
// --threads, --max-depth, --seed, --resolution, --mis, --camera and the integrator options
// --light-paths, --radius, --radius-alpha, --techniques, --connections, --adaptive-costs and
// --guiding-*.
CLI::Option* add_shared_options(CheckedOptions& options, SharedOptions* shared,
                                const std::string& time_help);

// Returns 0 and fills *scene / *settings, or prints the problem and returns the exit code (2).
// Before loading it checks the scene path and the --resolution override against memory, after
// loading the film the scene asks for.
int load_configured_scene(const SceneSetup& setup, std::unique_ptr<Scene>* scene,
                          IntegratorSettings* settings, double* load_seconds = nullptr);

}  // namespace caustica::cli
