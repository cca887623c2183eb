// Writes a comparison to a directory: per-integrator EXR and PNG, false-colour error images,
// results.json, results.csv (every snapshot), runs.csv (every run's final errors: one per
// integrator and seed), convergence.svg and index.html — a page that opens from disk with no
// network (all script and style inline; images are files beside it). With several runs per
// integrator the images, snapshots and curves are each integrator's median run.
#pragma once

#include <string>

#include "experiment/comparison.h"

namespace caustica {

struct ReportOptions {
  float exposure = 0;  // PNG exposure in stops
};

void write_comparison_report(const ComparisonResult& result, const Image& reference,
                             const std::string& dir, const ReportOptions& options = {});

// The convergence plot (relMSE against time, log-log, one line per integrator) as SVG.
std::string convergence_svg(const ComparisonResult& result, int width = 720, int height = 440);

// Summary rows: final errors and speed-up relative to `pt` in time-to-equal-relMSE
// (speedup = time pt needs to reach this integrator's final relMSE / this run's time), of each
// integrator's median run; with several runs also their seeds, every run's relMSE, the median,
// the least and the largest.
nlohmann::json comparison_summary(const ComparisonResult& result);

// What results.json holds: the scene, the settings, the summary rows and every run's snapshots.
// The Python module returns it as a dict, so a script sees what the report's reader sees.
nlohmann::json comparison_json(const ComparisonResult& result);

}  // namespace caustica
