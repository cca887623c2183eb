// A grid of grey cells as an inline SVG, for the report's small images (the merge mask of
// adaptive-vcm, the learned directional densities of the guided integrators).
#pragma once

#include <algorithm>
#include <cstdio>
#include <sstream>
#include <string>
#include <vector>

namespace caustica {

// grey[y * w + x] in [0, 1] (clamped; 1 is white), each cell `cell` pixels wide.
inline std::string grey_grid_svg(const std::vector<double>& grey, int w, int h, double cell,
                                 const char* css_class) {
  auto num = [](double v) {
    char buf[32];
    std::snprintf(buf, sizeof buf, "%.1f", v);
    return std::string(buf);
  };
  std::ostringstream o;
  o << "<svg class=\"" << css_class << "\" xmlns=\"http://www.w3.org/2000/svg\" width=\""
    << int(cell * w) << "\" height=\"" << int(cell * h) << "\" shape-rendering=\"crispEdges\">";
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      const double v = std::clamp(grey[size_t(y) * size_t(w) + size_t(x)], 0.0, 1.0);
      const int g = int(255.0 * v + 0.5);
      o << "<rect x=\"" << num(x * cell) << "\" y=\"" << num(y * cell) << "\" width=\"" << num(cell)
        << "\" height=\"" << num(cell) << "\" fill=\"rgb(" << g << "," << g << "," << g << ")\"/>";
    }
  o << "</svg>";
  return o.str();
}

}  // namespace caustica
