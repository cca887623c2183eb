// The benchmark scene with a million triangles: as big as promised, deterministic, listed.
#include <gtest/gtest.h>

#include "core/rng.h"
#include "core/warp.h"
#include "io/builtin_scenes.h"

using namespace caustica;

TEST(ManyTriangles, HasAMillionTrianglesInsideTheCornellBoxAndIsListed) {
  auto scene = make_builtin_scene("many-triangles", 16, 16);
  ASSERT_TRUE(scene);
  EXPECT_GE(scene->triangle_count(), 1000000u);
  // The height field lies within the box: the bounds are the Cornell box's own.
  auto cornell = make_builtin_scene("cornell", 16, 16);
  for (int a = 0; a < 3; ++a) {
    EXPECT_EQ(scene->bounds().lo[a], cornell->bounds().lo[a]) << a;
    EXPECT_EQ(scene->bounds().hi[a], cornell->bounds().hi[a]) << a;
  }
  bool listed = false;
  for (const auto& s : builtin_scenes()) listed = listed || s.name == "many-triangles";
  EXPECT_TRUE(listed);
}

TEST(ManyTriangles, TwoBuildsAreTheSameScene) {
  auto a = make_builtin_scene("many-triangles", 16, 16),
       b = make_builtin_scene("many-triangles", 16, 16);
  Pcg32 rng(3, 4);
  int floor_hits = 0;
  for (int i = 0; i < 2000; ++i) {
    // Rays from the box's centre, downward half mostly landing on the height field.
    const Ray ray{{0.f, 0.f, 0.f}, sample_uniform_sphere(rng.next_2d()), kInfinity};
    SurfaceInteraction sa, sb;
    const bool ha = a->intersect(ray, &sa), hb = b->intersect(ray, &sb);
    ASSERT_EQ(ha, hb);
    if (!ha) continue;
    EXPECT_EQ(sa.t, sb.t);
    EXPECT_EQ(a->primitive_index(sa), b->primitive_index(sb));
    floor_hits += sa.p.z < -1.0f;
  }
  EXPECT_GT(floor_hits, 200);
}
