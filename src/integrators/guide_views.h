// What a guided integrator learned, for the report (deliverable of the path-guiding issue: "an
// image of the directional distribution at a pixel"): at a 3 x 3 grid of pixels, the first
// surface the pixel's central camera ray hits, and there the learned directional distribution
// of the side the camera sees (GuidingField::side_class), as a kViewWidth x kViewHeight grid of
// its solid-angle density over the world's (phi, cos theta) square (guiding/
// directional_quadtree.h: x = phi / 2 pi, y = (cos theta + 1) / 2, z up), and the spatial leaf's
// box. The compare report draws them (experiment/guide_view.h). For the report's click (the
// view at a clicked pixel) also a grid of kClickColumns columns (and rows for square cells) of
// such views, each as its grey levels (255 sqrt(density / its largest), base64; "" where the
// ray misses or nothing was learned), row-major: {"grid": {"columns", "rows", "cells"}}.
#pragma once

#include <functional>
#include <nlohmann/json.hpp>

#include "core/vec.h"
#include "guiding/directional_quadtree.h"

namespace caustica {

class Scene;

inline constexpr int kViewWidth = 32, kViewHeight = 16, kClickColumns = 16;

// lookup(p, side): the distribution learned at p for side class `side` (nullptr: none).
using GuideLookup = std::function<const DirectionalQuadtree*(Vec3 p, int side)>;

// Returns {"width", "height", "views": [{"pixel": [x, y], "point": [..], "density": [...]}],
// "grid": ...}, a view without "density" where nothing was learned or the ray missed.
nlohmann::json guide_views(const Scene& scene, const GuideLookup& lookup);

}  // namespace caustica
