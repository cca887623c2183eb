// The raw Embree bound (scene/ray_bench.h) and the ray counters the bench weighs it with.
#include "scene/ray_bench.h"

#include <gtest/gtest.h>

#include <cmath>

#include "io/builtin_scenes.h"

using namespace caustica;

TEST(RayBench, IncoherentRaysStartOnSurfacesAndPointEverywhere) {
  auto scene = make_builtin_scene("cornell", 32, 32);
  const std::vector<Ray> rays = make_incoherent_rays(*scene, 4000, 7);
  ASSERT_EQ(rays.size(), 4000u);
  const Bounds3 box = scene->bounds();
  Vec3 mean_direction(0, 0, 0);
  for (const Ray& r : rays) {
    EXPECT_NEAR(length(r.d), 1.f, 1e-4f);
    for (int a = 0; a < 3; ++a) {
      EXPECT_GE(r.o[a], box.lo[a] - 1e-3f);
      EXPECT_LE(r.o[a], box.hi[a] + 1e-3f);
    }
    mean_direction += r.d;
  }
  // From all six walls and two spheres, the directions cancel out more or less: coherent rays
  // (all from one wall, or camera rays) would have a mean of length near 1.
  EXPECT_LT(length(mean_direction / float(rays.size())), 0.5f);
  // Deterministic for a seed.
  const std::vector<Ray> again = make_incoherent_rays(*scene, 4000, 7);
  EXPECT_EQ(again[1234].d.x, rays[1234].d.x);
}

TEST(RayBench, RawKernelsTraceEveryRayAndShadowRaysBeforeTheHitAreFree) {
  auto scene = make_builtin_scene("cornell", 32, 32);
  const std::vector<Ray> rays = make_incoherent_rays(*scene, 20000, 1);
  const uint64_t counted_before = scene->rays_traced();
  const RayBenchResult r = measure_raw_rays(*scene, rays);
  EXPECT_EQ(scene->rays_traced(), counted_before) << "raw rays are not the renderer's rays";
  EXPECT_EQ(r.rays, rays.size());
  // The box is open only toward the camera: most rays from its walls hit something.
  EXPECT_GT(r.hits, rays.size() / 2);
  EXPECT_LT(r.occluded, rays.size() / 1000 + 1);
  EXPECT_GT(r.intersect_rays_per_second, 0);
  EXPECT_GT(r.occluded_rays_per_second, 0);
  // The mixed bound lies between the two rates.
  const double mixed = r.mixed_rays_per_second(0.5);
  EXPECT_GE(mixed, std::min(r.intersect_rays_per_second, r.occluded_rays_per_second) * 0.999);
  EXPECT_LE(mixed, std::max(r.intersect_rays_per_second, r.occluded_rays_per_second) * 1.001);
}

TEST(RayBench, OcclusionRaysAreCountedApart) {
  auto scene = make_builtin_scene("cornell", 32, 32);
  const uint64_t all = scene->rays_traced(), occlusion = scene->occlusion_rays_traced();
  SurfaceInteraction si;
  const Ray up{{0, 0, 0}, {0, 0, 1}, kInfinity};
  EXPECT_TRUE(scene->intersect(up, &si));
  EXPECT_TRUE(scene->occluded(up));
  EXPECT_TRUE(scene->occluded(up));
  EXPECT_EQ(scene->rays_traced() - all, 3u);
  EXPECT_EQ(scene->occlusion_rays_traced() - occlusion, 2u);
}
