// The JSON statistics of a guided integrator's training schedule (guiding/training_schedule.h),
// the same keys for guided-pt and the guided bidirectional integrators.
#pragma once

#include <nlohmann/json.hpp>
#include <vector>

#include "guiding/training_schedule.h"
#include "image/inverse_variance.h"

namespace caustica {

// The passes of a guided integrator's image (image/inverse_variance.h): how they combine, and
// each pass's samples per pixel, variance and wall seconds, from when each completed pass ended
// (`ends`; the current pass until `now`).
inline void report_passes(const InverseVarianceCombiner& combiner, bool inverse_variance,
                          const std::vector<double>& ends, double now, nlohmann::json& g) {
  nlohmann::json passes = nlohmann::json::array();
  const std::vector<InverseVarianceCombiner::Pass> all = combiner.passes();
  for (size_t k = 0; k < all.size(); ++k) {
    const double begin = k == 0 ? 0.0 : (k - 1 < ends.size() ? ends[k - 1] : now);
    const double end = k < ends.size() ? ends[k] : now;
    passes.push_back({{"spp", all[k].samples},
                      {"variance", all[k].variance},
                      {"variance_error", all[k].variance_error},
                      {"seconds", end > begin ? end - begin : 0.0}});
  }
  g["passes"] = passes;
  g["combine"] = inverse_variance ? "inverse-variance" : "equal";
  g["pass_image_bytes"] = combiner.bytes();
}

inline void report_schedule(const TrainingSchedule& s, nlohmann::json& g) {
  g["passes_started"] = s.pass() + 1;
  g["training_passes"] = s.training_passes();
  g["rendering_from_iteration"] = s.rendering_from();
  g["training_stopped_by"] = s.reason();
  if (s.trial_guided_tau() >= 0 || s.trial_unguided_tau() >= 0) {
    g["trial_variance_seconds"] = {{"guided", s.trial_guided_tau()},
                                   {"unguided", s.trial_unguided_tau()}};
    g["trial_rounds"] = s.trial_rounds();
    g["early_trial"] = s.early_trial();
    g["trial_log_ratio_error"] = s.trial_log_ratio_error();
  }
  if (s.final_pass()) g["rendering_guided"] = s.guided();
  g["predicted_final_variances"] = s.predicted_final_variances();
}

}  // namespace caustica
