#include "geometry/camera.h"

#include <gtest/gtest.h>

#include "core/rng.h"

using namespace caustica;

namespace {
Camera test_camera(int w, int h, float lens_radius = 0) {
  CameraParams p;
  p.camera_to_world = Transform::look_at({0, -5, 1}, {0, 0, 1}, {0, 0, 1}).inverse();
  p.width = w;
  p.height = h;
  p.fov_degrees = 50;
  p.lens_radius = lens_radius;
  p.focal_distance = 5;
  return Camera(p);
}
}  // namespace

TEST(Camera, RayThroughRasterProjectsBackToIt) {
  const Camera cam = test_camera(64, 48);
  Pcg32 r(1, 1);
  for (int i = 0; i < 200; ++i) {
    const Vec2 raster(r.next_float() * 64, r.next_float() * 48);
    const Ray ray = cam.generate_ray(raster, {0.5f, 0.5f});
    const auto back = cam.project(ray.at(3.f));
    ASSERT_TRUE(back.has_value());
    EXPECT_NEAR(back->x, raster.x, 1e-2);
    EXPECT_NEAR(back->y, raster.y, 1e-2);
  }
}

TEST(Camera, FovSpansTheShorterAxis) {
  // Landscape 64x48: the vertical extent spans fov; the ray through the top edge centre
  // makes fov/2 with the axis.
  const Camera cam = test_camera(64, 48);
  const Ray top = cam.generate_ray({32, 0}, {0.5f, 0.5f});
  EXPECT_NEAR(std::acos(dot(top.d, cam.forward())), radians(25.f), 1e-4);
  const Camera portrait = test_camera(48, 64);
  const Ray left = portrait.generate_ray({0, 32}, {0.5f, 0.5f});
  EXPECT_NEAR(std::acos(dot(left.d, portrait.forward())), radians(25.f), 1e-4);
}

TEST(Camera, RasterYGrowsDownwardAndXFollowsPbrtHandedness) {
  const Camera cam = test_camera(64, 64);
  // World +z is up: a point above the axis lands in the upper half (small raster y).
  EXPECT_LT(cam.project({0, 0, 1.5f})->y, 32.f);
  // pbrt's LookAt is left-handed: world +x (to the right of a viewer looking down +y with
  // z up) lands on the *left* half of the image unless the scene mirrors with Scale -1 1 1.
  EXPECT_LT(cam.project({0.5f, 0, 1})->x, 32.f);
}

TEST(Camera, ImportanceAndDirectionPdfAreConsistent) {
  // We is normalised so that integrating We * cos over the directions of the film gives 1
  // (for a pinhole, lens area 1): sum over a fine raster grid of We * cos * dOmega.
  const Camera cam = test_camera(40, 30);
  double sum = 0;
  const int n = 200;
  for (int y = 0; y < n; ++y)
    for (int x = 0; x < n; ++x) {
      const Vec2 raster((x + 0.5f) * 40 / n, (y + 0.5f) * 30 / n);
      const Ray ray = cam.generate_ray(raster, {0.5f, 0.5f});
      float pdf_pos, pdf_dir;
      cam.pdf_we(ray.o, ray.d, &pdf_pos, &pdf_dir);
      const float we = cam.importance(ray.o, ray.d);
      ASSERT_GT(pdf_dir, 0);
      // Uniform raster sampling has density pdf_dir over directions: the MC estimate of the
      // integral of We * cos is the mean of We * cos / pdf_dir.
      sum += we * dot(ray.d, cam.forward()) / pdf_dir;
    }
  EXPECT_NEAR(sum / (n * n), 1.0, 1e-3);
}

TEST(Camera, SampleWiAgreesWithImportanceAndPdf) {
  const Camera cam = test_camera(64, 64, 0.1f);
  Pcg32 r(2, 2);
  const Vec3 ref(0.2f, 0.5f, 1.1f);
  int hits = 0;
  for (int i = 0; i < 100; ++i) {
    const auto s = cam.sample_wi(ref, r.next_2d());
    if (!s) continue;
    ++hits;
    EXPECT_NEAR(s->importance, cam.importance(s->p_lens, -s->wi), 1e-3f * s->importance);
    // Its raster position is where a camera ray from that lens point through ref lands.
    const auto raster = cam.raster_of(s->p_lens, -s->wi);
    ASSERT_TRUE(raster.has_value());
    EXPECT_NEAR(raster->x, s->raster.x, 1e-3);
    EXPECT_NEAR(distance(s->p_lens - s->wi * s->distance, ref), 0, 1e-4);
  }
  EXPECT_GT(hits, 90);
}

// A thin-lens ray leaving the lens off centre toward the film border is on the film: its
// densities must not be zero (they used to be tested from the lens centre, which dropped about
// 4 pixels of border at 64x64).
TEST(Camera, ThinLensBorderRaysHaveTheirDensity) {
  const Camera cam = test_camera(64, 64, 0.3f);
  Pcg32 r(5, 5);
  for (int i = 0; i < 2000; ++i) {
    // Raster points within half a pixel of the border, any lens point.
    const float t = r.next_float() * 64, e = r.next_float() * 0.5f;
    const int side = int(r.next_bounded(4));
    const Vec2 raster = side == 0   ? Vec2(e, t)
                        : side == 1 ? Vec2(64 - e, t)
                        : side == 2 ? Vec2(t, e)
                                    : Vec2(t, 64 - e);
    const Ray ray = cam.generate_ray(raster, r.next_2d());
    float pdf_pos, pdf_dir;
    cam.pdf_we(ray.o, ray.d, &pdf_pos, &pdf_dir);
    ASSERT_GT(pdf_dir, 0) << "raster " << raster.x << ", " << raster.y;
    ASSERT_GT(cam.importance(ray.o, ray.d), 0);
  }
}
