// ObjectBegin / ObjectInstance as Embree instances: the object's meshes are stored once, and
// everything downstream (hit records, stored-vertex primitive indices, shape ranges,
// occlusion, images) is what hand-flattened world-space copies give.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <set>
#include <sstream>
#include <string>

#include "image/metrics.h"
#include "pbrt_test_util.h"
#include "test_scenes.h"

namespace caustica {
namespace {

using test::load_text;

// A bumpy sphere as pbrt "trianglemesh" text: rows x 2 rows quads with normals and uv.
std::string bumpy_mesh(int rows) {
  const int cols = 2 * rows;
  std::ostringstream p, n, uv, idx;
  for (int i = 0; i <= rows; ++i)
    for (int j = 0; j <= cols; ++j) {
      const float theta = kPi * float(i) / float(rows), phi = 2 * kPi * float(j) / float(cols);
      const Vec3 d(std::sin(theta) * std::cos(phi), std::sin(theta) * std::sin(phi),
                   std::cos(theta));
      const float r = 1 + 0.08f * std::sin(5 * phi) * std::sin(4 * theta);
      p << d.x * r << ' ' << d.y * r << ' ' << d.z * r << ' ';
      n << d.x << ' ' << d.y << ' ' << d.z << ' ';
      uv << float(j) / float(cols) << ' ' << float(i) / float(rows) << ' ';
    }
  for (int i = 0; i < rows; ++i)
    for (int j = 0; j < cols; ++j) {
      const int a = i * (cols + 1) + j, b = a + cols + 1;
      if (i > 0) idx << a << ' ' << b << ' ' << a + 1 << ' ';
      if (i < rows - 1) idx << a + 1 << ' ' << b << ' ' << b + 1 << ' ';
    }
  return "Shape \"trianglemesh\" \"integer indices\" [ " + idx.str() + "] \"point3 P\" [ " +
         p.str() + "] \"normal N\" [ " + n.str() + "] \"point2 uv\" [ " + uv.str() + "]\n";
}

// The object: a rough-metal bumpy sphere on a diffuse box (no normals, ReverseOrientation).
std::string object_shapes(int rows) {
  return "AttributeBegin\nMaterial \"conductor\" \"float roughness\" 0.3\n" + bumpy_mesh(rows) +
         "AttributeEnd\nAttributeBegin\nMaterial \"diffuse\" \"rgb reflectance\" [0.7 0.5 0.2]\n"
         "ReverseOrientation\nTranslate 0 0 -1.6\nScale 0.6 0.6 0.3\n"
         "Shape \"trianglemesh\" \"integer indices\" [0 2 1 0 3 2 4 5 6 4 6 7 0 1 5 0 5 4 "
         "1 2 6 1 6 5 2 3 7 2 7 6 3 0 4 3 4 7]\n"
         "\"point3 P\" [-1 -1 -1 1 -1 -1 1 1 -1 -1 1 -1 -1 -1 1 1 -1 1 1 1 1 -1 1 1]\n"
         "AttributeEnd\n";
}

// Placement k of a grid^3 lattice in [-1.1, 1.1]^3: rotated, scaled non-uniformly, and every
// seventh mirrored.
std::string placement(int k, int grid) {
  const float spacing = 2.2f / float(grid), s = 0.3f * spacing;
  const int i = k % grid, j = (k / grid) % grid, l = k / (grid * grid);
  std::ostringstream t;
  t << "Translate " << -1.1f + spacing * (float(i) + 0.5f) << ' '
    << -1.1f + spacing * (float(j) + 0.5f) << ' ' << -1.1f + spacing * (float(l) + 0.5f) << '\n'
    << "Rotate " << float(37 * k % 360) << ' ' << std::sin(float(k)) << " 1 "
    << std::cos(float(3 * k)) << '\n'
    << "Scale " << s * (0.8f + 0.05f * float(k % 9)) << ' ' << s << ' '
    << s * (1.2f - 0.04f * float(k % 11)) << '\n';
  if (k % 7 == 0) t << "Scale -1 1 1\n";
  return t.str();
}

// A box with a ceiling light holding grid^3 placements of the object: ObjectInstances, or the
// same shapes written out at each placement (the hand-flattened scene).
std::string lattice_scene(int grid, int rows, bool flatten) {
  std::string s =
      "LookAt 0 -4.1 0.2  0 -3.1 0.17  0 0 1\nCamera \"perspective\" \"float fov\" 45\n"
      "Film \"rgb\" \"integer xresolution\" 32 \"integer yresolution\" 24\n"
      "PixelFilter \"box\"\nWorldBegin\n"
      "AttributeBegin\nAreaLightSource \"diffuse\" \"rgb L\" [12 12 12]\n"
      "Shape \"trianglemesh\" \"integer indices\" [0 1 2 0 2 3]\n"
      "\"point3 P\" [-0.5 -0.5 1.27 0.5 -0.5 1.27 0.5 0.5 1.27 -0.5 0.5 1.27]\nAttributeEnd\n"
      "Material \"diffuse\" \"rgb reflectance\" [0.75 0.75 0.75]\n"
      "Shape \"trianglemesh\" \"integer indices\" [0 1 2 0 2 3 4 6 5 4 7 6 3 2 6 3 6 7]\n"
      "\"point3 P\" [-1.3 -1.3 -1.3 1.3 -1.3 -1.3 1.3 1.3 -1.3 -1.3 1.3 -1.3\n"
      "-1.3 -1.3 1.3 1.3 -1.3 1.3 1.3 1.3 1.3 -1.3 1.3 1.3]\n";
  const std::string shapes = object_shapes(rows);
  if (!flatten) s += "ObjectBegin \"thing\"\n" + shapes + "ObjectEnd\n";
  for (int k = 0; k < grid * grid * grid; ++k)
    s += "AttributeBegin\n" + placement(k, grid) +
         (flatten ? shapes : std::string("ObjectInstance \"thing\"\n")) + "AttributeEnd\n";
  return s;
}

TEST(PbrtInstancing, ThousandPlacementsStoreTheObjectOnce) {
  auto instanced = load_text(lattice_scene(10, 6, false));
  auto flattened = load_text(lattice_scene(10, 6, true));
  const size_t object_triangles = 6 * 12 * 2 - 2 * 12 + 12;  // the sphere less its poles, box
  EXPECT_EQ(instanced->instance_count(), 1000u);
  EXPECT_EQ(flattened->instance_count(), 0u);
  EXPECT_EQ(instanced->triangle_count(), flattened->triangle_count());
  EXPECT_EQ(instanced->stored_triangle_count(), object_triangles + 2 + 6);
  EXPECT_EQ(flattened->stored_triangle_count(), 1000 * object_triangles + 2 + 6);
  const size_t a = instanced->geometry_bytes(), b = flattened->geometry_bytes();
  std::printf(
      "[ info ] 1000 placements of a %zu-triangle object: %.2f MB instanced, %.2f MB "
      "flattened\n",
      object_triangles, a / 1e6, b / 1e6);
  EXPECT_LT(a * 20, b);
  EXPECT_LT(length(instanced->bounds().lo - flattened->bounds().lo), 1e-5f);
  EXPECT_LT(length(instanced->bounds().hi - flattened->bounds().hi), 1e-5f);
}

// The same random streams see the same scene up to float rounding (transforms composed in
// another order, Embree intersecting in object space): only the rare path that rounding
// sends elsewhere differs, far below the noise between seeds.
TEST(PbrtInstancing, ImagesMatchHandFlattenedCopies) {
  auto instanced = load_text(lattice_scene(6, 6, false));
  auto flattened = load_text(lattice_scene(6, 6, true));
  for (const char* integrator : {"pt", "vcm"}) {
    const Image a = test::render_with(*instanced, integrator, 16).image;
    const Image b = test::render_with(*flattened, integrator, 16).image;
    EXPECT_NEAR(mean_ratio(a, b), 1.0, 0.005) << integrator;
    EXPECT_LT(rel_mse(a, b), 1e-3) << integrator;
  }
}

// Camera-ray hits on instances, pixel by pixel.
template <class F>
int for_each_instanced_hit(const Scene& scene, F f) {
  int hits = 0;
  for (int y = 0; y < 24; ++y)
    for (int x = 0; x < 32; ++x) {
      const Ray ray = scene.camera().generate_ray({float(x) + 0.5f, float(y) + 0.5f}, {0.5f, 0.5f});
      SurfaceInteraction si;
      if (!scene.intersect(ray, &si) || si.inst_id == SurfaceInteraction::kNoInstance) continue;
      ++hits;
      f(ray, si);
    }
  return hits;
}

TEST(PbrtInstancing, InteractionAtRebuildsAnInstancedHit) {
  auto scene = load_text(lattice_scene(4, 6, false));
  std::set<uint32_t> range_starts, instances;
  const int hits = for_each_instanced_hit(*scene, [&](const Ray&, const SurfaceInteraction& si) {
    const uint32_t index = scene->primitive_index(si);
    const SurfaceInteraction r = scene->interaction_at(index, si.p, si.wo);
    EXPECT_EQ(r.inst_id, si.inst_id);
    EXPECT_EQ(r.geom_id, si.geom_id);
    EXPECT_EQ(r.prim_id, si.prim_id);
    EXPECT_EQ(scene->primitive_index(r), index);
    EXPECT_LT(length(r.p - si.p), 1e-5f);
    EXPECT_GT(dot(r.ng, si.ng), 0.9999f);
    EXPECT_GT(dot(r.shading.n, si.shading.n), 0.9999f);
    EXPECT_NEAR(r.uv.x, si.uv.x, 1e-4f);
    EXPECT_NEAR(r.uv.y, si.uv.y, 1e-4f);
    EXPECT_EQ(r.material, si.material);
    EXPECT_EQ(r.wo, si.wo);
    const Scene::PrimitiveRange shape = scene->shape_primitives(si);
    EXPECT_TRUE(shape.contains(index));
    EXPECT_TRUE(shape.end - shape.begin == 12u || shape.end - shape.begin == 120u);
    range_starts.insert(shape.begin);
    instances.insert(si.inst_id);
  });
  EXPECT_GT(hits, 100);
  EXPECT_GT(instances.size(), 10u);
  // Each instance's shapes have their own primitive ranges.
  EXPECT_GT(range_starts.size(), instances.size());
}

TEST(PbrtInstancing, InstancesOccludeExactlyWhereTheyAreHit) {
  auto scene = load_text(lattice_scene(4, 6, false));
  const int hits =
      for_each_instanced_hit(*scene, [&](const Ray& ray, const SurfaceInteraction& si) {
        EXPECT_FALSE(scene->occluded({ray.o, ray.d, si.t * 0.999f}));
        EXPECT_TRUE(scene->occluded({ray.o, ray.d, si.t * 1.001f}));
      });
  EXPECT_GT(hits, 100);
}

// Normals through a rotation, a non-uniform scale and a mirror (inverse transpose and the
// winding flip), uv, and ReverseOrientation inside the object, against the flattened copy.
TEST(PbrtInstancing, HitRecordIsTheFlattenedCopys) {
  const std::string place =
      "Translate 0.2 0.1 3\nRotate 30 1 2 3\nScale 0.5 1.5 0.8\n"
      "Scale -1 1 1\n";
  auto instanced = load_text(test::with_camera("ObjectBegin \"o\"\n" + object_shapes(6) +
                                               "ObjectEnd\n" + place + "ObjectInstance \"o\"\n"));
  auto flattened = load_text(test::with_camera(place + object_shapes(6)));
  ASSERT_EQ(instanced->instance_count(), 1u);
  int compared = 0;
  for (float x = -0.4f; x <= 0.4f; x += 0.05f)
    for (float y = -0.6f; y <= 0.6f; y += 0.05f) {
      const Ray ray{{0, 0, 0}, normalize(Vec3(x, y, 1)), kInfinity};
      SurfaceInteraction a, b;
      const bool hit = instanced->intersect(ray, &a);
      ASSERT_EQ(hit, flattened->intersect(ray, &b));
      if (!hit) continue;
      ++compared;
      EXPECT_NEAR(a.t, b.t, 1e-5f * b.t);
      EXPECT_LT(length(a.p - b.p), 1e-5f);
      EXPECT_GT(dot(a.ng, b.ng), 0.9999f);
      EXPECT_GT(dot(a.shading.n, b.shading.n), 0.9999f);
      EXPECT_GT(dot(a.shading.s, b.shading.s), 0.999f);
      EXPECT_NEAR(a.uv.x, b.uv.x, 1e-4f);
      EXPECT_NEAR(a.uv.y, b.uv.y, 1e-4f);
      EXPECT_EQ(a.material != nullptr, b.material != nullptr);
    }
  EXPECT_GT(compared, 100);
}

// An exact sphere stays exact only under a similarity of the whole transform: it is copied
// into world space at each placement, while the object's meshes are instanced.
TEST(PbrtInstancing, SpheresInAnObjectAreCopiedPerPlacement) {
  auto scene = load_text(test::with_camera(
      "ObjectBegin \"o\"\nShape \"sphere\" \"float radius\" 0.5\n"
      "Shape \"trianglemesh\" \"point3 P\" [-1 -1 1  1 -1 1  0 1 1]\nObjectEnd\n"
      "AttributeBegin\nTranslate 0 0 5\nObjectInstance \"o\"\nAttributeEnd\n"
      "AttributeBegin\nTranslate 3 0 5\nScale 2 2 2\nObjectInstance \"o\"\nAttributeEnd\n"));
  EXPECT_EQ(scene->sphere_count(), 2u);
  EXPECT_EQ(scene->instance_count(), 2u);
  EXPECT_EQ(scene->stored_triangle_count(), 1u);
  SurfaceInteraction si;
  ASSERT_TRUE(scene->intersect({{3, 0, 0}, {0, 0, 1}, kInfinity}, &si));
  EXPECT_NEAR(si.p.z, 4, 1e-5f);  // the sphere of radius 1 around (3, 0, 5)
  EXPECT_EQ(si.inst_id, SurfaceInteraction::kNoInstance);
}

}  // namespace
}  // namespace caustica
