#include "experiment/comparison.h"

#include <tbb/global_control.h>

#include <algorithm>
#include <cmath>
#include <memory>
#include <optional>

#include "film/film.h"
#include "image/metrics.h"
#include "integrators/registry.h"
#include "render/renderer.h"
#include "render/statistics.h"
#include "scene/scene.h"

namespace caustica {

ErrorMetrics compute_errors(const Image& image, const Image& reference) {
  ErrorMetrics e;
  e.mse = mse(image, reference);
  e.rmse = std::sqrt(e.mse);
  e.rel_mse = rel_mse(image, reference, 0.01);
  e.rel_mse_trimmed = rel_mse_trimmed(image, reference, 0.001, 0.01);
  e.ssim = ssim(image, reference);
  e.block_rel_mse = block_rel_mse(image, reference, 16, 0.01);
  e.mean_ratio = mean_ratio(image, reference);
  return e;
}

nlohmann::json to_json(const ErrorMetrics& e) {
  return {{"mse", e.mse},
          {"rmse", e.rmse},
          {"relmse", e.rel_mse},
          {"relmse_trimmed", e.rel_mse_trimmed},
          {"ssim", e.ssim},
          {"block16_relmse", e.block_rel_mse},
          {"mean_ratio", e.mean_ratio}};
}

namespace {

// One render of `name` for config.seconds with `settings`; nullopt if config.stop ended it.
// progress(seconds) reports how far it is.
std::optional<IntegratorRun> run_integrator(const Scene& scene, const Image& reference,
                                            const ComparisonConfig& config, const std::string& name,
                                            const IntegratorSettings& settings,
                                            const std::function<void(double)>& progress) {
  auto integrator = make_integrator(name, settings);
  if (!integrator) throw std::invalid_argument("unknown integrator '" + name + "'");
  IntegratorRun run;
  run.integrator = name;
  run.seed = settings.seed;
  double next_snapshot = config.first_snapshot;
  RenderCallbacks cb;
  cb.quiet = true;
  cb.on_iteration = [&](const Film& film, uint32_t iterations, double seconds) {
    if (seconds >= next_snapshot) {
      run.snapshots.push_back(
          {seconds, iterations, compute_errors(integrator->image(film), reference)});
      while (next_snapshot <= seconds) next_snapshot *= 2;
    }
    progress(seconds);
    return true;
  };
  RenderBudget budget;
  budget.seconds = config.seconds;
  cb.stop = config.stop;
  const RenderResult r = render(scene, *integrator, budget, cb);
  if (r.interrupted) return std::nullopt;
  run.image = r.image;
  run.seconds = r.seconds;
  run.iterations = r.iterations;
  run.rays = r.rays;
  run.nonfinite = r.nonfinite;
  run.snapshots.push_back({r.seconds, r.iterations, compute_errors(r.image, reference)});
  RunDescription description;
  description.scene = scene.name();
  description.integrator = name;
  description.settings = settings;
  description.threads = config.threads;
  description.time_budget = config.seconds;
  run.integrator_stats = render_statistics(scene, *integrator, r, description);
  return run;
}

// The median of an integrator's runs (in seed order), with every run's errors attached.
IntegratorRun median_run(std::vector<IntegratorRun>& runs) {
  std::vector<double> rel_mse;
  std::vector<RepeatRun> repeats;
  for (const IntegratorRun& r : runs) {
    rel_mse.push_back(r.snapshots.back().errors.rel_mse);
    repeats.push_back({r.seed, r.seconds, r.iterations, r.snapshots.back().errors});
  }
  IntegratorRun median = std::move(runs[median_run_index(rel_mse)]);
  median.repeats = std::move(repeats);
  return median;
}

}  // namespace

size_t median_run_index(const std::vector<double>& rel_mse) {
  std::vector<size_t> order(rel_mse.size());
  for (size_t i = 0; i < order.size(); ++i) order[i] = i;
  // NaN sorts last, so that a broken run is never the median of good ones.
  auto key = [&](size_t i) { return std::isnan(rel_mse[i]) ? HUGE_VAL : rel_mse[i]; };
  std::stable_sort(order.begin(), order.end(), [&](size_t a, size_t b) { return key(a) < key(b); });
  return order.empty() ? 0 : order[(order.size() - 1) / 2];
}

double median_rel_mse(const IntegratorRun& run) {
  std::vector<double> v;
  for (const RepeatRun& r : run.repeats) v.push_back(r.errors.rel_mse);
  if (v.empty()) return run.snapshots.empty() ? 0.0 : run.snapshots.back().errors.rel_mse;
  std::sort(v.begin(), v.end());
  const size_t m = v.size() / 2;
  return v.size() % 2 ? v[m] : 0.5 * (v[m - 1] + v[m]);
}

ComparisonResult run_comparison(const Scene& scene, const Image& reference,
                                const ComparisonConfig& config,
                                const std::function<void(double, const std::string&)>& progress) {
  if (reference.width() != scene.camera().width() || reference.height() != scene.camera().height())
    throw std::runtime_error("reference is " + std::to_string(reference.width()) + "x" +
                             std::to_string(reference.height()) + " but the scene renders " +
                             std::to_string(scene.camera().width()) + "x" +
                             std::to_string(scene.camera().height()));
  if (config.runs < 1) throw std::invalid_argument("runs per integrator must be at least 1");
  std::unique_ptr<tbb::global_control> limit;
  if (config.threads > 0)
    limit = std::make_unique<tbb::global_control>(tbb::global_control::max_allowed_parallelism,
                                                  size_t(config.threads));

  ComparisonResult result;
  result.scene = scene.name();
  result.config = config;
  const size_t n = config.integrators.size();
  const double total = config.seconds * double(n) * config.runs;
  std::vector<std::vector<IntegratorRun>> runs(n);
  for (int round = 0; round < config.runs && !result.interrupted; ++round)
    for (size_t k = 0; k < n; ++k) {
      if (config.stop && config.stop->load()) {
        result.interrupted = true;
        break;
      }
      const std::string& name = config.integrators[k];
      IntegratorSettings settings = config.settings;
      settings.seed += uint64_t(round);
      const double before = (double(round) * double(n) + double(k)) * config.seconds;
      std::optional<IntegratorRun> run =
          run_integrator(scene, reference, config, name, settings, [&](double seconds) {
            if (progress) progress((before + std::min(seconds, config.seconds)) / total, name);
          });
      if (!run) {
        result.interrupted = true;
        break;
      }
      runs[k].push_back(std::move(*run));
    }
  for (auto& r : runs)
    if (!r.empty()) result.runs.push_back(median_run(r));
  if (progress && !result.interrupted) progress(1.0, "done");
  return result;
}

double time_to_rel_mse(const IntegratorRun& run, double target) {
  const auto& s = run.snapshots;
  if (s.empty() || !(target > 0)) return -1;
  for (size_t i = 0; i < s.size(); ++i) {
    if (s[i].errors.rel_mse <= target) {
      if (s[i].errors.rel_mse == target) return s[i].seconds;  // exp(log(t)) need not give t
      if (i == 0)
        return s[0].seconds * s[0].errors.rel_mse / target;  // ~1/t before the first point
      // Log-log interpolation between snapshots i-1 and i.
      const double t0 = std::log(s[i - 1].seconds), t1 = std::log(s[i].seconds);
      const double e0 = std::log(s[i - 1].errors.rel_mse), e1 = std::log(s[i].errors.rel_mse);
      if (e1 == e0) return s[i].seconds;
      const double f = (std::log(target) - e0) / (e1 - e0);
      return std::exp(t0 + f * (t1 - t0));
    }
  }
  const Snapshot& last = s.back();
  return last.errors.rel_mse > 0 ? last.seconds * last.errors.rel_mse / target : -1;
}

}  // namespace caustica
