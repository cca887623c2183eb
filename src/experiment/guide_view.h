// The comparison report's view of what the guided integrators learned (integrators/
// guide_views.h): per guided run, at 3 x 3 pixels, the learned directional density at the first
// surface the pixel sees, as small heat maps (phi across, cos theta up; white: densest), for
// guided-pt the incident radiance, for guided-bpt / guided-vcm also the incident importance;
// and the same view at a pixel clicked in the report's picture (from the views' grid). Empty when
// no run has views.
#pragma once

#include <string>

#include "experiment/comparison.h"

namespace caustica {

std::string guide_views_html(const ComparisonResult& result);

}  // namespace caustica
