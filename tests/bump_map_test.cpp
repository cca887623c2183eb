// Bump mapping (pbrt-v4's material "displacement", materials/bump_mapped.cpp) and the shading
// derivatives it displaces along (SurfaceInteraction::dpdu / dpdv, as pbrt-v4 has them).
#include <gtest/gtest.h>

#include <cmath>

#include "core/arena.h"
#include "geometry/interaction.h"
#include "materials/material.h"
#include "pbrt_test_util.h"
#include "scene/scene.h"

namespace caustica {
namespace {

using test::load_text;
using test::with_camera;

SurfaceInteraction hit(const Scene& scene, Vec3 o, Vec3 d) {
  SurfaceInteraction si;
  EXPECT_TRUE(scene.intersect({o, normalize(d), kInfinity}, &si)) << "ray missed";
  return si;
}

// A 2 x 1 single-channel PFM holding 0 and 1: bilinear between the texel centres at s = 1/4 and
// 3/4, the texture rises by 2 per unit of s there.
std::string ramp_pfm(const test::TempDir& dir) {
  return test::write_row_pfm(dir, "ramp.pfm", {0, 1});
}

// A quad over x in [0, 2], y in [0, 1] with uv = (x / 2, y): dp/du = (2, 0, 0), dp/dv = (0, 1, 0).
const char* kQuad =
    "Shape \"trianglemesh\" \"point3 P\" [0 0 0  2 0 0  2 1 0  0 1 0] "
    "\"point2 uv\" [0 0  1 0  1 1  0 1] \"integer indices\" [0 1 2  0 2 3]\n";

TEST(BumpMapping, ShadingNormalFollowsTheDisplacementsSlope) {
  test::TempDir dir;
  const std::string texture = "Texture \"ramp\" \"float\" \"imagemap\" \"string filename\" \"" +
                              ramp_pfm(dir) + "\" \"float scale\" 0.5\n";
  auto scene = test::load_file_text(
      dir, "bump.pbrt",
      with_camera(texture + "Material \"diffuse\" \"texture displacement\" \"ramp\"\n" + kQuad));
  EXPECT_TRUE(test::captured_warnings().empty());
  const SurfaceInteraction si = hit(*scene, {1, 0.5f, 1}, {0, 0, -1});
  EXPECT_NEAR(si.dpdu.x, 2, 1e-4f);
  EXPECT_NEAR(si.dpdv.y, 1, 1e-4f);
  ASSERT_NE(si.material, nullptr);
  ScratchArena arena;
  const Bsdf bsdf = si.material->bsdf(si, arena);
  // d rises by 0.5 x 2 = 1 per unit of u: dp/du' = (2, 0, 1), dp/dv' = (0, 1, 0), and the
  // shading normal is cross of them, (-1, 0, 2) / sqrt(5).
  const Vec3 n = bsdf.shading().n;
  EXPECT_NEAR(n.x, -1 / std::sqrt(5.f), 2e-3f);
  EXPECT_NEAR(n.y, 0, 1e-4f);
  EXPECT_NEAR(n.z, 2 / std::sqrt(5.f), 2e-3f);
  EXPECT_GT(si.ng.z, 0.999f);  // the geometry itself is unchanged
  // Without displacement the shading normal is the geometric one.
  auto flat = load_text(with_camera("Material \"diffuse\"\n" + std::string(kQuad)));
  const SurfaceInteraction fs = hit(*flat, {1, 0.5f, 1}, {0, 0, -1});
  EXPECT_GT(fs.material->bsdf(fs, arena).shading().n.z, 0.99999f);
}

TEST(BumpMapping, AConstantDisplacementChangesNothing) {
  auto scene = load_text(
      with_camera("Material \"conductor\" \"float displacement\" 0.3\n" + std::string(kQuad)));
  EXPECT_TRUE(test::captured_warnings().empty());
  const SurfaceInteraction si = hit(*scene, {1, 0.5f, 1}, {0, 0, -1});
  ScratchArena arena;
  EXPECT_GT(si.material->bsdf(si, arena).shading().n.z, 0.99999f);
  EXPECT_STREQ(si.material->name(), "conductor");
}

// pbrt-v4's sphere: n = cross(dp/du, dp/dv) points outward, with v = 1 - theta / pi.
TEST(BumpMapping, SphereDerivativesAreThoseOfItsParameterisation) {
  auto scene = load_text(with_camera("Shape \"sphere\" \"float radius\" 2\n"));
  const Vec3 d = normalize(Vec3(-1, -0.5f, -0.7f));
  const SurfaceInteraction si = hit(*scene, -d * 10.f, d);
  const Vec3 n = normalize(cross(si.dpdu, si.dpdv));
  EXPECT_NEAR(dot(n, si.ng), 1, 1e-4f);
  // Finite differences of the hit point along u and v agree with the derivatives.
  const float theta = kPi * (1 - si.uv.y), phi = 2 * kPi * si.uv.x, h = 1e-3f;
  auto point = [](float th, float ph) {
    return Vec3(std::sin(th) * std::cos(ph), std::sin(th) * std::sin(ph), std::cos(th)) * 2.f;
  };
  const Vec3 du = (point(theta, phi + 2 * kPi * h) - point(theta, phi)) / h;
  const Vec3 dv = (point(theta - kPi * h, phi) - point(theta, phi)) / h;
  EXPECT_NEAR(length(du - si.dpdu), 0, 0.02f * length(si.dpdu));
  EXPECT_NEAR(length(dv - si.dpdv), 0, 0.02f * length(si.dpdv));
}

// With per-vertex normals: dp/du made perpendicular to the shading normal, dp/dv = cross(n, it).
TEST(BumpMapping, SmoothMeshTangentsAreMadePerpendicular) {
  auto scene =
      load_text(with_camera("Shape \"trianglemesh\" \"point3 P\" [0 0 0  2 0 0  2 1 0  0 1 0] "
                            "\"point2 uv\" [0 0  1 0  1 1  0 1] \"integer indices\" [0 1 2  0 2 3] "
                            "\"normal N\" [0.3 0 1  0.3 0 1  0.3 0 1  0.3 0 1]\n"));
  const SurfaceInteraction si = hit(*scene, {1, 0.5f, 1}, {0, 0, -1});
  const Vec3 ns = si.shading.n;
  EXPECT_NEAR(dot(si.dpdu, ns), 0, 1e-5f);
  EXPECT_NEAR(dot(si.dpdv, ns), 0, 1e-5f);
  EXPECT_NEAR(length(si.dpdv), length(si.dpdu), 1e-5f);
  EXPECT_GT(dot(normalize(cross(si.dpdu, si.dpdv)), ns), 0.9999f);
}

}  // namespace
}  // namespace caustica
