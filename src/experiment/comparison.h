// Equal-time comparisons: every integrator renders the same scene for the same wall time and
// threads; the image is compared against a reference at log-spaced times (1, 2, 4, ... s)
// and at the end. Time spent computing errors is excluded from render time. With several runs
// per integrator (ComparisonConfig::runs) each renders once per seed, and the result keeps its
// median run and every run's errors: one seed's relMSE is one draw of a noisy number.
#pragma once

#include <atomic>
#include <functional>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "image/image.h"
#include "integrators/integrator.h"

namespace caustica {

class Scene;

struct ErrorMetrics {
  double mse = 0, rmse = 0, rel_mse = 0, rel_mse_trimmed = 0, ssim = 0;
  double block_rel_mse = 0;  // 16x16-pixel blocks: mostly bias
  double mean_ratio = 0;     // image mean over reference mean
};
ErrorMetrics compute_errors(const Image& image, const Image& reference);
nlohmann::json to_json(const ErrorMetrics& e);

struct Snapshot {
  double seconds = 0;
  uint32_t iterations = 0;
  ErrorMetrics errors;
};

// One run of an integrator when each renders with several seeds: its final errors.
struct RepeatRun {
  uint64_t seed = 0;
  double seconds = 0;
  uint32_t iterations = 0;
  ErrorMetrics errors;
};

struct IntegratorRun {
  std::string integrator;
  uint64_t seed = 0;                // this run's
  std::vector<Snapshot> snapshots;  // log-spaced, the last one at the end of the run
  Image image;
  double seconds = 0;
  uint32_t iterations = 0;
  uint64_t rays = 0;
  uint64_t nonfinite = 0;
  nlohmann::json integrator_stats;
  // Every run of this integrator, in seed order, this one included: one entry unless
  // ComparisonConfig::runs > 1. This run is their median by relMSE (median_run_index).
  std::vector<RepeatRun> repeats;
};

// Which of `rel_mse` (one per run) is the median run: the middle one by value, the lower of the
// two middle ones for an even count (a run that happened, not an average of two), the earlier
// run on ties.
size_t median_run_index(const std::vector<double>& rel_mse);
// The median of the runs' relMSE (the mean of the two middle ones for an even count).
double median_rel_mse(const IntegratorRun& run);

struct ComparisonConfig {
  std::vector<std::string> integrators;
  double seconds = 30;
  int threads = 0;  // 0 = all cores
  IntegratorSettings settings;
  double first_snapshot = 1.0;  // seconds; then doubling
  // Runs per integrator, with seeds settings.seed, settings.seed + 1, ... Each round runs every
  // integrator once, in turn, so that a drift of the machine's speed falls on all of them alike.
  int runs = 1;
  // When it becomes true the comparison ends: the integrator rendering then is dropped (its
  // time would not be equal to the others'), the completed ones are kept.
  const std::atomic<bool>* stop = nullptr;
};

struct ComparisonResult {
  std::string scene;
  ComparisonConfig config;
  std::vector<IntegratorRun> runs;  // one per integrator: its median run if it ran several
  std::string reference_description;
  bool interrupted = false;  // ended by config.stop: runs holds only the integrators completed
};

// progress(fraction, label) is called as the comparison advances (across all integrators).
ComparisonResult run_comparison(
    const Scene& scene, const Image& reference, const ComparisonConfig& config,
    const std::function<void(double, const std::string&)>& progress = {});

// Time integrator `run` would need to reach `target` relMSE, read off its convergence curve
// (log-log interpolation between snapshots; beyond the last snapshot, Monte Carlo's
// relMSE ~ 1/t is assumed). Returns a negative number if the curve is unusable.
double time_to_rel_mse(const IntegratorRun& run, double target);

}  // namespace caustica
