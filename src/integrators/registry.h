// The one list of integrators: name, one-line description, factory and capability flags. The
// command line's help, the README's integrator table (checked by a test) and the oracle tests
// (furnace, agreement with pt, thread determinism) all come from it, so an integrator added here
// is documented and tested without anyone naming it by hand.
#pragma once

#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "integrators/integrator.h"

namespace caustica {

struct IntegratorInfo {
  std::string name;
  std::string description;  // one line
  // Unbiased: the expectation of every iteration is the image. Consistent: biased for a finite
  // merge radius, converging as the radius shrinks (photon mapping, VCM).
  bool unbiased = true;
  // Path classes it can sample. every_path_without_delta: every path with no delta vertex (then
  // it must agree with pt wherever no path is delta-only). caustics_through_specular: paths in
  // which a diffuse vertex has specular vertices on both sides (caustics seen through glass or
  // in a mirror), which only merging samples well.
  bool every_path_without_delta = true;
  bool caustics_through_specular = false;
  MisHeuristic default_mis = MisHeuristic::Balance;  // when the user names none (--mis)
  std::function<std::unique_ptr<Integrator>(const IntegratorSettings&)> make;
};

// What `caustica render` and Python's render() use when neither the user nor the scene file
// names an integrator, and compare's first column: the one that picks its techniques per scene.
inline constexpr const char* kDefaultIntegrator = "adaptive-vcm";

// In the order the README documents them.
const std::vector<IntegratorInfo>& integrator_registry();
// nullptr for an unknown name.
const IntegratorInfo* find_integrator(const std::string& name);
std::vector<std::string> integrator_names();
// Returns nullptr for an unknown name. settings.mis, when empty, becomes the integrator's default.
std::unique_ptr<Integrator> make_integrator(const std::string& name,
                                            const IntegratorSettings& settings);

}  // namespace caustica
