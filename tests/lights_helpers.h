// Helpers shared by the light tests (local_lights_test.cpp, infinite_lights_test.cpp): the
// chi-square options they run with, and the check that a NEE sample's emission densities are
// what pdf_le reports.
#pragma once

#include <algorithm>
#include <cmath>

#include "chi2.h"
#include "lights/light.h"

namespace caustica::test {

// Many chi-square tests run in the light tests: Sidak-correct a 1% family-wise level over ~20.
inline constexpr double kSignificance = 0.0005;

inline Chi2Options options() {
  Chi2Options o;
  o.significance = kSignificance;
  return o;
}

// Checks that the emission densities a NEE sample carries are what pdf_le reports.
inline void expect_emit_pdfs_match(const Light& light, const LightLiSample& s, int* mismatches) {
  float pos = 0, dir = 0;
  light.pdf_le(s.p_light, s.n_light, -s.wi, &pos, &dir);
  const auto close = [](float a, float b) {
    return std::abs(a - b) <= 1e-4f * std::max({1.f, a, b});
  };
  if (!close(pos, s.pdf_emit_pos) || !close(dir, s.pdf_emit_dir)) ++*mismatches;
}

}  // namespace caustica::test
