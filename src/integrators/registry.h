// Integrators by name, for the command line and the tests.
#pragma once

#include <memory>
#include <string>
#include <vector>

#include "integrators/integrator.h"

namespace caustica {

// Names accepted by make_integrator, in the order the README documents them.
std::vector<std::string> integrator_names();
// Returns nullptr for an unknown name.
std::unique_ptr<Integrator> make_integrator(const std::string& name,
                                            const IntegratorSettings& settings);

}  // namespace caustica
