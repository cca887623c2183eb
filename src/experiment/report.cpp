#include "experiment/report.h"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "experiment/html_page.h"
#include "image/false_color.h"
#include "image/image_io.h"
#include "image/tonemap.h"

namespace caustica {

namespace {

// With several runs per integrator: how many, their seeds and every run's relMSE (the row's
// errors are the median run's).
void add_repeats_summary(const IntegratorRun& r, nlohmann::json* row) {
  const size_t n = std::max<size_t>(r.repeats.size(), 1);
  (*row)["runs"] = n;
  if (r.repeats.size() < 2) return;
  nlohmann::json seeds = nlohmann::json::array(), rel = nlohmann::json::array(),
                 trimmed = nlohmann::json::array();
  double lo = HUGE_VAL, hi = -HUGE_VAL;
  for (const RepeatRun& x : r.repeats) {
    seeds.push_back(x.seed);
    rel.push_back(x.errors.rel_mse);
    trimmed.push_back(x.errors.rel_mse_trimmed);
    lo = std::min(lo, x.errors.rel_mse);
    hi = std::max(hi, x.errors.rel_mse);
  }
  (*row)["seeds"] = seeds;
  (*row)["relmse_runs"] = rel;
  (*row)["relmse_trimmed_runs"] = trimmed;
  (*row)["relmse_median"] = median_rel_mse(r);
  (*row)["relmse_min"] = lo;
  (*row)["relmse_max"] = hi;
}

}  // namespace

nlohmann::json comparison_summary(const ComparisonResult& result) {
  const IntegratorRun* pt = nullptr;
  for (const auto& r : result.runs)
    if (r.integrator == "pt") pt = &r;
  nlohmann::json rows = nlohmann::json::array();
  for (const auto& r : result.runs) {
    const ErrorMetrics& e = r.snapshots.back().errors;
    nlohmann::json row = {{"integrator", r.integrator},
                          {"seed", r.seed},
                          {"seconds", r.seconds},
                          {"iterations", r.iterations},
                          {"rays_per_second", r.seconds > 0 ? double(r.rays) / r.seconds : 0.0},
                          {"errors", to_json(e)}};
    add_repeats_summary(r, &row);
    if (pt == &r) {
      row["speedup_vs_pt"] = 1.0;  // by definition (its own curve is not monotonic)
    } else if (pt && r.seconds > 0) {
      const double t = time_to_rel_mse(*pt, e.rel_mse);
      if (t > 0)
        row["speedup_vs_pt"] = t / r.seconds;
      else
        row["speedup_vs_pt"] = nullptr;
    }
    rows.push_back(row);
  }
  return rows;
}

nlohmann::json comparison_json(const ComparisonResult& result) {
  nlohmann::json j;
  j["scene"] = result.scene;
  j["seconds_per_integrator"] = result.config.seconds;
  j["threads"] = result.config.threads;
  j["runs_per_integrator"] = result.config.runs;
  j["reference"] = result.reference_description;
  j["interrupted"] = result.interrupted;
  j["summary"] = comparison_summary(result);
  j["runs"] = nlohmann::json::array();
  for (const auto& r : result.runs) {
    nlohmann::json run = {
        {"integrator", r.integrator}, {"seed", r.seed}, {"seconds", r.seconds},
        {"iterations", r.iterations}, {"rays", r.rays}, {"nonfinite", r.nonfinite},
        {"stats", r.integrator_stats}};
    for (const RepeatRun& x : r.repeats)
      run["repeats"].push_back({{"seed", x.seed},
                                {"seconds", x.seconds},
                                {"iterations", x.iterations},
                                {"errors", to_json(x.errors)}});
    for (const auto& s : r.snapshots)
      run["snapshots"].push_back(
          {{"seconds", s.seconds}, {"iterations", s.iterations}, {"errors", to_json(s.errors)}});
    j["runs"].push_back(run);
  }
  return j;
}

std::string convergence_svg(const ComparisonResult& result, int W, int H) {
  static const char* colors[] = {"#1f77b4", "#d62728", "#2ca02c", "#ff7f0e",
                                 "#9467bd", "#8c564b", "#e377c2", "#17becf"};
  double tmin = 1e30, tmax = -1e30, emin = 1e30, emax = -1e30;
  for (const auto& r : result.runs)
    for (const auto& s : r.snapshots)
      if (s.seconds > 0 && s.errors.rel_mse > 0) {
        tmin = std::min(tmin, s.seconds);
        tmax = std::max(tmax, s.seconds);
        emin = std::min(emin, s.errors.rel_mse);
        emax = std::max(emax, s.errors.rel_mse);
      }
  if (tmin > tmax) tmin = 0.1, tmax = 1, emin = 0.01, emax = 1;
  const double lt0 = std::floor(std::log10(tmin)),
               lt1 = std::max(lt0 + 1, std::ceil(std::log10(tmax)));
  const double le0 = std::floor(std::log10(emin)),
               le1 = std::max(le0 + 1, std::ceil(std::log10(emax)));
  const int ml = 70, mr = 130, mt = 20, mb = 50;
  auto px = [&](double t) { return ml + (std::log10(t) - lt0) / (lt1 - lt0) * (W - ml - mr); };
  auto py = [&](double e) { return mt + (le1 - std::log10(e)) / (le1 - le0) * (H - mt - mb); };
  std::ostringstream o;
  o << "<svg xmlns=\"http://www.w3.org/2000/svg\" id=\"convergence\" width=\"" << W
    << "\" height=\"" << H << "\" viewBox=\"0 0 " << W << ' ' << H
    << "\" font-family=\"sans-serif\" font-size=\"12\">\n"
    << "<rect width=\"100%\" height=\"100%\" fill=\"white\"/>\n";
  for (double d = lt0; d <= lt1 + 1e-9; d += 1) {
    const double x = px(std::pow(10, d));
    o << "<line x1=\"" << x << "\" y1=\"" << mt << "\" x2=\"" << x << "\" y2=\"" << H - mb
      << "\" stroke=\"#ddd\"/>"
      << "<text x=\"" << x << "\" y=\"" << H - mb + 16 << "\" text-anchor=\"middle\">"
      << std::pow(10, d) << "</text>\n";
  }
  for (double d = le0; d <= le1 + 1e-9; d += 1) {
    const double y = py(std::pow(10, d));
    o << "<line x1=\"" << ml << "\" y1=\"" << y << "\" x2=\"" << W - mr << "\" y2=\"" << y
      << "\" stroke=\"#ddd\"/>"
      << "<text x=\"" << ml - 6 << "\" y=\"" << y + 4 << "\" text-anchor=\"end\">1e" << int(d)
      << "</text>\n";
  }
  o << "<rect x=\"" << ml << "\" y=\"" << mt << "\" width=\"" << W - ml - mr << "\" height=\""
    << H - mt - mb << "\" fill=\"none\" stroke=\"#444\"/>\n"
    << "<text x=\"" << (ml + W - mr) / 2 << "\" y=\"" << H - 10
    << "\" text-anchor=\"middle\">time (s)</text>\n"
    << "<text transform=\"translate(16," << (mt + H - mb) / 2
    << ") rotate(-90)\" text-anchor=\"middle\">relMSE</text>\n";
  for (size_t k = 0; k < result.runs.size(); ++k) {
    const auto& r = result.runs[k];
    const char* c = colors[k % 8];
    o << "<polyline class=\"curve\" data-integrator=\"" << r.integrator
      << "\" fill=\"none\" stroke=\"" << c << "\" stroke-width=\"2\" points=\"";
    for (const auto& s : r.snapshots)
      if (s.seconds > 0 && s.errors.rel_mse > 0)
        o << px(s.seconds) << ',' << py(s.errors.rel_mse) << ' ';
    o << "\"/>\n";
    for (const auto& s : r.snapshots)
      if (s.seconds > 0 && s.errors.rel_mse > 0)
        o << "<circle cx=\"" << px(s.seconds) << "\" cy=\"" << py(s.errors.rel_mse)
          << "\" r=\"3\" fill=\"" << c << "\"/>";
    o << "\n<line x1=\"" << W - mr + 12 << "\" y1=\"" << mt + 14 + 20 * k << "\" x2=\""
      << W - mr + 36 << "\" y2=\"" << mt + 14 + 20 * k << "\" stroke=\"" << c
      << "\" stroke-width=\"3\"/><text x=\"" << W - mr + 42 << "\" y=\"" << mt + 18 + 20 * k
      << "\">" << r.integrator << "</text>\n";
  }
  o << "</svg>\n";
  return o.str();
}

void write_comparison_report(const ComparisonResult& result, const Image& reference,
                             const std::string& dir, const ReportOptions& options) {
  namespace fs = std::filesystem;
  fs::create_directories(dir);
  const fs::path d(dir);
  write_exr(reference, (d / "reference.exr").string());
  write_png_srgb(tonemap_srgb(reference, options.exposure), (d / "reference.png").string());
  for (const auto& r : result.runs) {
    write_exr(r.image, (d / (r.integrator + ".exr")).string());
    write_png_srgb(tonemap_srgb(r.image, options.exposure), (d / (r.integrator + ".png")).string());
    write_png_srgb(false_color_rel_error(r.image, reference),
                   (d / (r.integrator + "_error.png")).string());
  }
  const nlohmann::json j = comparison_json(result);
  write_file_atomic((d / "results.json").string(), j.dump(2) + "\n");

  std::ostringstream csv;
  csv << "integrator,seconds,iterations,mse,rmse,relmse,relmse_trimmed,ssim\n";
  for (const auto& r : result.runs)
    for (const auto& s : r.snapshots)
      csv << r.integrator << ',' << s.seconds << ',' << s.iterations << ',' << s.errors.mse << ','
          << s.errors.rmse << ',' << s.errors.rel_mse << ',' << s.errors.rel_mse_trimmed << ','
          << s.errors.ssim << '\n';
  write_file_atomic((d / "results.csv").string(), csv.str());

  std::ostringstream runs_csv;  // every run's final errors; `shown` marks the median run
  runs_csv << "integrator,seed,seconds,iterations,relmse,relmse_trimmed,ssim,shown\n";
  for (const auto& r : result.runs)
    for (const RepeatRun& x : r.repeats)
      runs_csv << r.integrator << ',' << x.seed << ',' << x.seconds << ',' << x.iterations << ','
               << x.errors.rel_mse << ',' << x.errors.rel_mse_trimmed << ',' << x.errors.ssim << ','
               << (x.seed == r.seed ? 1 : 0) << '\n';
  write_file_atomic((d / "runs.csv").string(), runs_csv.str());

  const std::string svg = convergence_svg(result);
  write_file_atomic((d / "convergence.svg").string(), svg);
  write_file_atomic((d / "index.html").string(), comparison_html(result, j["summary"], svg));
}

}  // namespace caustica
