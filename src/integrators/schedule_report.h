// The JSON statistics of a guided integrator's training schedule (guiding/training_schedule.h),
// the same keys for guided-pt and the guided bidirectional integrators.
#pragma once

#include <nlohmann/json.hpp>
#include <vector>

#include "guiding/training_schedule.h"

namespace caustica {

// Wall seconds of pass k, from when each completed pass ended (the last, current pass: until
// `now`); 0 past the passes known.
inline double pass_seconds(const std::vector<double>& ends, size_t k, double now) {
  const double begin = k == 0 ? 0.0 : (k - 1 < ends.size() ? ends[k - 1] : now);
  const double end = k < ends.size() ? ends[k] : now;
  return end > begin ? end - begin : 0.0;
}

inline void report_schedule(const TrainingSchedule& s, nlohmann::json& g) {
  g["passes_started"] = s.pass() + 1;
  g["training_passes"] = s.training_passes();
  g["rendering_from_iteration"] = s.rendering_from();
  g["training_stopped_by"] = s.reason();
  if (s.trial_guided_tau() >= 0 || s.trial_unguided_tau() >= 0)
    g["trial_variance_seconds"] = {{"guided", s.trial_guided_tau()},
                                   {"unguided", s.trial_unguided_tau()}};
  if (s.final_pass()) g["rendering_guided"] = s.guided();
  g["predicted_final_variances"] = s.predicted_final_variances();
}

}  // namespace caustica
