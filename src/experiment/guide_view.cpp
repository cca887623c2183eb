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

// Click handling: a click on the picture (not the end of a drag) finds the grid cell under it
// and draws each field's view there into its canvas. #selftest clicks the picture's middle and
// reports in #guideselftest.
constexpr const char* kClickScript = R"JS(
(function () {
  const fields = JSON.parse(document.getElementById('guideclicks').textContent);
  const stage = document.getElementById('stage'), img = document.getElementById('shown');
  let down = null;
  stage.addEventListener('mousedown', function (e) { down = [e.clientX, e.clientY]; });
  function showAt(px, py) {
    fields.forEach(function (f, k) {
      const col = Math.min(f.columns - 1, Math.max(0, Math.floor(px / img.naturalWidth * f.columns)));
      const row = Math.min(f.rows - 1, Math.max(0, Math.floor(py / img.naturalHeight * f.rows)));
      const cell = f.cells[row * f.columns + col];
      const canvas = document.getElementById('guideclick' + k), ctx = canvas.getContext('2d');
      const caption = document.getElementById('guideclickcap' + k);
      const where = 'pixel (' + Math.floor(px) + ', ' + Math.floor(py) + '), grid cell (' + col + ', ' + row + ')';
      if (!cell) { ctx.clearRect(0, 0, canvas.width, canvas.height); caption.textContent = where + ': nothing learned'; return; }
      const bytes = atob(cell), pixels = ctx.createImageData(f.width, f.height);
      for (let i = 0; i < bytes.length; i++) {
        const g = bytes.charCodeAt(i);
        pixels.data[4 * i] = pixels.data[4 * i + 1] = pixels.data[4 * i + 2] = g;
        pixels.data[4 * i + 3] = 255;
      }
      ctx.putImageData(pixels, 0, 0);
      caption.textContent = where;
    });
  }
  stage.addEventListener('click', function (e) {
    if (down && Math.hypot(e.clientX - down[0], e.clientY - down[1]) > 3) return;  // a drag
    const r = img.getBoundingClientRect();
    if (!img.naturalWidth || e.clientX < r.left || e.clientY < r.top || e.clientX >= r.right || e.clientY >= r.bottom) return;
    showAt((e.clientX - r.left) / r.width * img.naturalWidth, (e.clientY - r.top) / r.height * img.naturalHeight);
  });
  if (location.hash === '#selftest') {
    const report = document.getElementById('guideselftest');
    const run = function () {
      try {
        // The centre of the middle pixel, in the page's coordinates.
        const cx = Math.floor(img.naturalWidth / 2), cy = Math.floor(img.naturalHeight / 2);
        const r = img.getBoundingClientRect();
        const x = r.left + (cx + 0.5) / img.naturalWidth * r.width, y = r.top + (cy + 0.5) / img.naturalHeight * r.height;
        stage.dispatchEvent(new MouseEvent('mousedown', { clientX: x, clientY: y, bubbles: true }));
        window.dispatchEvent(new MouseEvent('mouseup', { clientX: x, clientY: y, bubbles: true }));
        stage.dispatchEvent(new MouseEvent('click', { clientX: x, clientY: y, bubbles: true }));
        const caption = document.getElementById('guideclickcap0').textContent;
        if (caption.indexOf('pixel (' + cx + ', ' + cy + ')') !== 0) throw new Error('caption: ' + caption);
        const data = document.getElementById('guideclick0').getContext('2d').getImageData(0, 0, fields[0].width, fields[0].height).data;
        let lit = 0;
        for (let i = 0; i < data.length; i += 4) if (data[i] > 0) ++lit;
        if (caption.indexOf('nothing learned') < 0 && lit === 0) throw new Error('the view was not drawn');
        report.textContent = 'guideselftest:pass';
      } catch (err) {
        report.textContent = 'guideselftest:fail: ' + err.message;
      }
    };
    if (img.complete && img.naturalWidth) run(); else img.addEventListener('load', run, { once: true });
  }
})();
)JS";

// The click section: a canvas per field of every guided run with a grid, and their data.
std::string click_html(const ComparisonResult& result) {
  nlohmann::json fields = nlohmann::json::array();
  std::ostringstream canvases;
  for (const auto& run : result.runs) {
    if (!run.integrator_stats.contains("guiding")) continue;
    const nlohmann::json& guiding = run.integrator_stats["guiding"];
    if (!guiding.contains("views")) continue;
    const nlohmann::json& views = guiding["views"];
    for (const char* name : {"", "radiance", "importance"}) {
      // guided-pt's views are the field's; guided-bpt/vcm hold one per field.
      if (*name && !views.contains(name)) continue;
      const nlohmann::json& v = *name ? views[name] : views;
      if (!v.is_object() || !v.contains("grid")) continue;
      const int k = int(fields.size());
      fields.push_back({{"width", v["width"]},
                        {"height", v["height"]},
                        {"columns", v["grid"]["columns"]},
                        {"rows", v["grid"]["rows"]},
                        {"cells", v["grid"]["cells"]}});
      canvases << "<figure style=\"margin:0\"><canvas id=\"guideclick" << k << "\" width=\""
               << v["width"].get<int>() << "\" height=\"" << v["height"].get<int>()
               << "\" style=\"width:" << 8 * v["width"].get<int>()
               << "px;image-rendering:pixelated;background:#000\"></canvas><figcaption>"
               << run.integrator << (*name ? std::string(", ") + name : std::string())
               << ": <span id=\"guideclickcap" << k
               << "\">click the picture above</span></figcaption></figure>\n";
    }
  }
  if (fields.empty()) return "";
  std::string data = fields.dump();
  // Inside <script>, "</" would end the element: base64 and numbers never hold it, but be sure.
  for (size_t at = data.find("</"); at != std::string::npos; at = data.find("</", at + 2))
    data.replace(at, 2, "<\\/");
  std::ostringstream o;
  o << "<h2>What was learned at a clicked pixel</h2>\n<p class=\"hint\">Click the picture "
       "above (a drag pans): the learned directional density at the first surface seen near "
       "that pixel (a grid of "
    << fields[0]["columns"].get<int>() << " x " << fields[0]["rows"].get<int>()
    << " cells across the image), drawn as the 3 x 3 views below.</p>\n"
    << canvases.str() << "<div id=\"guideselftest\" class=\"hint\"></div>\n"
    << "<script type=\"application/json\" id=\"guideclicks\">" << data << "</script>\n<script>"
    << kClickScript << "</script>\n";
  return o.str();
}

}  // namespace

std::string guide_views_html(const ComparisonResult& result) {
  std::ostringstream o;
  o << click_html(result);
  for (const auto& run : result.runs) {
    if (!run.integrator_stats.contains("guiding")) continue;
    const auto& g = run.integrator_stats["guiding"];
    if (!g.contains("views")) continue;
    const auto& views = g["views"];
    o << "<h2>What " << run.integrator << " learned</h2>\n<p class=\"hint\">At 3 x 3 pixels, the "
      << "learned directional density at the first surface the pixel sees, on the side it is "
      << "seen from (world frame: phi across, cos theta up, +z at the top row; white: densest, "
      << "square root scale).</p>\n";
    if (views.contains("radiance") || views.contains("importance")) {
      // guided-bpt/vcm: the fields of the subpaths it guided (--guiding-subpaths).
      if (views.contains("radiance"))
        o << "<p class=\"hint\">Incident radiance (guides camera subpaths):</p>\n"
          << grid_html(views["radiance"]);
      if (views.contains("importance"))
        o << "<p class=\"hint\">Incident importance (guides light subpaths):</p>\n"
          << grid_html(views["importance"]);
    } else {
      o << "<p class=\"hint\">Incident radiance:</p>\n" << grid_html(views);
    }
  }
  return o.str();
}

}  // namespace caustica
