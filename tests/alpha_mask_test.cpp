// pbrt-v4's alpha masks on shapes ("float alpha" / "texture alpha"): closest-hit and shadow rays
// ignore a hit where the mask is 0 and keep one where it is in (0, 1) with that probability, by a
// hash of the ray (scene/scene.cpp, alpha_filter).
#include <gtest/gtest.h>

#include <cmath>

#include "core/rng.h"
#include "core/warp.h"
#include "geometry/interaction.h"
#include "pbrt_test_util.h"
#include "scene/scene.h"

namespace caustica {
namespace {

using test::load_text;
using test::with_camera;

// An 8 x 1 single-channel PFM, four texels 0 then four 1: with bilinear lookup and repeat
// wrapping the mask is 0 for s in [1/16, 7/16] and 1 for s in [9/16, 15/16].
std::string mask_pfm(const test::TempDir& dir) {
  return test::write_row_pfm(dir, "mask.pfm", {0, 0, 0, 0, 1, 1, 1, 1});
}

// The mask as the float texture "mask", before `world`, loaded from a file in dir.
std::unique_ptr<Scene> load_with_mask(const test::TempDir& dir, const std::string& world) {
  return test::load_file_text(
      dir, "alpha.pbrt",
      with_camera("Texture \"mask\" \"float\" \"imagemap\" \"string filename\" \"" + mask_pfm(dir) +
                  "\"\n" + world));
}

// A unit quad at z = 0 with uv = (x, y), and a diffuse floor at z = -1 behind it.
const char* kQuadAndFloor =
    "Shape \"trianglemesh\" \"point3 P\" [0 0 0  1 0 0  1 1 0  0 1 0] "
    "\"point2 uv\" [0 0  1 0  1 1  0 1] \"integer indices\" [0 1 2  0 2 3]";
const char* kFloor =
    "\nShape \"trianglemesh\" \"point3 P\" [-5 -5 -1  5 -5 -1  5 5 -1  -5 5 -1] "
    "\"integer indices\" [0 1 2  0 2 3]\n";

TEST(AlphaMask, TexturedMaskLetsRaysThroughWhereItIsZero) {
  test::TempDir dir;
  auto scene =
      load_with_mask(dir, std::string(kQuadAndFloor) + " \"texture alpha\" \"mask\"" + kFloor);
  EXPECT_TRUE(test::captured_warnings().empty());
  SurfaceInteraction si;
  ASSERT_TRUE(scene->intersect({{0.2f, 0.5f, 1}, {0, 0, -1}, kInfinity}, &si));
  EXPECT_NEAR(si.p.z, -1, 1e-4f);  // through the masked part, onto the floor
  ASSERT_TRUE(scene->intersect({{0.7f, 0.5f, 1}, {0, 0, -1}, kInfinity}, &si));
  EXPECT_NEAR(si.p.z, 0, 1e-4f);
  // Shadow rays alike.
  EXPECT_FALSE(scene->occluded({{0.2f, 0.5f, 1}, {0, 0, -1}, 1.5f}));
  EXPECT_TRUE(scene->occluded({{0.7f, 0.5f, 1}, {0, 0, -1}, 1.5f}));
}

TEST(AlphaMask, AFractionalMaskKeepsThatShareOfHitsAndDecidesAlikeForOneRay) {
  auto scene = load_text(with_camera(std::string(kQuadAndFloor) + " \"float alpha\" 0.3" + kFloor));
  Pcg32 rng(3, 4);
  const int n = 4000;
  int on_quad = 0;
  for (int i = 0; i < n; ++i) {
    const Vec3 o(0.2f + 0.6f * rng.next_float(), 0.2f + 0.6f * rng.next_float(), 1);
    const Ray r{o, {0, 0, -1}, kInfinity};
    SurfaceInteraction a, b;
    ASSERT_TRUE(scene->intersect(r, &a));
    ASSERT_TRUE(scene->intersect(r, &b));
    EXPECT_EQ(a.p.z, b.p.z);
    EXPECT_EQ(scene->occluded({o, {0, 0, -1}, 1.5f}), a.p.z > -0.5f);
    on_quad += a.p.z > -0.5f;
  }
  EXPECT_NEAR(double(on_quad) / n, 0.3, 0.03);
}

TEST(AlphaMask, OpaqueAndTransparentConstants) {
  auto opaque = load_text(with_camera(std::string(kQuadAndFloor) + " \"float alpha\" 1" + kFloor));
  SurfaceInteraction si;
  ASSERT_TRUE(opaque->intersect({{0.5f, 0.5f, 1}, {0, 0, -1}, kInfinity}, &si));
  EXPECT_NEAR(si.p.z, 0, 1e-4f);
  auto gone = load_text(with_camera(std::string(kQuadAndFloor) + " \"float alpha\" 0" + kFloor));
  EXPECT_EQ(gone->triangle_count(), 2u);  // only the floor
}

TEST(AlphaMask, AMaskedSphereIsTessellatedWithItsUv) {
  test::TempDir dir;
  auto scene = load_with_mask(dir, "Shape \"sphere\" \"texture alpha\" \"mask\"\n");
  EXPECT_TRUE(test::captured_warnings().empty());
  EXPECT_EQ(scene->sphere_count(), 0u);
  EXPECT_GT(scene->triangle_count(), 0u);
  // u = phi / 2 pi: at phi = 0.4 pi (u = 0.2) the mask is 0, at phi = 1.4 pi (u = 0.7) it is 1.
  // A ray through the centre from the first side passes it and stops at the second.
  const Vec3 side(std::cos(0.4f * kPi), std::sin(0.4f * kPi), 0.02f);
  SurfaceInteraction si;
  ASSERT_TRUE(scene->intersect({side * 5.f, -side, kInfinity}, &si));
  EXPECT_NEAR(dot(si.p, side), -1, 1e-2f);
}

}  // namespace
}  // namespace caustica
