// The power formulas of lights/light_power.h against independent numeric integrals of each
// model's emission over the sphere, and the pbrt loader's "power" parameter against the power
// of the light it builds.
#include "lights/light_power.h"

#include <gtest/gtest.h>

#include <cmath>

#include "chi2.h"
#include "core/math.h"
#include "lights/light.h"
#include "pbrt_test_util.h"

namespace caustica {
namespace {

// pbrt-v4's SmoothStep, in double and written here rather than taken from the light model.
double smoothstep(double a, double b, double x) {
  if (a == b) return x < a ? 0.0 : 1.0;
  const double t = std::clamp((x - a) / (b - a), 0.0, 1.0);
  return t * t * (3 - 2 * t);
}

TEST(LightPower, PointLightIsIntensityIntegratedOverTheSphere) {
  const double integral = test::integrate_sphere([](Vec3) { return 1.0; }, 64, 64);
  EXPECT_NEAR(point_light_power_per_intensity(), integral, 1e-5 * integral);
}

TEST(LightPower, SpotLightIsSmoothstepFalloffIntegratedOverTheSphere) {
  // (cone angle, falloff start angle) in degrees: a hard cone, a narrow band, a band reaching
  // the axis, a cone wider than a hemisphere and the whole sphere.
  const float cones[][2] = {{30, 30}, {30, 25}, {40, 0}, {120, 60}, {180, 170}};
  for (const auto& [cone, start] : cones) {
    const float cos_end = std::cos(radians(cone)), cos_start = std::cos(radians(start));
    // Midpoint rule in cos theta, the spot axis being +z: the falloff depends on z alone.
    const double integral = test::integrate_sphere(
        [&](Vec3 w) { return smoothstep(cos_end, cos_start, w.z); }, 1 << 16, 1);
    EXPECT_NEAR(spot_light_power_per_intensity(cos_start, cos_end), integral, 1e-3 * integral)
        << cone << " " << start;
  }
}

TEST(LightPower, DiffuseAreaLightIsCosineWeightedRadianceTimesArea) {
  // Radiance 1 from a unit patch facing +z: its intensity is cos theta on each emitting side.
  const double one_sided =
      test::integrate_sphere([](Vec3 w) { return std::max(0.0, double(w.z)); }, 4096, 4);
  const double two_sided = test::integrate_sphere([](Vec3 w) { return std::abs(w.z); }, 4096, 4);
  for (float area : {0.25f, 1.f, 7.5f}) {
    EXPECT_NEAR(diffuse_area_light_power_per_radiance(area, false), area * one_sided,
                1e-5 * area * one_sided);
    EXPECT_NEAR(diffuse_area_light_power_per_radiance(area, true), area * two_sided,
                1e-5 * area * two_sided);
  }
}

// pbrt-v4's "power": each light emits the power asked for (RGB [1 1 1] has luminance 1).
TEST(LightPower, PbrtPowerParameterIsThePowerOfTheLoadedLight) {
  struct Case {
    const char* text;
    float power;
  };
  const Case cases[] = {
      {"LightSource \"point\" \"float power\" 12\n", 12},
      {"LightSource \"spot\" \"float coneangle\" 40 \"float conedeltaangle\" 15 "
       "\"float power\" 30\n",
       30},
      {"AreaLightSource \"diffuse\" \"float power\" 20 \"bool twosided\" true\n"
       "Shape \"sphere\" \"float radius\" 0.3\n",
       20},
      {"AreaLightSource \"diffuse\" \"float power\" 5\n"
       "Shape \"trianglemesh\" \"point3 P\" [-1 -1 0  1 -1 0  1 1 0]\n",
       5},
  };
  for (const Case& c : cases) {
    auto scene = test::load_text(test::with_camera(c.text));
    ASSERT_EQ(scene->lights().size(), 1u) << c.text;
    EXPECT_NEAR(scene->lights()[0]->power().luminance(), c.power, 1e-4 * c.power) << c.text;
  }
}

}  // namespace
}  // namespace caustica
