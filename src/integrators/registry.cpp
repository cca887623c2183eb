#include "integrators/registry.h"

#include "integrators/bidir/bidir_integrator.h"
#include "integrators/path_tracer.h"

namespace caustica {

std::vector<std::string> integrator_names() { return {"pt", "lt", "bpt", "ppm", "bpm", "vcm"}; }

std::unique_ptr<Integrator> make_integrator(const std::string& name,
                                            const IntegratorSettings& settings) {
  if (name == "pt") return std::make_unique<PathTracer>(settings);
  if (auto bidir = make_bidir_integrator(name, settings)) return bidir;
  return nullptr;
}

}  // namespace caustica
