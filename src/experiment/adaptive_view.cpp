#include "experiment/adaptive_view.h"

#include <cstdio>
#include <limits>
#include <sstream>

#include "experiment/svg_grid.h"

namespace caustica {

namespace {

std::string num(double v, const char* f) {
  char buf[64];
  std::snprintf(buf, sizeof buf, f, v);
  return buf;
}

// A number from the statistics; +infinity where JSON holds null (an infinite score).
double number(const nlohmann::json& v) {
  return v.is_number() ? v.get<double>() : std::numeric_limits<double>::infinity();
}

// A block-averaged mask as grey squares, scaled to at most 384 px wide.
std::string mask_svg(const nlohmann::json& mask, const char* css_class) {
  const int w = mask["width"].get<int>(), h = mask["height"].get<int>();
  const auto& fraction = mask["fraction"];
  if (w <= 0 || h <= 0 || fraction.size() != size_t(w) * size_t(h)) return "";
  std::vector<double> grey(fraction.size());
  for (size_t i = 0; i < grey.size(); ++i) grey[i] = fraction[i].get<double>();
  return grey_grid_svg(grey, w, h, std::max(1.0, 384.0 / w), css_class);
}

// A history entry's variant (adaptive_choice.cpp): each pixel's own mode, or one for all.
std::string variant_label(const std::string& variant) {
  if (variant == "mixed") return "per-pixel mix";
  if (variant == "bidirectional") return "all: core, no merging";
  if (variant == "merge") return "all: core and merging";
  if (variant == "photon_mapping") return "all: photon mapping";
  return variant;
}

}  // namespace

std::string adaptive_choices_html(const ComparisonResult& result) {
  std::ostringstream o;
  for (const auto& run : result.runs) {
    if (!run.integrator_stats.contains("adaptive")) continue;
    const auto& a = run.integrator_stats["adaptive"];
    o << "<h2>What " << run.integrator << " chose</h2>\n<table class=\"adaptive\"><thead><tr>"
      << "<th>after probe</th><th>light paths / pixel</th><th>connections</th>"
      << "<th>pixels</th>"
      << "<th>merging pixels</th><th>path-traced pixels</th><th>photon-mapped pixels</th>"
      << "<th>predicted relVar</th>"
      << "<th>cost (us / pixel)</th>"
      << "</tr></thead><tbody>\n";
    for (const auto& h : a["history"]) {
      // The chosen row of the candidate table: the one of the chosen light paths and connections
      // (not simply the lowest score: the plan first compares the pixels where a candidate would
      // miss energy, and keeps path tracing within a margin).
      const nlohmann::json* best = nullptr;
      for (const auto& c : h["candidates"])
        if (c["light_path_factor"] == h["light_path_factor"] &&
            c["connections"] == h["connections"])
          best = &c;
      o << "<tr><td>" << h["after_probe"].get<int>() << "</td><td>"
        << num(h["light_path_factor"].get<double>(), "%g") << "</td><td>"
        << h["connections"].get<int>() << "</td><td>"
        << (h.contains("variant") ? variant_label(h["variant"].get<std::string>())
                                  : std::string("-"))
        << "</td><td>" << num(100 * number(h["merge_fraction"]), "%.1f%%") << "</td><td>"
        << (h.contains("path_trace_fraction")
                ? num(100 * number(h["path_trace_fraction"]), "%.1f%%")
                : std::string("-"))
        << "</td><td>"
        << (h.contains("stop_fraction") ? num(100 * number(h["stop_fraction"]), "%.1f%%")
                                        : std::string("-"))
        << "</td><td>" << (best ? num(number((*best)["relative_variance"]), "%.4g") : "-")
        << "</td><td>" << (best ? num(number((*best)["cost_us_per_pixel"]), "%.3g") : "-")
        << "</td></tr>\n";
    }
    o << "</tbody></table>\n";
    if (a.contains("merge_mask"))
      o << "<p class=\"hint\">Merge mask (white: the pixel merges; blocks of "
        << a["merge_mask"]["block"].get<int>() << " px):</p>\n"
        << mask_svg(a["merge_mask"], "mergemask") << "\n";
    if (a.contains("path_trace_mask"))
      o << "<p class=\"hint\">Path-trace mask (white: the pixel is rendered by path tracing "
           "alone, without light-tracing splats; blocks of "
        << a["path_trace_mask"]["block"].get<int>() << " px):</p>\n"
        << mask_svg(a["path_trace_mask"], "ptmask") << "\n";
    if (a.contains("stop_mask"))
      o << "<p class=\"hint\">Photon-mapping mask (white: the camera path stops at its first "
           "non-specular vertex and merges there, ppm's estimator; blocks of "
        << a["stop_mask"]["block"].get<int>() << " px):</p>\n"
        << mask_svg(a["stop_mask"], "stopmask") << "\n";
  }
  return o.str();
}

}  // namespace caustica
