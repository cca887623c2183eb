// adaptive-vcm's report (AdaptivePlan::report): what it chose, why, and where.
#include <algorithm>
#include <nlohmann/json.hpp>

#include "integrators/bidir/adaptive_plan.h"

namespace caustica::bidir {

void AdaptivePlan::report(nlohmann::json& stats) const {
  nlohmann::json a;
  a["probes"] = probes_;
  a["probe_iterations"] = probe_iterations_;  // from the second on (the first is iteration 0)
  // A probe records one pixel per probe_stride x probe_stride block (1: every pixel); the
  // candidates' variances and pixel counts are of those pixels.
  a["probe_stride"] = stride_;
  a["costs"] = measured_ ? "measured" : "model";
  a["light_paths_per_iteration"] = chosen_.light_paths;
  a["connections"] = chosen_.connections;
  a["merge_fraction"] = fraction_of(modes_, PixelMode::Merge);
  a["path_trace_fraction"] = fraction_of(modes_, PixelMode::PathTrace);
  a["stop_fraction"] = fraction_of(modes_, PixelMode::Stop);
  a["history"] = history_;
  a["checks"] = checks_;
  // The masks, block-averaged to at most 64 x 64 cells.
  const int block = std::max(1, (std::max(width_, height_) + 63) / 64);
  const int cw = (width_ + block - 1) / block, ch = (height_ + block - 1) / block;
  auto mask = [&](PixelMode mode) {
    std::vector<double> fraction(size_t(cw) * ch, 0.0), count(size_t(cw) * ch, 0.0);
    for (int y = 0; y < height_; ++y)
      for (int x = 0; x < width_; ++x) {
        const size_t cell = size_t(y / block) * cw + size_t(x / block);
        fraction[cell] += modes_[size_t(y) * width_ + x] == mode;
        count[cell] += 1;
      }
    for (size_t i = 0; i < fraction.size(); ++i) fraction[i] /= std::max(count[i], 1.0);
    return nlohmann::json{{"width", cw}, {"height", ch}, {"block", block}, {"fraction", fraction}};
  };
  a["merge_mask"] = mask(PixelMode::Merge);
  a["path_trace_mask"] = mask(PixelMode::PathTrace);
  a["stop_mask"] = mask(PixelMode::Stop);  // photon mapping alone
  stats["adaptive"] = a;
}

}  // namespace caustica::bidir
