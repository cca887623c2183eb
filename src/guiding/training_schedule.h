// How a guided integrator splits its budget between learning and rendering (Müller et al. 2017,
// "Practical Path Guiding", sec. 5.2 and its implementation), shared by guided-pt and the
// guided bidirectional integrators.
//
// Training passes double: pass k renders 2^k iterations (one sample per pixel each), samples
// with the field learned by the passes before it and records into the next one. One pass is
// final: it samples with the field as it is and records nothing, so it costs only the sampling,
// and it lasts until the budget is spent. Which pass is final:
//  - with a sample budget B, the next pass when after it fewer than twice its length would
//    remain (Müller's rule: the last pass takes the rest, never a sliver of a pass);
//  - with a time budget, the same rule with the next pass's predicted seconds (twice the last);
//  - with either, when learning stopped paying: with tau_k = V_k B_k (the variance of pass k's
//    image times the budget it took, samples or seconds) and R_k the budget left at its start,
//    the final image's variance had training stopped after pass k is V^_k = tau_k / R_k; the
//    pass after the first k with V^_k > V^_{k-1} is final (V^ is convex when training has
//    diminishing returns, sec. 5.2).
// Without a budget (an integrator driven iteration by iteration) training never stops.
//
// Determinism: with a sample budget the decisions depend on the passes' variances only, which
// the inverse-variance combiner computes in a fixed order; only time budgets read the clock.
#pragma once

#include <cstdint>
#include <vector>

namespace caustica {

class TrainingSchedule {
 public:
  TrainingSchedule() = default;
  // spp > 0: a sample budget; else seconds > 0: a time budget; neither: train forever.
  TrainingSchedule(int spp, double seconds) : spp_(spp), seconds_(seconds) {}

  // Called before each iteration, in order from 0: whether it starts a new pass (never for
  // iteration 0). `elapsed` is the seconds since the render began (time budgets only).
  bool starts_pass(uint32_t iteration, double elapsed);
  // After a pass has ended (starts_pass returned true): its variance (V_k, the variance of its
  // pixel mean; negative: unknown). Decides whether the pass now starting is final.
  void end_pass(double variance);

  int pass() const { return pass_; }
  bool final_pass() const { return final_; }
  // Whether the current pass records what it sees (every pass but the final one).
  bool learning() const { return !final_; }
  // The iteration the final pass began at (-1 while training).
  int64_t final_from() const { return final_ ? int64_t(pass_start_) : -1; }
  // Why the final pass is final: "budget" (too little left for another pass) or "variance"
  // (V^ rose), empty while training.
  const char* reason() const { return reason_; }

  // For each completed pass, V^_k as above (negative when unknown).
  const std::vector<double>& predicted_final_variances() const { return predicted_; }

 private:
  int spp_ = 0;
  double seconds_ = 0;
  int pass_ = 0;
  uint32_t pass_start_ = 0;  // first iteration of the current pass
  uint32_t pass_length_ = 1;
  double pass_start_seconds_ = 0;
  struct Ended {
    uint32_t start = 0, length = 0;
    double start_seconds = 0, seconds = 0;
  } ended_;  // the pass that ended last
  bool final_ = false;
  const char* reason_ = "";
  std::vector<double> predicted_;
};

}  // namespace caustica
