#include "experiment/guide_view.h"

#include <algorithm>
#include <cmath>
#include <sstream>

#include "experiment/svg_grid.h"

namespace caustica {

namespace {

// One view's density as grey cells (sqrt of the density over the view's largest), 4 px each.
std::string density_svg(const nlohmann::json& view, int w, int h) {
  if (!view.contains("density")) return "<div class=\"guideempty\">nothing learned</div>";
  const auto& d = view["density"];
  if (d.size() != size_t(w) * size_t(h)) return "";
  double peak = 0;
  for (const auto& x : d) peak = std::max(peak, x.get<double>());
  if (!(peak > 0)) return "";
  std::vector<double> grey(d.size());
  for (size_t i = 0; i < grey.size(); ++i)
    grey[i] = std::sqrt(std::max(0.0, d[i].get<double>()) / peak);
  return grey_grid_svg(grey, w, h, 4.0, "guideview");
}

std::string grid_html(const nlohmann::json& views) {
  if (!views.contains("views") || !views.contains("width") || !views.contains("height")) return "";
  const int w = views["width"].get<int>(), h = views["height"].get<int>();
  std::ostringstream o;
  o << "<div class=\"guidegrid\" style=\"display:grid;grid-template-columns:repeat(3,auto);"
       "gap:6px;justify-content:start\">";
  for (const auto& v : views["views"]) {
    o << "<figure style=\"margin:0\">" << density_svg(v, w, h) << "<figcaption>pixel ("
      << v["pixel"][0].get<int>() << ", " << v["pixel"][1].get<int>() << ")</figcaption></figure>";
  }
  o << "</div>\n";
  return o.str();
}

}  // namespace

std::string guide_views_html(const ComparisonResult& result) {
  std::ostringstream o;
  for (const auto& run : result.runs) {
    if (!run.integrator_stats.contains("guiding")) continue;
    const auto& g = run.integrator_stats["guiding"];
    if (!g.contains("views")) continue;
    const auto& views = g["views"];
    o << "<h2>What " << run.integrator << " learned</h2>\n<p class=\"hint\">At 3 x 3 pixels, the "
      << "learned directional density at the first surface the pixel sees, on the side it is "
      << "seen from (world frame: phi across, cos theta up, +z at the top row; white: densest, "
      << "square root scale).</p>\n";
    if (views.contains("radiance")) {
      o << "<p class=\"hint\">Incident radiance (guides camera subpaths):</p>\n"
        << grid_html(views["radiance"]);
      o << "<p class=\"hint\">Incident importance (guides light subpaths):</p>\n"
        << grid_html(views["importance"]);
    } else {
      o << "<p class=\"hint\">Incident radiance:</p>\n" << grid_html(views);
    }
  }
  return o.str();
}

}  // namespace caustica
