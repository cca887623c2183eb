// The integrator interface. The render loop drives iterations; an iteration estimates every
// pixel once (camera-path integrators: one sample per pixel; bidirectional ones: one batch of
// light paths plus one camera path per pixel). Iteration results are added to the Film.
#pragma once

#include <cstdint>
#include <memory>
#include <string>

#include <nlohmann/json_fwd.hpp>

namespace caustica {

class Scene;
class Film;

enum class MisHeuristic { Balance, Power };

// Settings shared by all integrators; integrator-specific knobs live in their own structs.
struct IntegratorSettings {
  int max_depth = 10;        // scattering vertices, as pbrt-v4's maxdepth (1 = direct light only)
  uint64_t seed = 0;
  MisHeuristic mis = MisHeuristic::Power;
  // True when `mis` was chosen by the user (--mis). The bidirectional family then uses `mis`;
  // otherwise it uses its own default, the balance heuristic (pt always uses `mis`).
  bool mis_from_user = false;
  // Bidirectional family (ignored by the others).
  uint64_t light_paths = 0;  // light subpaths per iteration; 0 = one per pixel
  float radius = 0;          // initial merge radius; 0 = derived from the scene size
  float radius_alpha = 0.75f;
  std::string techniques_dir;  // if set, write one image per technique
};

class Integrator {
 public:
  virtual ~Integrator() = default;
  virtual const char* name() const = 0;
  // Called once before the first iteration.
  virtual void prepare(const Scene& scene, Film& film) { (void)scene; (void)film; }
  // Renders iteration `iteration` (0-based) into film; film.end_iteration() is the caller's.
  virtual void render_iteration(const Scene& scene, uint32_t iteration, Film& film) = 0;
  // Called once after the last iteration (e.g. to write per-technique images).
  virtual void finish(const Scene& scene, Film& film) { (void)scene; (void)film; }
  // Integrator-specific statistics for the JSON output.
  virtual void report(nlohmann::json& stats) const { (void)stats; }
};

}  // namespace caustica
