// adaptive-vcm's measurement of what it chose: the pixel moments of the iterations that render
// one choice (those between two probes), so that the report can set the variance the probes
// predicted for that configuration against the variance it showed (AdaptivePlan::finish_probe).
//
// An iteration's estimate of a pixel is the film's total after it minus before it (every
// camera sample and light-tracing splat of the iteration, exactly). The sums are exact (fixed
// point, core/fixed_sum.h): under MPI every rank adds the iterations it owns, and the sum over
// the ranks (Integrator::learning_sums) is the sum one process makes, so every rank measures the
// same variances and reports what one process reports.
#pragma once

#include <span>
#include <vector>

#include "core/fixed_sum.h"

namespace caustica {
class Film;
}

namespace caustica::bidir {

class SegmentMoments {
 public:
  // Zeroed sums for the film's pixels listed in `pixels` (adaptive-vcm's probed grid: only
  // those are checked against a prediction, and on a large image they are one in stride^2).
  void reset(std::vector<size_t> pixels);
  // Around one iteration that renders the current choice.
  void begin_iteration(const Film& film);
  void end_iteration(const Film& film);
  // Per listed pixel the sums of v and v^2 (v: the scalar estimate, the mean of the channels),
  // then the number of iterations: the layout variances() reads, to be summed over ranks.
  std::span<FixedSum> sums() { return sums_; }
  // Zero the sums (a new choice begins).
  void clear();
  // Per listed pixel, from sums (this process's or summed over ranks): the unbiased variance of one
  // iteration's estimate, from the sample variance of the segment's M iterations; empty when
  // M < 2. *iterations: M.
  static std::vector<double> variances(std::span<const FixedSum> sums, double* iterations);

 private:
  std::vector<size_t> pixels_;    // the film's pixels measured
  std::vector<FixedSum> before_;  // per listed pixel: the film's three channel totals, added
  std::vector<FixedSum> sums_;
};

}  // namespace caustica::bidir
