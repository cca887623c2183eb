// Lights at infinity, the distant light and the uniform and image environments, and the
// environment maps' mappings of the sphere (equal-area octahedral, lat-long): sampled densities
// against evaluated ones (chi-square, for image maps in texel space), emission from the disk that
// enters the scene, power, and pbrt-v4's orientation conventions. Lights at a place in the scene:
// local_lights_test.cpp.
#include <gtest/gtest.h>

#include <cmath>
#include <functional>
#include <memory>
#include <optional>

#include "chi2.h"
#include "core/rng.h"
#include "core/transform.h"
#include "core/warp.h"
#include "image/image.h"
#include "lights/env_mapping.h"
#include "lights/lights.h"
#include "lights_helpers.h"

namespace caustica {
namespace {

using test::chi2_test;
using test::Chi2Options;
using test::DirectionSample;
using test::expect_emit_pdfs_match;
using test::options;

// ------------------------------------------------------------------------------------------
// Lights at infinity

constexpr Vec3 kSceneCenter(0.5f, -1.f, 2.f);
constexpr float kSceneRadius = 3.f;

// Emission from a light at infinity starts on the disk of radius R perpendicular to the
// direction, R behind the scene's centre, with pdf_pos = 1 / (pi R^2).
void expect_on_entry_disk(const LightLeSample& e) {
  const Vec3 rel = e.p - kSceneCenter;
  EXPECT_NEAR(dot(rel, e.dir), -kSceneRadius, 1e-4f);
  EXPECT_LE(length(rel + e.dir * kSceneRadius), kSceneRadius * 1.0001f);
  EXPECT_NEAR(e.pdf_pos, 1.f / (kPi * sqr(kSceneRadius)), 1e-7f);
}

TEST(DistantLight, ArrivesFromOppositeOfItsDirectionAndEmitsFromEntryDisk) {
  const Vec3 dir = normalize(Vec3(0.2f, -1.f, 0.3f));
  const auto light = make_distant_light(dir * 3.f, Rgb(2.f));
  light->preprocess(kSceneCenter, kSceneRadius);
  EXPECT_TRUE(light->is_delta());
  EXPECT_TRUE(light->is_infinite());
  auto s = light->sample_li(Vec3(1, 2, 3), Vec2(0.3f, 0.9f));
  ASSERT_TRUE(s.has_value());
  EXPECT_NEAR(dot(s->wi, -dir), 1.f, 1e-6f);
  EXPECT_EQ(s->distance, kInfinity);
  EXPECT_EQ(s->pdf_w, 1.f);
  EXPECT_EQ(s->radiance, Rgb(2.f));
  int mismatches = 0;
  expect_emit_pdfs_match(*light, *s, &mismatches);
  EXPECT_EQ(mismatches, 0);
  Pcg32 rng(21, 22);
  for (int i = 0; i < 1000; ++i) {
    auto e = light->sample_le(rng.next_2d(), rng.next_2d());
    ASSERT_TRUE(e.has_value());
    EXPECT_NEAR(dot(e->dir, dir), 1.f, 1e-6f);
    EXPECT_EQ(e->pdf_dir, 1.f);
    expect_on_entry_disk(*e);
  }
  EXPECT_NEAR(light->power().r, 2.f * kPi * sqr(kSceneRadius), 1e-3f);
}

TEST(UniformEnvironment, NeeSamplesMatchPdf) {
  const auto light = make_uniform_environment(Rgb(0.5f));
  light->preprocess(kSceneCenter, kSceneRadius);
  const Vec3 ref(0.1f, 0.2f, 0.3f);
  int mismatches = 0;
  auto sample = [&](Pcg32& rng) -> std::optional<DirectionSample> {
    auto s = light->sample_li(ref, rng.next_2d());
    if (!s) return std::nullopt;
    EXPECT_EQ(s->distance, kInfinity);
    EXPECT_EQ(s->radiance, light->radiance_escaped(s->wi));
    expect_emit_pdfs_match(*light, *s, &mismatches);
    return DirectionSample{s->wi, s->pdf_w};
  };
  const auto r = chi2_test(
      sample, [&](Vec3 w) { return light->pdf_li(ref, w, {}, {}); }, options());
  EXPECT_TRUE(r.passed) << r.message;
  EXPECT_EQ(mismatches, 0);
}

TEST(UniformEnvironment, EmissionMatchesPdfLeAndPowerIsRadianceTimesEtendue) {
  const auto light = make_uniform_environment(Rgb(0.5f, 1.f, 2.f));
  light->preprocess(kSceneCenter, kSceneRadius);
  int bad_pos = 0;
  auto sample = [&](Pcg32& rng) -> std::optional<DirectionSample> {
    auto e = light->sample_le(rng.next_2d(), rng.next_2d());
    if (!e) return std::nullopt;
    float pos, dir;
    light->pdf_le(e->p, e->n, e->dir, &pos, &dir);
    if (pos != e->pdf_pos) ++bad_pos;
    if (std::abs(dot(e->p - kSceneCenter, e->dir) + kSceneRadius) > 1e-4f) ++bad_pos;
    return DirectionSample{e->dir, e->pdf_dir};
  };
  auto pdf = [&](Vec3 w) {
    float pos, dir;
    light->pdf_le({}, {}, w, &pos, &dir);
    return dir;
  };
  const auto r = chi2_test(sample, pdf, options());
  EXPECT_TRUE(r.passed) << r.message;
  EXPECT_EQ(bad_pos, 0);
  expect_on_entry_disk(*light->sample_le(Vec2(0.9f, 0.1f), Vec2(0.3f, 0.3f)));
  EXPECT_NEAR(light->power().g, 4 * kPi * kPi * sqr(kSceneRadius), 1e-2f);
}

// ------------------------------------------------------------------------------------------
// Environment mappings

TEST(EqualAreaMapping, RoundTripsAndFollowsPbrtOrientation) {
  Pcg32 rng(31, 32);
  for (int i = 0; i < 100000; ++i) {
    const Vec3 d = sample_uniform_sphere(rng.next_2d());
    const Vec2 uv = equal_area_sphere_to_square(d);
    ASSERT_TRUE(uv.x >= 0 && uv.x <= 1 && uv.y >= 0 && uv.y <= 1);
    const Vec3 back = equal_area_square_to_sphere(uv);
    ASSERT_LT(distance(back, d), 2e-5f) << d.x << " " << d.y << " " << d.z;
    const Vec2 p = rng.next_2d();
    const Vec2 q = equal_area_sphere_to_square(equal_area_square_to_sphere(p));
    ASSERT_LT(std::abs(q.x - p.x) + std::abs(q.y - p.y), 2e-5f) << p.x << " " << p.y;
  }
  // pbrt-v4's orientation: centre +z, corners -z, u with x, v with y.
  EXPECT_LT(distance(equal_area_square_to_sphere({0.5f, 0.5f}), Vec3(0, 0, 1)), 1e-6f);
  for (Vec2 corner : {Vec2(0, 0), Vec2(1, 0), Vec2(0, 1), Vec2(1, 1)})
    EXPECT_LT(distance(equal_area_square_to_sphere(corner), Vec3(0, 0, -1)), 1e-6f);
  EXPECT_LT(distance(equal_area_square_to_sphere({1, 0.5f}), Vec3(1, 0, 0)), 1e-6f);
  EXPECT_LT(distance(equal_area_square_to_sphere({0, 0.5f}), Vec3(-1, 0, 0)), 1e-6f);
  EXPECT_LT(distance(equal_area_square_to_sphere({0.5f, 1}), Vec3(0, 1, 0)), 1e-6f);
  EXPECT_LT(distance(equal_area_square_to_sphere({0.5f, 0}), Vec3(0, -1, 0)), 1e-6f);
}

TEST(EqualAreaMapping, IsAreaPreserving) {
  // Uniform points in the square must land uniformly on the sphere.
  auto sample = [](Pcg32& rng) -> std::optional<DirectionSample> {
    return DirectionSample{equal_area_square_to_sphere(rng.next_2d()), float(kInv4Pi)};
  };
  const auto r = chi2_test(
      sample, [](Vec3) { return float(kInv4Pi); }, options());
  EXPECT_TRUE(r.passed) << r.message;
}

TEST(LatLongMapping, RoundTripsWithRowZeroUp) {
  Pcg32 rng(33, 34);
  for (int i = 0; i < 100000; ++i) {
    const Vec3 d = sample_uniform_sphere(rng.next_2d());
    ASSERT_LT(distance(lat_long_to_sphere(lat_long_from_sphere(d)), d), 2e-5f);
  }
  EXPECT_LT(distance(lat_long_to_sphere({0.3f, 0}), Vec3(0, 0, 1)), 1e-6f);
  EXPECT_LT(distance(lat_long_to_sphere({0, 0.5f}), Vec3(1, 0, 0)), 1e-6f);
  EXPECT_LT(distance(lat_long_to_sphere({0.25f, 0.5f}), Vec3(0, 1, 0)), 1e-6f);
}

// ------------------------------------------------------------------------------------------
// Image environment

// A dim gradient with one bright 3x3 spot at texel (sx, sy).
std::shared_ptr<Image> spot_image(int w, int h, int sx, int sy, float spot = 200.f) {
  auto img = std::make_shared<Image>(w, h);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) img->at(x, y) = Rgb(0.2f + 0.5f * x / w, 0.3f, 0.1f + 0.8f * y / h);
  for (int dy = -1; dy <= 1; ++dy)
    for (int dx = -1; dx <= 1; ++dx)
      img->at((sx + dx + w) % w, clamp(sy + dy, 0, h - 1)) = Rgb(spot, 0.75f * spot, 0.5f * spot);
  return img;
}

struct EnvCase {
  EnvironmentMapping mapping;
  int w, h;
  const char* name;
};
const EnvCase kEnvCases[] = {{EnvironmentMapping::EqualAreaOctahedral, 32, 32, "octahedral"},
                             {EnvironmentMapping::LatLong, 40, 20, "lat-long"}};

Transform env_rotation() { return Transform::rotate(37.f, normalize(Vec3(1, 2, 0.5f))); }

Vec2 env_to_uv(EnvironmentMapping m, Vec3 wl) {
  return m == EnvironmentMapping::EqualAreaOctahedral ? equal_area_sphere_to_square(wl)
                                                      : lat_long_from_sphere(wl);
}
Vec3 env_from_uv(EnvironmentMapping m, Vec2 uv) {
  return m == EnvironmentMapping::EqualAreaOctahedral ? equal_area_square_to_sphere(uv)
                                                      : lat_long_to_sphere(uv);
}

// The map's density is piecewise constant on texels, whose edges cut the chi-square grid's cells
// (see the triangle tests in local_lights_test.cpp), so the test runs in texel space: a
// direction's uv goes to the cylindrical equal-area direction (z' = 1 - 2v, phi' = 2 pi u), whose
// (cos theta, phi) cells are exactly the texels when the grid is h x w. The density there is
// pdf_w * d omega / d omega'.
void check_env_in_texel_space(
    const Light& light, const EnvCase& c, const Transform& to_world,
    const std::function<std::optional<DirectionSample>(Pcg32&)>& sample_world,
    const std::function<float(Vec3)>& pdf_world) {
  const Transform to_light = to_world.inverse();
  const auto jacobian = [&](Vec3 wl) {  // d omega / d omega', omega' has 4 pi du dv
    return c.mapping == EnvironmentMapping::EqualAreaOctahedral
               ? 1.f
               : kPi * safe_sqrt(1 - wl.z * wl.z) / 2;
  };
  auto pdf = [&](Vec3 wp) {
    float phi = std::atan2(wp.y, wp.x);
    if (phi < 0) phi += 2 * kPi;
    const Vec2 uv(std::min(phi * kInv2Pi, kOneMinusEpsilon), clamp((1 - wp.z) / 2, 0.f, 1.f));
    const Vec3 wl = env_from_uv(c.mapping, uv);
    return pdf_world(normalize(to_world.vector(wl))) * jacobian(wl);
  };
  int pdf_mismatches = 0;
  auto sample = [&](Pcg32& rng) -> std::optional<DirectionSample> {
    auto s = sample_world(rng);
    if (!s) return std::nullopt;
    // The reported pdf is checked where it is defined, in world space; in texel space the test
    // reports its own re-evaluation, since a sample on a texel edge may round to either side.
    const float expected = pdf_world(s->w);
    if (std::abs(s->pdf - expected) > 1e-5f * expected) ++pdf_mismatches;
    const Vec2 uv = env_to_uv(c.mapping, normalize(to_light.vector(s->w)));
    const float z = 1 - 2 * uv.y, r = safe_sqrt(1 - z * z), phi = 2 * kPi * uv.x;
    const Vec3 wp(r * std::cos(phi), r * std::sin(phi), z);
    return DirectionSample{wp, pdf(wp)};
  };
  Chi2Options o = options();
  o.theta_bins = c.h;
  o.phi_bins = c.w;
  const auto r = chi2_test(sample, pdf, o);
  EXPECT_TRUE(r.passed) << r.message;
  EXPECT_EQ(pdf_mismatches, 0);
  (void)light;
}

TEST(ImageEnvironment, NeeSamplesMatchPdfInBothMappings) {
  for (const EnvCase& c : kEnvCases) {
    SCOPED_TRACE(c.name);
    const auto light =
        make_image_environment(spot_image(c.w, c.h, c.w / 3, c.h / 4), c.mapping, env_rotation());
    light->preprocess(kSceneCenter, kSceneRadius);
    const Vec3 ref(1, 2, 3);
    int mismatches = 0, radiance_mismatches = 0;
    check_env_in_texel_space(
        *light, c, env_rotation(),
        [&](Pcg32& rng) -> std::optional<DirectionSample> {
          auto s = light->sample_li(ref, rng.next_2d());
          if (!s) return std::nullopt;
          expect_emit_pdfs_match(*light, *s, &mismatches);
          if (!(s->radiance == light->radiance_escaped(s->wi))) ++radiance_mismatches;
          if (s->distance != kInfinity) ++mismatches;
          return DirectionSample{s->wi, s->pdf_w};
        },
        [&](Vec3 w) { return light->pdf_li(ref, w, {}, {}); });
    EXPECT_EQ(mismatches, 0);
    EXPECT_EQ(radiance_mismatches, 0);
  }
}

TEST(ImageEnvironment, EmittedDirectionsMatchPdfLe) {
  for (const EnvCase& c : kEnvCases) {
    SCOPED_TRACE(c.name);
    const auto light =
        make_image_environment(spot_image(c.w, c.h, c.w / 2, c.h / 3), c.mapping, env_rotation());
    light->preprocess(kSceneCenter, kSceneRadius);
    int bad = 0;
    check_env_in_texel_space(
        *light, c, env_rotation(),
        [&](Pcg32& rng) -> std::optional<DirectionSample> {
          auto e = light->sample_le(rng.next_2d(), rng.next_2d());
          if (!e) return std::nullopt;
          float pos, dir;
          light->pdf_le(e->p, e->n, e->dir, &pos, &dir);
          if (pos != e->pdf_pos || std::abs(dir - e->pdf_dir) > 1e-4f * dir) ++bad;
          if (std::abs(dot(e->p - kSceneCenter, e->dir) + kSceneRadius) > 1e-4f) ++bad;
          return DirectionSample{-e->dir, e->pdf_dir};  // the direction toward the light
        },
        [&](Vec3 w) {
          float pos, dir;
          light->pdf_le({}, {}, -w, &pos, &dir);
          return dir;
        });
    EXPECT_EQ(bad, 0);
  }
}

// Solid-angle checks independent of the light's own mapping code: the pdf integrates to 1 over
// the sphere, NEE estimates integral L d omega, and power is pi R^2 times that integral.
TEST(ImageEnvironment, PdfIntegratesToOneAndPowerMatchesQuadrature) {
  for (const EnvCase& c : kEnvCases) {
    SCOPED_TRACE(c.name);
    // A milder spot: the quadrature's error on texel edges that cut its cells grows with contrast.
    const auto light = make_image_environment(spot_image(c.w, c.h, c.w / 4, c.h / 2, 20.f),
                                              c.mapping, env_rotation(), Rgb(2.f, 1.f, 0.5f));
    light->preprocess(kSceneCenter, kSceneRadius);
    const double pdf_integral =
        test::integrate_sphere([&](Vec3 w) { return light->pdf_li({}, w, {}, {}); }, 1024, 2048);
    EXPECT_NEAR(pdf_integral, 1.0, 2e-3);
    const double L_integral = test::integrate_sphere(
        [&](Vec3 w) { return light->radiance_escaped(w).luminance(); }, 1024, 2048);
    const double power = light->power().luminance() / (kPi * sqr(kSceneRadius));
    EXPECT_NEAR(power, L_integral, 3e-3 * L_integral);
    Pcg32 rng(41, 42);
    double sum = 0;
    const int n = 100000;
    for (int i = 0; i < n; ++i) {
      auto s = light->sample_li({}, rng.next_2d());
      if (s) sum += s->radiance.luminance() / s->pdf_w;
    }
    EXPECT_NEAR(sum / n, L_integral, 0.01 * L_integral);
  }
}

TEST(ImageEnvironment, OctahedralDensityIsProportionalToLuminance) {
  const auto light =
      make_image_environment(spot_image(16, 16, 5, 9), EnvironmentMapping::EqualAreaOctahedral, {});
  Pcg32 rng(43, 44);
  const Vec3 w0 = sample_uniform_sphere(rng.next_2d());
  const float ratio = light->pdf_li({}, w0, {}, {}) / light->radiance_escaped(w0).luminance();
  for (int i = 0; i < 1000; ++i) {
    const Vec3 w = sample_uniform_sphere(rng.next_2d());
    ASSERT_NEAR(light->pdf_li({}, w, {}, {}) / light->radiance_escaped(w).luminance(), ratio,
                1e-4f * ratio);
  }
}

// pbrt-v4 conventions: texel (x, y) counts from the left and from the top row; the octahedral
// map's centre is +z and the middle of its top row -y; light_to_world rotates the map.
TEST(ImageEnvironment, OrientationFollowsPbrt) {
  auto img = std::make_shared<Image>(8, 8, Rgb(1.f));
  img->at(4, 0) = Rgb(5.f);  // top row, middle: -y
  img->at(7, 4) = Rgb(7.f);  // right column, middle: +x
  img->at(4, 4) = Rgb(9.f);  // centre: +z (texel 4 touches the centre from below right)
  const auto light = make_image_environment(img, EnvironmentMapping::EqualAreaOctahedral, {});
  EXPECT_EQ(light->radiance_escaped(normalize(Vec3(0.01f, -1, 0))).r, 5.f);
  EXPECT_EQ(light->radiance_escaped(normalize(Vec3(1, 0.01f, 0))).r, 7.f);
  EXPECT_EQ(light->radiance_escaped(normalize(Vec3(0.01f, 0.01f, 1))).r, 9.f);
  // Rotating by 90 degrees about x takes the map's -y to world -z.
  const auto rotated = make_image_environment(img, EnvironmentMapping::EqualAreaOctahedral,
                                              Transform::rotate(90, Vec3(1, 0, 0)));
  EXPECT_EQ(rotated->radiance_escaped(normalize(Vec3(0.01f, 0, -1))).r, 5.f);
  EXPECT_EQ(rotated->radiance_escaped(normalize(Vec3(0.01f, -1, 0))).r, 9.f);  // map's +z

  auto ll = std::make_shared<Image>(8, 4, Rgb(1.f));
  ll->at(0, 0) = Rgb(3.f);  // top row: around +z
  ll->at(2, 2) = Rgb(4.f);  // phi in [90, 135) degrees, theta in [90, 135)
  const auto latlong = make_image_environment(ll, EnvironmentMapping::LatLong, {});
  EXPECT_EQ(latlong->radiance_escaped(normalize(Vec3(1, 0.01f, 5))).r, 3.f);
  EXPECT_EQ(latlong->radiance_escaped(normalize(Vec3(-0.2f, 1, -0.3f))).r, 4.f);
}

}  // namespace
}  // namespace caustica
