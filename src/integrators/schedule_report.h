// The JSON statistics of a guided integrator's training schedule (guiding/training_schedule.h),
// the same keys for guided-pt and the guided bidirectional integrators.
#pragma once

#include <nlohmann/json.hpp>

#include "guiding/training_schedule.h"

namespace caustica {

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
