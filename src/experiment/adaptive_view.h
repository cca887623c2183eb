// The comparison report's view of what adaptive-vcm chose (integrators/bidir/adaptive_plan.h):
// per adaptive run, the configuration after each probe (light paths per pixel, connections per
// camera vertex, share of merging pixels, predicted relative variance and cost) and the final
// per-pixel merge mask as an inline SVG (white: the pixel merges). Empty when no run has it.
#pragma once

#include <string>

#include "experiment/comparison.h"

namespace caustica {

std::string adaptive_choices_html(const ComparisonResult& result);

}  // namespace caustica
