#include "scene/scene.h"

#include <gtest/gtest.h>
#include <tbb/global_control.h>
#include <tbb/info.h>

#include "core/rng.h"
#include "core/warp.h"
#include "io/builtin_scenes.h"
#include "io/scene_builder.h"
#include "materials/materials.h"

using namespace caustica;

namespace {
std::unique_ptr<Scene> sphere_scene(float radius, Vec3 center) {
  SceneBuilder b;
  b.add_sphere({center, radius}, make_diffuse(make_constant_texture(Rgb(0.5f))));
  CameraParams c;
  c.width = c.height = 8;
  b.set_camera(c);
  return b.build("sphere");
}
}  // namespace

TEST(Scene, SphereIsExactNotFaceted) {
  auto scene = sphere_scene(2.f, {1, 2, 3});
  Pcg32 r(1, 2);
  for (int i = 0; i < 1000; ++i) {
    const Vec3 d = sample_uniform_sphere(r.next_2d());
    SurfaceInteraction si;
    ASSERT_TRUE(scene->intersect({{1, 2, 3}, d, kInfinity}, &si));
    EXPECT_NEAR(distance(si.p, {1, 2, 3}), 2.f, 2e-6f);
    EXPECT_NEAR(si.t, 2.f, 1e-5f);
    EXPECT_NEAR(dot(si.ng, d), 1.f, 1e-5f);  // outward normal
  }
}

TEST(Scene, RaysLeavingASurfaceDoNotHitItAgain) {
  // From inside a sphere, a ray spawned at a hit toward the inside must reach the far side,
  // and one spawned outward must escape: the classic self-intersection failure modes.
  auto scene = sphere_scene(1.f, {0, 0, 0});
  Pcg32 r(3, 4);
  int failures = 0;
  for (int i = 0; i < 20000; ++i) {
    const Vec3 d = sample_uniform_sphere(r.next_2d());
    SurfaceInteraction si;
    ASSERT_TRUE(scene->intersect({{0.1f, -0.2f, 0.05f}, d, kInfinity}, &si));
    Vec3 inward = sample_cosine_hemisphere(r.next_2d());
    inward = Frame::from_normal(-si.ng).to_world(inward);
    SurfaceInteraction next;
    if (!scene->intersect(si.spawn_ray(inward), &next) || next.t < 1e-3f) ++failures;
    if (scene->intersect(si.spawn_ray(si.ng), &next)) ++failures;
  }
  EXPECT_EQ(failures, 0);
}

TEST(Scene, TriangleHitHasWindingNormalUvAndMaterial) {
  SceneBuilder b;
  TriangleMesh m;
  m.positions = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}};
  m.uvs = {{0, 0}, {1, 0}, {0, 1}};
  m.indices = {0, 1, 2};
  auto mat = make_diffuse(make_constant_texture(Rgb(0.5f)));
  b.add_mesh(m, mat);
  CameraParams c;
  b.set_camera(c);
  auto scene = b.build("tri");
  SurfaceInteraction si;
  ASSERT_TRUE(scene->intersect({{0.25f, 0.25f, 1}, {0, 0, -1}, kInfinity}, &si));
  EXPECT_NEAR(si.ng.z, 1, 1e-6);  // cross(p1 - p0, p2 - p0) = +z
  EXPECT_NEAR(si.uv.x, 0.25f, 1e-6);
  EXPECT_NEAR(si.uv.y, 0.25f, 1e-6);
  EXPECT_EQ(si.material, mat.get());
  EXPECT_FALSE(scene->occluded({{0.25f, 0.25f, 1}, {0, 0, -1}, 0.5f}));
  EXPECT_TRUE(scene->occluded({{0.25f, 0.25f, 1}, {0, 0, -1}, 1.5f}));
  EXPECT_GT(scene->rays_traced(), 2u);
}

TEST(Scene, EmissiveTrianglesBecomeAreaLights) {
  auto scene = make_builtin_scene("cornell-glass", 16, 16);
  EXPECT_EQ(scene->lights().size(), 2u);  // the light quad's two triangles
  SurfaceInteraction si;
  // Straight up from the floor centre we hit the light quad from below (its emitting side).
  ASSERT_TRUE(scene->intersect({{0, 0, -1.2f}, {0, 0, 1}, kInfinity}, &si));
  ASSERT_NE(si.area_light, nullptr);
  EXPECT_NEAR(si.area_light->radiance(si.p, si.ng, si.uv, si.wo).r, 25.0333f, 1e-3);
  // Its back (top) side does not emit.
  EXPECT_TRUE(si.area_light->radiance(si.p, si.ng, si.uv, -si.wo).is_black());
}

TEST(Scene, ShadowRaysFromAPlaneThroughTheOriginDoNotHitIt) {
  // Regression: a floor at y = 0 has a zero error bound along its normal; spawned rays must
  // still leave it (material-spheres rendered a black floor before the fix).
  SceneBuilder b;
  TriangleMesh floor;
  floor.positions = {{-5, 0, -5}, {5, 0, -5}, {5, 0, 5}, {-5, 0, 5}};
  floor.indices = {0, 2, 1, 0, 3, 2};
  b.add_mesh(floor, make_diffuse(make_constant_texture(Rgb(0.5f))));
  CameraParams c;
  b.set_camera(c);
  auto scene = b.build("floor");
  Pcg32 r(8, 8);
  int blocked = 0;
  for (int i = 0; i < 2000; ++i) {
    const Vec3 o(r.next_float() * 4 - 2, 1, r.next_float() * 4 - 2);
    SurfaceInteraction si;
    ASSERT_TRUE(scene->intersect({o, {0, -1, 0}, kInfinity}, &si));
    ASSERT_EQ(si.p.y, 0.f);
    const Vec3 light(r.next_float() * 2 - 1, 2, r.next_float() * 2 - 1);
    blocked += scene->occluded(si.spawn_ray_to(light));
    blocked += scene->occluded(si.spawn_ray(normalize(Vec3(0.3f, 1, 0.2f))));
  }
  EXPECT_EQ(blocked, 0);
}

TEST(Scene, BuildingASceneDoesNotCapTheRenderersParallelism) {
  // Regression: creating the Embree device with "threads=1" installed a process-wide
  // tbb::global_control, and every render ran on one thread.
  auto scene = make_builtin_scene("cornell-glass", 8, 8);
  EXPECT_EQ(tbb::global_control::active_value(tbb::global_control::max_allowed_parallelism),
            size_t(tbb::info::default_concurrency()));
}
