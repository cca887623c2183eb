#include "integrators/registry.h"

#include "integrators/path_tracer.h"

namespace caustica {

std::vector<std::string> integrator_names() { return {"pt"}; }

std::unique_ptr<Integrator> make_integrator(const std::string& name, const IntegratorSettings& settings) {
  if (name == "pt") return std::make_unique<PathTracer>(settings);
  return nullptr;
}

}  // namespace caustica
