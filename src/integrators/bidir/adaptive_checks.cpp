// What rendering a choice showed (AdaptivePlan::check_last_choice): the segment of iterations
// between two probes, against the variance and cost predicted for the choice, and the variance
// that no probe predicted (add_unseen), which every later choice prices into its candidates,
// and the segments' variance against the probes' own, which weights the probes in the image
// (probe_weight).
#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <nlohmann/json.hpp>

#include "integrators/bidir/adaptive_plan.h"
#include "integrators/bidir/grid_statistics.h"

namespace caustica::bidir {

namespace {
// The mean over pixels of value[p] / denominator[p], over the finite ratios (NaN: none).
double finite_mean(const std::vector<double>& value, const std::vector<double>& denominator) {
  double sum = 0;
  size_t n = 0;
  for (size_t p = 0; p < value.size(); ++p) {
    const double x = value[p] / denominator[p];
    if (!std::isfinite(x)) continue;
    sum += x;
    ++n;
  }
  return n > 0 ? sum / double(n) : std::numeric_limits<double>::quiet_NaN();
}
}  // namespace

void AdaptivePlan::check_last_choice(const std::vector<double>& measured, double iterations,
                                     double thread_seconds, const std::vector<float>& means) {
  // The measured relative variance, pooled as the prediction was; both capped at the
  // prediction's 99.5th percentile, so that a firefly that one segment happened to render (or
  // that the prediction's winsorising took out) does not decide the comparison alone.
  std::vector<double> relative(grid_pixels_);
  for (size_t p = 0; p < grid_pixels_; ++p)
    relative[p] = measured[p] / (double(means[p]) * means[p] + kRelEps);
  relative = box_blur(relative, grid_w_, grid_h_, kPoolRadius);
  const double cap = finite_quantile(chosen_variance_, kWinsorize);
  std::vector<std::array<double, 2>> blocks((grid_pixels_ + kPixelBlock - 1) / kPixelBlock);
  for_pixel_blocks(grid_pixels_, [&](size_t b, size_t begin, size_t end) {
    std::array<double, 2> sum{};
    for (size_t p = begin; p < end; ++p) {
      if (!std::isfinite(chosen_variance_[p]) || !std::isfinite(relative[p])) continue;
      sum[0] += std::min(relative[p], cap);
      sum[1] += std::min(chosen_variance_[p], cap);
    }
    blocks[b] = sum;
  });
  double measured_total = 0, predicted_total = 0;
  for (const std::array<double, 2>& sum : blocks) {
    measured_total += sum[0];
    predicted_total += sum[1];
  }
  // Relative to the mean shrunk by the segment's variance too: a firefly raises its own
  // pixel's mean as much as its variance.
  const std::vector<double> shrunk = denominators(means, &measured);
  const double unseen_total = add_unseen(measured, iterations, shrunk);
  const double rendered = finite_mean(measured, shrunk);
  if (std::isfinite(rendered)) {
    rendered_relative_sum_ += rendered * iterations;
    rendered_iterations_ += iterations;
  }
  checks_.push_back({{"after_probe", probes_},
                     {"light_path_factor", candidates()[chosen_j_].light_path_factor},
                     {"connections", candidates()[chosen_j_].connections},
                     {"iterations", iterations},
                     {"measured_relative_variance", measured_total / double(grid_pixels_)},
                     {"predicted_relative_variance", predicted_total / double(grid_pixels_)},
                     {"unseen_relative_variance", unseen_total},
                     // Not deterministic (a clock); with the fixed cost model the two differ by
                     // the machine's speed, so compare their ratio across choices.
                     {"measured_us_per_pixel",
                      iterations > 0 ? 1e6 * thread_seconds / (iterations * double(pixels_)) : 0.0},
                     {"predicted_us_per_pixel", chosen_cost_}});
}

double AdaptivePlan::add_unseen(const std::vector<double>& measured, double iterations,
                                const std::vector<double>& shrunk) {
  // What the prediction missed by far (uncapped) where the pixel saw the camera pass alone:
  // fireflies of events no probe sampled.
  double total = 0;
  if (unseen_sums_.empty()) {
    unseen_sums_.assign(grid_pixels_, 0.0);
    unseen_iterations_.assign(grid_pixels_, 0.0);
  }
  std::vector<double> robust(grid_pixels_);
  for (size_t p = 0; p < grid_pixels_; ++p) robust[p] = measured[p] / shrunk[p];
  robust = box_blur(robust, grid_w_, grid_h_, kPoolRadius);
  // The last choice's mode of each grid pixel is that of its image pixel (take_choice).
  const std::vector<size_t> image_pixels = grid_image_pixels();
  for (size_t p = 0; p < grid_pixels_; ++p) {
    const PixelMode mode = modes_[image_pixels[p]];
    if (mode != PixelMode::PathTrace && mode != PixelMode::Stop) continue;
    unseen_iterations_[p] += iterations;
    const double predicted = chosen_variance_[p];
    if (!std::isfinite(predicted) || !std::isfinite(robust[p])) continue;
    if (robust[p] <= kUnseenFactor * predicted) continue;
    unseen_sums_[p] += (robust[p] - predicted) * iterations;
    total += robust[p] - predicted;
  }
  return total / double(grid_pixels_);
}

std::vector<double> AdaptivePlan::unseen_variance() const {
  if (unseen_sums_.empty()) return {};
  std::vector<double> out(grid_pixels_, 0.0);
  for (size_t p = 0; p < grid_pixels_; ++p)
    if (unseen_iterations_[p] > 0) out[p] = unseen_sums_[p] / unseen_iterations_[p];
  return out;
}

AdaptivePlan::ProbeWeight AdaptivePlan::probe_weight(const std::vector<float>& image_means) const {
  ProbeWeight w;
  if (probes_ < 2 || !(rendered_iterations_ > 0)) return w;
  const std::vector<float> means = on_grid(image_means);
  if (means.size() != grid_pixels_) return w;
  std::vector<double> own(grid_pixels_);
  for (size_t p = 0; p < grid_pixels_; ++p) own[p] = std::max(probe_estimate_variance(p), 0.0);
  w.probe_relative_variance = finite_mean(own, denominators(means));
  w.rendered_relative_variance = rendered_relative_sum_ / rendered_iterations_;
  if (w.probe_relative_variance > 0 && std::isfinite(w.rendered_relative_variance))
    w.weight = std::clamp(w.rendered_relative_variance / w.probe_relative_variance, 0.0, 1.0);
  return w;
}

}  // namespace caustica::bidir
