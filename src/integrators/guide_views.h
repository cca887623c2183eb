// What a guided integrator learned, for the report (deliverable of the path-guiding issue: "an
// image of the directional distribution at a pixel"): at a 3 x 3 grid of pixels, the first
// surface the pixel's central camera ray hits, and there the learned directional distribution
// of the side the camera sees (GuidingField::side_class), as a kViewWidth x kViewHeight grid of
// its solid-angle density over the world's (phi, cos theta) square (guiding/
// directional_quadtree.h: x = phi / 2 pi, y = (cos theta + 1) / 2, z up), and the spatial leaf's
// box. The compare report draws them (experiment/guide_view.h).
#pragma once

#include <functional>
#include <nlohmann/json.hpp>

#include "core/vec.h"
#include "guiding/directional_quadtree.h"

namespace caustica {

class Scene;

inline constexpr int kViewWidth = 32, kViewHeight = 16;

// lookup(p, side): the distribution learned at p for side class `side` (nullptr: none).
// Returns {"width", "height", "views": [{"pixel": [x, y], "point": [..], "density": [...]}]},
// a view without "density" where nothing was learned or the ray missed.
nlohmann::json guide_views(
    const Scene& scene, const std::function<const DirectionalQuadtree*(Vec3 p, int side)>& lookup);

}  // namespace caustica
