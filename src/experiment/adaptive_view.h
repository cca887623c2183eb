// The comparison report's view of what adaptive-vcm chose (integrators/bidir/adaptive_plan.h):
// per adaptive run, the configuration after each probe (light paths per pixel, connections per
// camera vertex, shares of merging and of path-traced pixels, the chosen candidate's predicted
// relative variance and cost) and the final per-pixel merge and path-trace masks as inline SVGs
// (white: the pixel merges / path traces alone). Empty when no run has it.
#pragma once

#include <string>

#include "experiment/comparison.h"

namespace caustica {

std::string adaptive_choices_html(const ComparisonResult& result);

}  // namespace caustica
