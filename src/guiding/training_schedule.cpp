#include "guiding/training_schedule.h"

#include <cstddef>

namespace caustica {

bool TrainingSchedule::starts_pass(uint32_t iteration, double elapsed) {
  if (iteration == 0) {
    *this = TrainingSchedule(spp_, seconds_);
    pass_start_seconds_ = elapsed;
    return false;
  }
  if (final_ || iteration < pass_start_ + pass_length_) return false;
  ended_ = {pass_start_, pass_length_, pass_start_seconds_, elapsed - pass_start_seconds_};
  ++pass_;
  pass_start_ = iteration;
  pass_length_ = pass_ < 31 ? 1u << pass_ : 1u << 31;
  pass_start_seconds_ = elapsed;
  return true;
}

void TrainingSchedule::end_pass(double variance) {
  // Budget spent by the pass that ended, and the budget that was left at its start.
  const bool samples = spp_ > 0;
  const double spent = samples ? double(ended_.length) : ended_.seconds;
  const double left =
      samples ? double(spp_) - double(ended_.start) : seconds_ - ended_.start_seconds;
  predicted_.push_back(variance >= 0 && left > 0 && spent > 0 ? variance * spent / left : -1);
  if (spp_ <= 0 && seconds_ <= 0) return;  // no budget: train forever

  const size_t k = predicted_.size() - 1;
  if (k >= 1 && predicted_[k] >= 0 && predicted_[k - 1] >= 0 && predicted_[k] > predicted_[k - 1]) {
    final_ = true;
    reason_ = "variance";
    return;
  }
  // Too little left for the next pass and a longer one after it: the next pass takes the rest.
  double next = 0, remaining = 0;
  if (samples) {
    next = double(pass_length_);
    remaining = double(spp_) - double(pass_start_);
  } else {
    next = 2 * ended_.seconds;
    remaining = seconds_ - pass_start_seconds_;
  }
  if (remaining - next < 2 * next) {
    final_ = true;
    reason_ = "budget";
  }
}

}  // namespace caustica
