// Corners of the bidirectional core that an independent review found wrong: a thin lens at the
// film border, merging exact at any scene extent, shading normals in merging, hash-grid
// neighbours visited once, MIS sums that overflow, and light paths shared by pixels.
#include <gtest/gtest.h>

#include <cmath>
#include <map>
#include <set>

#include "core/rng.h"
#include "geometry/texture.h"
#include "integrators/bidir/hash_grid.h"
#include "integrators/bidir/light_path_assignment.h"
#include "integrators/bidir/mis.h"
#include "io/builtin_scenes.h"
#include "io/scene_builder.h"
#include "lights/lights.h"
#include "materials/materials.h"
#include "test_scenes.h"

using namespace caustica;
using namespace caustica::test;

namespace {

MaterialPtr diffuse(Rgb albedo) { return make_diffuse(make_constant_texture(albedo)); }

TriangleMesh quad(Vec3 a, Vec3 b, Vec3 c, Vec3 d) {
  TriangleMesh m;
  m.positions = {a, b, c, d};
  m.indices = {0, 1, 2, 0, 2, 3};
  return m;
}

// Mean over the pixels within `band` of the border, and over the rest.
struct BandMeans {
  double border = 0, inside = 0;
};
BandMeans band_means(const Image& img, int band) {
  double b = 0, i = 0;
  size_t nb = 0, ni = 0;
  for (int y = 0; y < img.height(); ++y)
    for (int x = 0; x < img.width(); ++x) {
      const bool border =
          x < band || y < band || x >= img.width() - band || y >= img.height() - band;
      (border ? b : i) += img.at(x, y).average();
      ++(border ? nb : ni);
    }
  return {b / double(nb), i / double(ni)};
}

}  // namespace

// --- 1. Thin lens -------------------------------------------------------------------------------

// A thin-lens camera inside a uniform environment with an albedo-1 sphere: every pixel is 1, the
// border included, for every integrator (the camera pdf used to be tested from the lens centre:
// bidirectional camera paths near the border were dropped, a black band about 4 px wide).
TEST(BidirThinLens, EnvironmentFurnaceIsOneUpToTheBorder) {
  SceneBuilder b;
  b.add_sphere({{0, 3, 0}, 1.f}, diffuse(Rgb(1.f)));
  b.add_light(make_uniform_environment(Rgb(1.f)));
  CameraParams c;
  c.camera_to_world = Transform::look_at({0, 0, 0}, {0, 1, 0}, {0, 0, 1}).inverse();
  c.width = c.height = 24;
  c.fov_degrees = 40;
  c.lens_radius = 0.4f;
  c.focal_distance = 2.5f;
  b.set_camera(c);
  auto scene = b.build("thin-lens-env-furnace");
  IntegratorSettings s;
  s.max_depth = 50;
  for (const char* name : {"pt", "lt", "bpt", "vcm"}) {
    const auto [border, se] = over_seeds(4, [&](uint64_t seed) {
      s.seed = seed;
      return band_means(render_with(*scene, name, 4, s).image, 4).border;
    });
    std::printf("[ thin lens ] %-4s border mean %.4f se %.4f\n", name, border, se);
    EXPECT_NEAR(border, 1.0, 3 * se + 2e-3) << name;
  }
}

// --- 2. Merging exact at any scene extent ------------------------------------------------------

namespace {
// A floor under a point light; optionally a 1 mm sphere a million units away, which used to make
// the fixed-point step of stored photon positions larger than the merge radius.
std::unique_ptr<Scene> floor_under_point_light(bool far_sphere) {
  SceneBuilder b;
  b.add_mesh(quad({-2, 0, -2}, {-2, 0, 2}, {2, 0, 2}, {2, 0, -2}), diffuse(Rgb(0.8f)));
  b.add_light(make_point_light({0, 1.5f, 0}, Rgb(4.f)));
  if (far_sphere) b.add_sphere({{1e6f, 1e6f, 1e6f}, 1e-3f}, diffuse(Rgb(0.5f)));
  CameraParams c;
  c.camera_to_world = Transform::look_at({0, 2, -2.5f}, {0, 0, 0}, {0, 1, 0}).inverse();
  c.width = c.height = 24;
  c.fov_degrees = 35;
  b.set_camera(c);
  return b.build(far_sphere ? "floor-far-sphere" : "floor");
}
}  // namespace

TEST(BidirExactPositions, FarAwayObjectDoesNotChangeMerging) {
  IntegratorSettings s;
  s.bidir.radius = 0.01f;
  s.max_depth = 3;
  for (const char* name : {"bpm", "vcm", "ppm"}) {
    const Image near_only = render_with(*floor_under_point_light(false), name, 2, s).image;
    const Image with_far = render_with(*floor_under_point_light(true), name, 2, s).image;
    const double mean = pixel_stats(near_only).mean;
    ASSERT_GT(mean, 0.05) << name << ": the floor is lit";
    double max_diff = 0;
    for (size_t i = 0; i < near_only.pixel_count(); ++i)
      max_diff =
          std::max(max_diff, double(std::abs(near_only[i].average() - with_far[i].average())));
    EXPECT_LT(max_diff, 1e-6 * std::max(1.0, mean)) << name << " mean " << mean;
  }
}

// --- 3. Shading normals in merging --------------------------------------------------------------

namespace {
// A floor whose interpolated shading normals lean 35 degrees away from its geometric normal, lit
// by a small quad light: merging must weigh photons with |ns . wi| / |ng . wi| as NEE does.
std::unique_ptr<Scene> floor_with_tilted_normals() {
  SceneBuilder b;
  TriangleMesh floor = quad({-5, 0, -5}, {-5, 0, 5}, {5, 0, 5}, {5, 0, -5});
  const Vec3 n = normalize(Vec3(std::sin(radians(35.f)), std::cos(radians(35.f)), 0));
  floor.normals = {n, n, n, n};
  b.add_mesh(floor, diffuse(Rgb(0.7f)));
  const AreaEmission e{Rgb(20.f), false};
  b.add_mesh(quad({-0.3f, 2, -0.3f}, {0.3f, 2, -0.3f}, {0.3f, 2, 0.3f}, {-0.3f, 2, 0.3f}),
             diffuse(Rgb(0.f)), &e);
  CameraParams c;
  c.camera_to_world = Transform::look_at({0, 1.5f, -3}, {0, 0, 0.5f}, {0, 1, 0}).inverse();
  c.width = c.height = 24;
  c.fov_degrees = 30;
  b.set_camera(c);
  return b.build("tilted-normals");
}
}  // namespace

TEST(BidirShadingNormals, MergingAgreesWithPathTracing) {
  auto scene = floor_with_tilted_normals();
  IntegratorSettings s;
  s.max_depth = 3;
  s.bidir.radius = 0.05f;  // the floor is flat: no curvature bias, only the light's gradient
  s.bidir.light_paths = 16384;
  auto mean_of = [&](const char* name, int spp) {
    return over_seeds(4, [&](uint64_t seed) {
      s.seed = seed;
      return pixel_stats(render_with(*scene, name, spp, s).image).mean;
    });
  };
  const auto [pt, pt_se] = mean_of("pt", 64);
  for (const char* name : {"bpm", "vcm", "bpt"}) {
    const auto [m, se] = mean_of(name, 16);
    std::printf("[ shading normals ] %-4s mean %.5f se %.5f (pt %.5f se %.5f)\n", name, m, se, pt,
                pt_se);
    // 3 standard errors, plus 1% for the merge kernel's bias.
    EXPECT_NEAR(m, pt, 3 * std::hypot(se, pt_se) + 0.01 * pt) << name;
  }
}

// --- 4. Hash grid -------------------------------------------------------------------------------

// With a tiny table, neighbouring cells share buckets; every vertex within the radius must still
// be reported exactly once (a bucket visited twice used to count its photons twice).
TEST(BidirHashGrid, ReportsEachNeighbourOnceEvenWhenCellsCollide) {
  Pcg32 rng(3, 4);
  std::vector<bidir::LightVertex> vertices;
  for (int i = 0; i < 2000; ++i) {
    bidir::LightVertexData v;
    v.p = {rng.next_float(), rng.next_float(), rng.next_float() * 0.1f};
    v.wo = {0, 0, 1};
    vertices.push_back(bidir::pack_light_vertex(v));
  }
  const float radius = 0.05f;
  for (uint32_t table : {1u, 2u, 8u, 0u}) {
    bidir::HashGrid grid;
    grid.build(vertices, radius, table);
    for (int q = 0; q < 200; ++q) {
      const Vec3 p(rng.next_float(), rng.next_float(), rng.next_float() * 0.1f);
      std::map<uint32_t, int> seen;
      grid.for_each_near(p, vertices, [&](uint32_t index, Vec3) { ++seen[index]; });
      size_t expected = 0;
      for (const auto& v : vertices) expected += distance_squared(v.p(), p) <= radius * radius;
      ASSERT_EQ(seen.size(), expected) << "table " << table;
      for (const auto& [index, n] : seen)
        ASSERT_EQ(n, 1) << "vertex " << index << " table " << table;
    }
  }
}

// Far from the vertices' bounds, cell coordinates must neither overflow nor lose the cell.
TEST(BidirHashGrid, FindsNeighboursFarFromTheOrigin) {
  std::vector<bidir::LightVertex> vertices;
  for (float x : {-1e6f, 0.f, 1e6f}) {
    bidir::LightVertexData v;
    v.p = {x, 0.5f, 0.25f};
    vertices.push_back(bidir::pack_light_vertex(v));
  }
  bidir::HashGrid grid;
  grid.build(vertices, 1e-3f);
  for (const auto& v : vertices) {
    int found = 0;
    grid.for_each_near(v.p() + Vec3(0, 4e-4f, 0), vertices, [&](uint32_t, Vec3) { ++found; });
    EXPECT_EQ(found, 1) << v.p().x;
  }
}

// --- 5. MIS sums that overflow
// --------------------------------------------------------------------

// An infinite partial sum (a grazing cosine in a denominator) times the zero pdf of a technique
// that cannot make the path: that term is 0, not NaN, and the other techniques keep their weight.
TEST(BidirMisLimits, ZeroTimesInfiniteSumIsTheLimitNotAZeroWeight) {
  const bidir::MisRules rules(MisHeuristic::Balance, true, false, 100.f, 0.f);
  const float inf = std::numeric_limits<float>::infinity();
  // Both vertices beyond their subpath's first: dVCM stands for a connection (count 1).
  const bidir::MisSums light{inf, 0.f, 2.f, 0.f, false}, camera{0.5f, 0.f, 0.25f, 0.f, false};
  // The camera side cannot sample the light vertex (pdf 0): w_light = 0; w_camera finite.
  const float w = rules.connect(light, camera, /*camera_pdf_a=*/0.f, 1.f, /*light_pdf_a=*/2.f, 1.f)
                      .weight(rules.counts());
  const float w_camera = 2.f * (0.5f + 0.25f * 1.f);
  EXPECT_FLOAT_EQ(w, 1.f / (1.f + w_camera));
  // Sums reaching a grazing vertex: 0 * (1 / cos 0) stays 0, not NaN.
  bidir::MisSums s;
  rules.hit(s, 1.f, 0.f);
  EXPECT_EQ(s.vcm, 0.f);
  EXPECT_EQ(s.conn, 0.f);
  // A genuinely infinite sum of other techniques gives the current one weight 0.
  EXPECT_EQ(rules.connect(light, camera, 1.f, 1.f, 2.f, 1.f).weight(rules.counts()), 0.f);
}

// --- 6. Light paths fewer than pixels -----------------------------------------------------------

TEST(BidirLightPathAssignment, IdentityWithOnePathPerPixel) {
  const bidir::LightPathAssignment a(1000, 1000, 3, 7);
  for (uint64_t p = 0; p < 1000; ++p) ASSERT_EQ(a.light_path(p), p);
}

TEST(BidirLightPathAssignment, BalancedScatteredAndNewEachIteration) {
  const uint64_t pixels = 32 * 32, paths = 300;
  const bidir::LightPathAssignment a(pixels, paths, 0, 1), b(pixels, paths, 1, 1);
  std::vector<std::vector<uint64_t>> users(paths);
  int same_next_iteration = 0;
  for (uint64_t p = 0; p < pixels; ++p) {
    const uint64_t l = a.light_path(p);
    ASSERT_LT(l, paths);
    users[l].push_back(p);
    same_next_iteration += a.light_path(p) == b.light_path(p);
  }
  // Balanced: floor or ceil of P / N pixels per path.
  for (const auto& u : users) {
    EXPECT_GE(u.size(), pixels / paths);
    EXPECT_LE(u.size(), pixels / paths + 1);
  }
  // No regular pattern: pixels sharing a path are not a fixed distance apart (pixel % N made
  // every pair exactly a multiple of N apart).
  std::map<uint64_t, int> strides;
  int pairs = 0;
  for (const auto& u : users)
    for (size_t i = 1; i < u.size(); ++i, ++pairs) ++strides[u[i] - u[i - 1]];
  int most_common = 0;
  for (const auto& [stride, n] : strides) most_common = std::max(most_common, n);
  EXPECT_LT(most_common, pairs / 10) << "a dominant stride between pixels sharing a light path";
  // A new shuffle every iteration: about 1 / N of the pixels keep their path by chance.
  EXPECT_LT(same_next_iteration, int(pixels / 20));
}

TEST(BidirLightPathAssignment, FewerLightPathsThanPixelsStayUnbiased) {
  FurnaceParams p;
  p.albedo = 0.5f;
  p.emission = 1.5f;
  auto scene = make_furnace_scene(p, 24, 24);
  IntegratorSettings s;
  s.max_depth = 200;
  s.bidir.radius = 0.05f;
  s.bidir.light_paths = 24 * 24 / 3;
  for (const char* name : {"bpt", "vcm"}) {
    const auto [m, se] = over_seeds(6, [&](uint64_t seed) {
      s.seed = seed;
      return pixel_stats(render_with(*scene, name, 8, s).image).mean;
    });
    EXPECT_NEAR(m, p.expected_radiance(), 3 * se + 1e-5) << name;
  }
}

// --- Merging without light leaks (issue: zero-thickness walls) ---------------------------------

namespace {
// Two closed rooms side by side sharing one zero-thickness wall at x = 0; each room has its own
// floor, ceiling and side walls (as modelled scenes do), the light hangs in room A (x < 0) and
// the camera looks from room B at the junction of the wall with the floor and a side wall.
// Nothing reaches room B: every correct estimator renders it black.
std::unique_ptr<Scene> two_rooms(bool look_into_lit_room = false) {
  SceneBuilder b;
  const MaterialPtr white = diffuse(Rgb(0.8f));
  for (float x0 : {-2.f, 0.f}) {
    const float x1 = x0 + 2;
    b.add_mesh(quad({x0, 0, -1}, {x0, 0, 1}, {x1, 0, 1}, {x1, 0, -1}), white);  // floor
    b.add_mesh(quad({x0, 2, -1}, {x1, 2, -1}, {x1, 2, 1}, {x0, 2, 1}), white);  // ceiling
    b.add_mesh(quad({x0, 0, 1}, {x0, 2, 1}, {x1, 2, 1}, {x1, 0, 1}), white);    // side walls
    b.add_mesh(quad({x0, 0, -1}, {x1, 0, -1}, {x1, 2, -1}, {x0, 2, -1}), white);
    const float end = x0 < 0 ? x0 : x1;  // the outer end wall
    b.add_mesh(quad({end, 0, -1}, {end, 2, -1}, {end, 2, 1}, {end, 0, 1}), white);
  }
  b.add_mesh(quad({0, 0, -1}, {0, 2, -1}, {0, 2, 1}, {0, 0, 1}), white);  // the shared wall
  const AreaEmission e{Rgb(30.f), false};
  b.add_mesh(quad({-1.2f, 1.99f, -0.2f}, {-0.8f, 1.99f, -0.2f}, {-0.8f, 1.99f, 0.2f},
                  {-1.2f, 1.99f, 0.2f}),
             diffuse(Rgb(0.f)), &e);
  CameraParams c;
  const float mirror = look_into_lit_room ? -1.f : 1.f;
  c.camera_to_world =
      Transform::look_at({1.6f * mirror, 1.2f, -0.6f}, {0, 0.2f, 0.8f}, {0, 1, 0}).inverse();
  c.width = c.height = 24;
  c.fov_degrees = 60;
  b.set_camera(c);
  return b.build("two-rooms");
}
}  // namespace

TEST(BidirMergingLeaks, NoLightThroughAZeroThicknessWall) {
  auto scene = two_rooms();
  IntegratorSettings s;
  s.max_depth = 6;
  s.bidir.radius = 0.1f;  // large, so that a leak would be wide and bright
  s.bidir.light_paths = 20000;
  for (const char* name : {"bpt", "vcm", "bpm", "ppm"}) {
    const Image img = render_with(*scene, name, 2, s).image;
    double max_value = 0;
    for (const Rgb& p : img.pixels()) max_value = std::max(max_value, double(p.max_component()));
    EXPECT_EQ(max_value, 0.0) << name << " sees light in the dark room";
  }
  // The mirrored view from inside the lit room does see light: the test can fail.
  auto lit_room = two_rooms(true);
  for (const char* name : {"bpt", "vcm", "bpm", "ppm"})
    EXPECT_GT(pixel_stats(render_with(*lit_room, name, 2, s).image).mean, 0.01) << name;
}

// --- A small light seen directly ----------------------------------------------------------------

namespace {
// A two-sided light of radiance 100 on the rectangle [x0, x1] x [y0, y1] at z = 5, facing a
// pinhole camera at the origin (24 x 24 pixels, 30 degrees): its projection is a rectangle,
// 12 / (5 tan 15 deg) pixels per unit. With `interface`, a surface without a material lies
// between them at z = 3.
constexpr double kPixelsPerUnit = 12.0 / (5.0 * 0.2679491924311227);  // tan 15 deg
std::unique_ptr<Scene> light_facing_the_lens(float x0, float x1, float y0, float y1,
                                             bool interface) {
  SceneBuilder b;
  const AreaEmission e{Rgb(100.f), true};
  b.add_mesh(quad({x0, y0, 5}, {x1, y0, 5}, {x1, y1, 5}, {x0, y1, 5}), diffuse(Rgb(0.f)), &e);
  if (interface) b.add_mesh(quad({-2, -2, 3}, {2, -2, 3}, {2, 2, 3}, {-2, 2, 3}), nullptr);
  CameraParams c;
  c.camera_to_world = Transform::look_at({0, 0, 0}, {0, 0, 1}, {0, 1, 0}).inverse();
  c.width = c.height = 24;
  c.fov_degrees = 30;
  b.set_camera(c);
  return b.build("light-facing-the-lens");
}
double image_sum(const Image& img) {
  double t = 0;
  for (size_t i = 0; i < img.pixel_count(); ++i) t += img[i].average();
  return t;
}
}  // namespace

// A 0.10 x 0.07 light 5 units from the pinhole, nothing else: the image holds only paths of one
// segment and sums to L times 0.896 x 0.627 pixels = 56.1585. A camera ray finds such a light in
// a few of its samples (pt's total varies by about a third between renders at 16 spp); the
// bidirectional integrators also connect every light subpath's emission point to the lens
// (s = 1, t = 1), which the balance heuristic prefers here 1000 to 1.
TEST(BidirLightSeenDirectly, EmissionPointsConnectedToTheLensConvergeAtOnce) {
  auto scene =
      light_facing_the_lens(0.03f - 0.05f, 0.03f + 0.05f, 0.02f - 0.035f, 0.02f + 0.035f, false);
  const double expected = 100.0 * (0.1 * kPixelsPerUnit) * (0.07 * kPixelsPerUnit);
  std::map<std::string, double> spread;
  for (const char* name : {"pt", "bpt", "vcm", "adaptive-vcm"}) {
    IntegratorSettings s;
    const auto [mean, se] = over_seeds(6, [&](uint64_t seed) {
      s.seed = seed;
      return image_sum(render_with(*scene, name, 16, s).image);
    });
    std::printf("[ small light ] %-12s image sum %.4f se %.4f (expected %.4f)\n", name, mean, se,
                expected);
    EXPECT_NEAR(mean, expected, 3 * se + 2e-3 * expected) << name;
    spread[name] = se;
  }
  // Without the emission-point connections bpt and vcm would vary as pt does.
  for (const char* name : {"bpt", "vcm"}) EXPECT_LT(spread[name], 0.02 * spread["pt"]) << name;
}

// A 1.0 x 0.7 light (about 56 pixels) behind a surface without a material (a pbrt-v4
// "interface"): camera rays pass it, and so do the emission points' shadow rays
// (Scene::shadow_transmittance). When they stopped there, weighting the camera ray against
// connections that could not happen (about 91% of the weight here) made the light go dark.
TEST(BidirLightSeenDirectly, ThroughAnInterfaceCameraRaysKeepTheLight) {
  auto scene = light_facing_the_lens(-0.5f, 0.5f, -0.35f, 0.35f, true);
  const double expected = 100.0 * (1.0 * kPixelsPerUnit) * (0.7 * kPixelsPerUnit);
  for (const char* name : {"pt", "bpt", "vcm"}) {
    IntegratorSettings s;
    const auto [mean, se] = over_seeds(4, [&](uint64_t seed) {
      s.seed = seed;
      return image_sum(render_with(*scene, name, 8, s).image);
    });
    std::printf("[ light behind an interface ] %-4s image sum %.2f se %.2f (expected %.2f)\n", name,
                mean, se, expected);
    EXPECT_NEAR(mean, expected, 3 * se + 5e-3 * expected) << name;
  }
}
