#include "experiment/html_page.h"

#include <cstdio>
#include <sstream>

#include "experiment/adaptive_view.h"
#include "experiment/guide_view.h"

namespace caustica {

namespace {

std::string escape(const std::string& s) {
  std::string o;
  for (char c : s) {
    switch (c) {
      case '<':
        o += "&lt;";
        break;
      case '>':
        o += "&gt;";
        break;
      case '&':
        o += "&amp;";
        break;
      case '"':
        o += "&quot;";
        break;
      default:
        o += c;
    }
  }
  return o;
}

std::string fmt_g(double v, const char* f = "%.4g") {
  char b[64];
  std::snprintf(b, sizeof b, f, v);
  return b;
}

// "seed: relMSE" of every run of a summary row, the shown (median) run in bold.
std::string runs_cell(const nlohmann::json& row) {
  if (!row.contains("relmse_runs")) return "-";
  std::string cell;
  const auto& seeds = row["seeds"];
  const auto& rel = row["relmse_runs"];
  for (size_t i = 0; i < rel.size(); ++i) {
    const bool shown = seeds[i] == row["seed"];
    cell += (i ? ", " : "") + std::string(shown ? "<b>" : "") +
            std::to_string(seeds[i].get<uint64_t>()) + ": " + fmt_g(rel[i].get<double>()) +
            (shown ? "</b>" : "");
  }
  return cell;
}

constexpr const char* kStyle = R"CSS(
body { font-family: sans-serif; margin: 1.5em; color: #222; max-width: 1200px; }
#buttons button { margin: 0 .3em .3em 0; padding: .3em .8em; border: 1px solid #888; background: #f4f4f4; cursor: pointer; }
#buttons button.active { background: #335; color: white; }
#stage { width: 100%; height: 560px; overflow: hidden; background: #111; position: relative; cursor: grab; }
#stage img { position: absolute; left: 0; top: 0; transform-origin: 0 0; image-rendering: pixelated; }
#caption { margin: .4em 0 1em; color: #555; }
table { border-collapse: collapse; } td, th { border: 1px solid #ccc; padding: .25em .6em; text-align: right; }
th:first-child, td:first-child { text-align: left; }
.hint { color: #777; font-size: 90%; }
)CSS";

constexpr const char* kScript = R"JS(
(function () {
  const views = JSON.parse(document.getElementById('views').textContent);
  const img = document.getElementById('shown');
  const stage = document.getElementById('stage');
  const caption = document.getElementById('caption');
  const errToggle = document.getElementById('errtoggle');
  let current = views.length > 1 ? 1 : 0, scale = 1, tx = 0, ty = 0, fitted = false;
  function apply() { img.style.transform = 'translate(' + tx + 'px,' + ty + 'px) scale(' + scale + ')'; }
  function fit() {
    if (!img.naturalWidth) return;
    scale = Math.min(stage.clientWidth / img.naturalWidth, stage.clientHeight / img.naturalHeight);
    tx = (stage.clientWidth - img.naturalWidth * scale) / 2; ty = (stage.clientHeight - img.naturalHeight * scale) / 2;
    apply();
  }
  function show(i) {
    current = i;
    const v = views[i];
    const useErr = errToggle.checked && v.error;
    img.src = useErr ? v.error : v.image;
    caption.textContent = v.name + (useErr ? ' (relative error, log scale)' : '') + (v.caption ? ' - ' + v.caption : '');
    document.querySelectorAll('#buttons button').forEach(function (b, k) { b.classList.toggle('active', k === i); });
  }
  img.addEventListener('load', function () { if (!fitted) { fitted = true; fit(); } });
  views.forEach(function (v, i) {
    const b = document.createElement('button');
    b.textContent = (i < 10 ? i + ' ' : '') + v.name;
    b.addEventListener('click', function () { show(i); });
    document.getElementById('buttons').appendChild(b);
  });
  errToggle.addEventListener('change', function () { show(current); });
  document.addEventListener('keydown', function (e) {
    if (e.key >= '0' && e.key <= '9' && +e.key < views.length) show(+e.key);
    else if (e.key === 'e') { errToggle.checked = !errToggle.checked; show(current); }
    else if (e.key === 'r') show(0);
    else if (e.key === 'f') fit();
    else if (e.key === 'ArrowRight') show((current + 1) % views.length);
    else if (e.key === 'ArrowLeft') show((current + views.length - 1) % views.length);
  });
  stage.addEventListener('wheel', function (e) {
    e.preventDefault();
    const r = stage.getBoundingClientRect(), mx = e.clientX - r.left, my = e.clientY - r.top;
    const k = Math.exp(-e.deltaY * 0.0015);
    tx = mx - (mx - tx) * k; ty = my - (my - ty) * k; scale *= k; apply();
  }, { passive: false });
  let drag = null;
  stage.addEventListener('mousedown', function (e) { drag = [e.clientX - tx, e.clientY - ty]; });
  window.addEventListener('mouseup', function () { drag = null; });
  window.addEventListener('mousemove', function (e) { if (drag) { tx = e.clientX - drag[0]; ty = e.clientY - drag[1]; apply(); } });
  show(current);

  if (location.hash === '#selftest') {
    const wait = function (ms) { return new Promise(function (r) { setTimeout(r, ms); }); };
    const loaded = function () {
      return new Promise(function (resolve, reject) {
        if (img.complete && img.naturalWidth > 0) return resolve();
        img.onload = function () { resolve(); };
        img.onerror = function () { reject(new Error('image failed to load: ' + img.src)); };
      });
    };
    (async function () {
      try {
        const curves = document.querySelectorAll('#convergence polyline.curve').length;
        if (curves !== views.length - 1) throw new Error('plot has ' + curves + ' curves for ' + (views.length - 1) + ' integrators');
        if (document.querySelectorAll('#summary tbody tr').length !== views.length - 1) throw new Error('summary rows missing');
        const seen = [];
        for (let i = 0; i < views.length; i++) {
          document.querySelectorAll('#buttons button')[i].click();
          await loaded();
          if (!img.src.endsWith(views[i].image)) throw new Error('button ' + i + ' did not switch the image');
          seen.push(img.src);
        }
        if (new Set(seen).size !== views.length) throw new Error('switching integrators did not change the image');
        document.dispatchEvent(new KeyboardEvent('keydown', { key: 'e' }));
        await loaded();
        if (views[current].error && !img.src.endsWith(views[current].error)) throw new Error('error view did not show');
        document.dispatchEvent(new KeyboardEvent('keydown', { key: '0' }));
        await wait(10);
        document.title = 'selftest:pass';
      } catch (err) {
        document.title = 'selftest:fail: ' + err.message;
      }
      document.getElementById('selftest').textContent = document.title;
    })();
  }
})();
)JS";

}  // namespace

std::string comparison_html(const ComparisonResult& result, const nlohmann::json& summary,
                            const std::string& svg) {
  nlohmann::json views = nlohmann::json::array();
  views.push_back({{"name", "reference"},
                   {"image", "reference.png"},
                   {"caption", result.reference_description}});
  for (const auto& r : result.runs) {
    const auto& e = r.snapshots.back().errors;
    views.push_back(
        {{"name", r.integrator},
         {"image", r.integrator + ".png"},
         {"error", r.integrator + "_error.png"},
         {"caption",
          std::to_string(r.iterations) + " iterations in " + fmt_g(r.seconds, "%.1f") +
              " s, relMSE " + fmt_g(e.rel_mse) +
              (r.repeats.size() > 1 ? ", seed " + std::to_string(r.seed) + ": the median of " +
                                          std::to_string(r.repeats.size()) + " runs"
                                    : std::string())}});
  }
  bool repeated = false;
  for (const auto& r : result.runs) repeated = repeated || r.repeats.size() > 1;
  std::ostringstream o;
  o << "<!doctype html>\n<html lang=\"en\"><head><meta charset=\"utf-8\"><title>caustica: "
    << escape(result.scene) << "</title>\n<style>" << kStyle << "</style></head>\n<body>\n<h1>"
    << escape(result.scene) << ": " << fmt_g(result.config.seconds, "%g")
    << " s per integrator</h1>\n"
    << (repeated ? "<p>Each integrator ran " + std::string(result.interrupted ? "up to " : "") +
                       std::to_string(result.config.runs) + " times, with seeds " +
                       std::to_string(result.config.settings.seed) + " to " +
                       std::to_string(result.config.settings.seed + result.config.runs - 1) +
                       ", taking turns; the images, the curves and the summary's errors are "
                       "each one's median run by relMSE, and the last column lists every "
                       "run's.</p>\n"
                 : std::string())
    << "<p class=\"hint\">Keys: 0 reference, 1-9 integrators, arrows cycle, e error view, f fit. "
       "Wheel zooms, drag "
       "pans; the view stays put when switching.</p>\n"
    << "<div id=\"buttons\"></div><label><input type=\"checkbox\" id=\"errtoggle\"> error view "
       "(e)</label>\n"
    << "<div id=\"stage\"><img id=\"shown\" alt=\"render\"></div><div id=\"caption\"></div>\n"
    << "<h2>Convergence</h2>\n"
    << svg
    << "<h2>Summary</h2>\n<table "
       "id=\"summary\"><thead><tr><th>integrator</th><th>iterations</th><th>Mrays/s</th>"
       "<th>RMSE</th><th>relMSE</th><th>relMSE (trimmed 0.1%)</th><th>SSIM</th><th>speed-up vs "
       "pt</th>"
    << (repeated ? "<th>relMSE of each run (seed: relMSE)</th>" : "") << "</tr></thead><tbody>\n";
  for (const auto& row : summary) {
    const auto& e = row["errors"];
    o << "<tr><td>" << escape(row["integrator"].get<std::string>()) << "</td><td>"
      << row["iterations"].get<uint32_t>() << "</td><td>"
      << fmt_g(row["rays_per_second"].get<double>() * 1e-6, "%.2f") << "</td><td>"
      << fmt_g(e["rmse"].get<double>()) << "</td><td>" << fmt_g(e["relmse"].get<double>())
      << "</td><td>" << fmt_g(e["relmse_trimmed"].get<double>()) << "</td><td>"
      << fmt_g(e["ssim"].get<double>(), "%.4f") << "</td><td>"
      << (row.contains("speedup_vs_pt") && row["speedup_vs_pt"].is_number()
              ? fmt_g(row["speedup_vs_pt"].get<double>(), "%.2fx")
              : std::string("-"))
      << "</td>";
    if (repeated) o << "<td>" << runs_cell(row) << "</td>";
    o << "</tr>\n";
  }
  o << "</tbody></table>\n<p class=\"hint\">Speed-up: the time pt needs to reach this integrator's "
       "final relMSE "
       "(read off pt's curve; beyond it relMSE ~ 1/t), divided by this integrator's time.</p>\n"
    << "<p class=\"hint\">Reference: " << escape(result.reference_description) << "</p>\n"
    << adaptive_choices_html(result) << guide_views_html(result)
    << "<pre id=\"selftest\"></pre>\n<script type=\"application/json\" id=\"views\">"
    << views.dump() << "</script>\n<script>" << kScript << "</script>\n</body></html>\n";
  return o.str();
}

}  // namespace caustica
