// What the pbrt loader builds: camera handedness and projection as pbrt-v4 has them,
// transforms, shapes and their orientation, area and other lights, textures, and every
// scene in scenes/ (copied from the project's shared scenes).
#include <gtest/gtest.h>

#include <chrono>
#include <cmath>
#include <filesystem>

#include "core/arena.h"
#include "geometry/interaction.h"
#include "io/pbrt/color.h"
#include "lights/light.h"
#include "materials/material.h"
#include "pbrt_test_util.h"
#include "test_scenes.h"

namespace caustica {
namespace {

using test::load_text;
using test::with_camera;

std::string camera_block(const std::string& before_camera, int w, int h, float fov) {
  return before_camera + "\nCamera \"perspective\" \"float fov\" " + std::to_string(fov) +
         "\nFilm \"rgb\" \"integer xresolution\" " + std::to_string(w) +
         " \"integer yresolution\" " + std::to_string(h) + "\nWorldBegin\n";
}

void expect_raster(const Scene& scene, Vec3 p, float x, float y) {
  const auto r = scene.camera().project(p);
  ASSERT_TRUE(r.has_value()) << "point not visible";
  EXPECT_NEAR(r->x, x, 1e-3f);
  EXPECT_NEAR(r->y, y, 1e-3f);
}

// pbrt-v4's LookAt builds a left-handed camera frame: right = cross(up, dir). Looking down
// +z with +y up, world +x is on the right of the image; raster y grows downward.
TEST(PbrtCamera, LookAtProjectsAsPbrtV4) {
  auto scene = load_text(camera_block("LookAt 0 0 -5  0 0 0  0 1 0", 100, 100, 90));
  expect_raster(*scene, {0, 0, 0}, 50, 50);
  expect_raster(*scene, {1, 0, 0}, 60, 50);  // tan(45) = 1: screen x = 1/5
  expect_raster(*scene, {0, 1, 0}, 50, 40);
}

TEST(PbrtCamera, ScaleMinusOneBeforeLookAtMirrorsTheImage) {
  auto scene = load_text(camera_block("Scale -1 1 1\nLookAt 0 0 -5  0 0 0  0 1 0", 100, 100, 90));
  expect_raster(*scene, {1, 0, 0}, 40, 50);
  expect_raster(*scene, {0, 1, 0}, 50, 40);
}

TEST(PbrtCamera, LookingDownMinusZPutsWorldXOnTheLeft) {
  // right = cross(+y, -z) = -x: the well-known pbrt mirror that Scale -1 1 1 undoes.
  auto scene = load_text(camera_block("LookAt 0 0 5  0 0 0  0 1 0", 100, 100, 90));
  expect_raster(*scene, {1, 0, 0}, 40, 50);
}

TEST(PbrtCamera, FovSpansTheShorterAxis) {
  auto wide = load_text(camera_block("LookAt 0 0 -5  0 0 0  0 1 0", 200, 100, 90));
  expect_raster(*wide, {0, 1, 0}, 100, 40);  // vertical: 100 px for screen [-1, 1]
  expect_raster(*wide, {1, 0, 0}, 110, 50);  // horizontal: 200 px for [-2, 2]
  auto tall = load_text(camera_block("LookAt 0 0 -5  0 0 0  0 1 0", 100, 200, 90));
  expect_raster(*tall, {1, 0, 0}, 60, 100);  // horizontal is the shorter axis now
  expect_raster(*tall, {0, 1, 0}, 50, 90);   // vertical: 200 px for [-2, 2]
}

TEST(PbrtCamera, TransformMatrixIsWorldToCamera) {
  // Column-major world-to-camera: translate by (0, 0, 5), so the camera sits at z = -5.
  auto scene =
      load_text(camera_block("Transform [1 0 0 0  0 1 0 0  0 0 1 0  0 0 5 1]", 100, 100, 90));
  EXPECT_NEAR(scene->camera().position().z, -5, 1e-5f);
  expect_raster(*scene, {1, 0, 0}, 60, 50);
}

TEST(PbrtCamera, ThinLensParameters) {
  auto scene = load_text(
      "LookAt 0 0 -5 0 0 0 0 1 0\nCamera \"perspective\" \"float lensradius\" 0.1 \"float "
      "focaldistance\" 5\nWorldBegin\n");
  EXPECT_FALSE(scene->camera().is_pinhole());
  EXPECT_NEAR(scene->camera().lens_area(), kPi * 0.01f, 1e-6f);
  EXPECT_EQ(scene->camera().width(), 1280);  // pbrt-v4's default film
  EXPECT_EQ(scene->camera().height(), 720);
}

TEST(PbrtCamera, NamedCameraCoordinateSystem) {
  auto scene = load_text(
      camera_block("LookAt 0 0 -5  0 0 0  0 1 0", 64, 64, 90) +
      "CoordSysTransform \"camera\"\nTranslate 0 0 2\nShape \"sphere\" \"float radius\" 0.5\n");
  SurfaceInteraction si;
  ASSERT_TRUE(scene->intersect({{0, 0, -10}, {0, 0, 1}, kInfinity}, &si));
  EXPECT_NEAR(si.p.z, -3.5f, 1e-4f);
}

SurfaceInteraction hit(const Scene& scene, Vec3 o, Vec3 d) {
  SurfaceInteraction si;
  EXPECT_TRUE(scene.intersect({o, normalize(d), kInfinity}, &si)) << "ray missed";
  return si;
}

TEST(PbrtTransforms, ComposeAsPbrtPostMultiplies) {
  // Translate then Rotate: the sphere is rotated about its own origin, then moved.
  auto scene =
      load_text(with_camera("AttributeBegin\nTranslate 0 0 10\nRotate 90 0 1 0\nScale 2 2 2\n"
                            "Shape \"sphere\" \"float radius\" 1\nAttributeEnd\n"));
  const SurfaceInteraction si = hit(*scene, {0, 0, 0}, {0, 0, 1});
  EXPECT_NEAR(si.p.z, 8, 1e-4f);
  EXPECT_EQ(scene->sphere_count(), 1u);
}

TEST(PbrtTransforms, AttributeEndRestoresTransformAndMaterial) {
  auto scene =
      load_text(with_camera("AttributeBegin\nTranslate 100 0 0\nAttributeEnd\n"
                            "Translate 0 0 10\nShape \"sphere\"\n"));
  EXPECT_NEAR(hit(*scene, {0, 0, 0}, {0, 0, 1}).p.z, 9, 1e-4f);
}

TEST(PbrtTransforms, TransformBeginEndRestoreOnlyTheTransform) {
  auto scene =
      load_text(with_camera("TransformBegin\nTranslate 100 0 0\nTransformEnd\n"
                            "Translate 0 0 10\nShape \"sphere\"\n"));
  EXPECT_NEAR(hit(*scene, {0, 0, 0}, {0, 0, 1}).p.z, 9, 1e-4f);
}

TEST(PbrtShapes, NonUniformScaleTessellatesTheSphereWithAWarning) {
  auto scene = load_text(with_camera("Translate 0 0 10\nScale 1 1 3\nShape \"sphere\"\n"));
  EXPECT_EQ(scene->sphere_count(), 0u);
  EXPECT_GT(scene->triangle_count(), 1000u);
  EXPECT_EQ(test::count_containing(test::captured_warnings(), "tessellated"), 1);
  EXPECT_NEAR(hit(*scene, {0, 0, 0}, {0, 0, 1}).p.z, 7, 1e-3f);
}

TEST(PbrtShapes, PartialSphereIsTessellatedWithAWarning) {
  auto scene = load_text(with_camera("Shape \"sphere\" \"float zmin\" 0\n"));
  EXPECT_EQ(scene->sphere_count(), 0u);
  EXPECT_EQ(test::count_containing(test::captured_warnings(), "partial sphere"), 1);
  // Upper hemisphere only: a ray from below passes through the open bottom and hits the
  // inside of the cap.
  const SurfaceInteraction si = hit(*scene, {0, 0, -5}, {0, 0, 1});
  EXPECT_NEAR(si.p.z, 1, 1e-3f);
}

TEST(PbrtMaterials, CoatedConductorIsTheLayeredBsdfNotTheBareMetal) {
  test::captured_warnings().clear();
  auto scene = load_text(with_camera(
      "Material \"coatedconductor\" \"float interface.roughness\" 0.05 \"float interface.eta\" "
      "1.4 \"spectrum conductor.eta\" \"metal-Au-eta\" \"spectrum conductor.k\" \"metal-Au-k\" "
      "\"float conductor.roughness\" 0.2 \"float thickness\" 0.02 \"integer maxdepth\" 8\n"
      "Translate 0 0 10\nShape \"sphere\"\n"));
  EXPECT_TRUE(test::captured_warnings().empty());
  const SurfaceInteraction si = hit(*scene, {0, 0, 0}, {0, 0, 1});
  ASSERT_TRUE(si.material);
  EXPECT_STREQ(si.material->name(), "coatedconductor");
  ScratchArena arena;
  EXPECT_TRUE(si.material->bsdf(si, arena).stochastic());
}

TEST(PbrtShapes, DiskNormalIsPlusZ) {
  auto scene = load_text(with_camera("Translate 0 0 2\nShape \"disk\" \"float radius\" 1\n"));
  const SurfaceInteraction si = hit(*scene, {0.3f, 0.2f, 5}, {0, 0, -1});
  EXPECT_NEAR(si.p.z, 2, 1e-5f);
  EXPECT_GT(si.ng.z, 0.99f);
}

// pbrt-v4's cylinder: radius, zmin, zmax, phimax about the z axis; the normal points away
// from the axis (cross(dp/du, dp/dv)), uv = (phi / phimax, (z - zmin) / (zmax - zmin)).
TEST(PbrtShapes, CylinderIsPbrtV4s) {
  test::captured_warnings().clear();
  auto scene = load_text(
      with_camera("Shape \"cylinder\" \"float radius\" 2 \"float zmin\" 3 \"float zmax\" -1\n"));
  EXPECT_TRUE(test::captured_warnings().empty());
  const SurfaceInteraction side = hit(*scene, {9, 0, 2}, {-1, 0, 0});
  EXPECT_NEAR(side.p.x, 2, 1e-4f);
  EXPECT_GT(side.ng.x, 0.999f);
  EXPECT_GT(side.shading.n.x, 0.99999f);
  EXPECT_NEAR(side.uv.x, 0, 1e-4f);
  EXPECT_NEAR(side.uv.y, 0.75f, 1e-4f);
  // A quarter turn: u = 1/4; the shading normal is radial between the tessellation's edges.
  const float c = std::cos(0.3f), s = std::sin(0.3f);
  const SurfaceInteraction turned = hit(*scene, {9 * c, 9 * s, 0}, {-c, -s, 0});
  EXPECT_NEAR(turned.uv.x, 0.3f / (2 * kPi), 1e-4f);
  EXPECT_NEAR(turned.shading.n.x, c, 1e-4f);
  EXPECT_NEAR(turned.shading.n.y, s, 1e-4f);
  EXPECT_NEAR(length(turned.p - Vec3(0, 0, turned.p.z)), 2, 1e-3f);
  // Open at both ends: a ray along the axis hits nothing.
  SurfaceInteraction none;
  EXPECT_FALSE(scene->intersect(Ray{{0, 0, 9}, {0, 0, -1}, kInfinity}, &none));
}

TEST(PbrtShapes, PartialCylinderAndItsOrientation) {
  const std::string half = "Shape \"cylinder\" \"float phimax\" 180\n";
  // Through the missing half (y < 0) to the inside of the kept one: the normal faces away.
  const SurfaceInteraction inside = hit(*load_text(with_camera(half)), {0, -5, 0}, {0, 1, 0});
  EXPECT_NEAR(inside.p.y, 1, 1e-4f);
  EXPECT_GT(inside.ng.y, 0.999f);
  EXPECT_NEAR(inside.uv.x, 0.5f, 1e-4f);
  const SurfaceInteraction reversed =
      hit(*load_text(with_camera("ReverseOrientation\n" + half)), {0, -5, 0}, {0, 1, 0});
  EXPECT_LT(reversed.ng.y, -0.999f);
  EXPECT_LT(reversed.shading.n.y, -0.999f);
  // A mirroring transform flips a quadric's normal as pbrt-v4 does (unlike a mesh's winding).
  const SurfaceInteraction mirrored =
      hit(*load_text(with_camera("Scale 1 1 -1\n" + half)), {0, -5, 0}, {0, 1, 0});
  EXPECT_LT(mirrored.ng.y, -0.999f);
}

TEST(PbrtLights, CylinderAreaLightEmitsOutward) {
  auto scene =
      load_text(with_camera("AreaLightSource \"diffuse\" \"rgb L\" [3 3 3]\n"
                            "Shape \"cylinder\" \"float radius\" 0.5\n"));
  EXPECT_EQ(scene->lights().size(), scene->triangle_count());  // one emitter per triangle
  const SurfaceInteraction si = hit(*scene, {0, 5, 0}, {0, -1, 0});
  ASSERT_NE(si.area_light, nullptr);
  EXPECT_NEAR(si.area_light->radiance(si.p, si.ng, si.uv, {0, 1, 0}).g, 3, 1e-4f);
  EXPECT_TRUE(si.area_light->radiance(si.p, si.ng, si.uv, {0, -1, 0}).is_black());
}

TEST(PbrtShapes, ReverseOrientationFlipsTriangleNormals) {
  const std::string tri = "Shape \"trianglemesh\" \"point3 P\" [-1 -1 0  1 -1 0  0 1 0]\n";
  EXPECT_GT(hit(*load_text(with_camera(tri)), {0, 0, 5}, {0, 0, -1}).ng.z, 0.99f);
  EXPECT_LT(hit(*load_text(with_camera("ReverseOrientation\n" + tri)), {0, 0, 5}, {0, 0, -1}).ng.z,
            -0.99f);
  // A mirroring transform keeps the object-space side (pbrt-v4 compensates the winding).
  EXPECT_LT(hit(*load_text(with_camera("Scale 1 1 -1\n" + tri)), {0, 0, 5}, {0, 0, -1}).ng.z,
            -0.99f);
}

TEST(PbrtShapes, BilinearMeshIsTwoTrianglesPerPatch) {
  auto scene =
      load_text(with_camera("Shape \"bilinearmesh\" \"point3 P\" [0 0 0  1 0 0  0 1 0  1 1 0] "
                            "\"point2 uv\" [0 0 1 0 0 1 1 1]\n"));
  EXPECT_EQ(scene->triangle_count(), 2u);
  const SurfaceInteraction si = hit(*scene, {0.8f, 0.7f, 1}, {0, 0, -1});
  EXPECT_GT(si.ng.z, 0.99f);  // cross(p10 - p00, p01 - p00)
  EXPECT_NEAR(si.uv.x, 0.8f, 1e-4f);
  EXPECT_NEAR(si.uv.y, 0.7f, 1e-4f);
}

TEST(PbrtLights, AreaLightIsOneSidedOnTheWindingSide) {
  auto scene =
      load_text(with_camera("AreaLightSource \"diffuse\" \"rgb L\" [17 12 4]\n"
                            "Shape \"trianglemesh\" \"point3 P\" [-1 -1 0  1 -1 0  0 1 0] "
                            "\"integer indices\" [0 1 2]\n"));
  ASSERT_EQ(scene->lights().size(), 1u);
  const SurfaceInteraction si = hit(*scene, {0, 0, 5}, {0, 0, -1});
  ASSERT_NE(si.area_light, nullptr);
  const Rgb front = si.area_light->radiance(si.p, si.ng, si.uv, {0, 0, 1});
  const Rgb back = si.area_light->radiance(si.p, si.ng, si.uv, {0, 0, -1});
  // pbrt-v4 divides rgb L by the illuminant's photometric value: values come out as given.
  EXPECT_NEAR(front.r, 17, 1e-4f);
  EXPECT_NEAR(front.g, 12, 1e-4f);
  EXPECT_NEAR(front.b, 4, 1e-4f);
  EXPECT_TRUE(back.is_black());
}

TEST(PbrtLights, TwoSidedAndScale) {
  auto scene = load_text(with_camera(
      "AreaLightSource \"diffuse\" \"rgb L\" [1 2 3] \"bool twosided\" true \"float scale\" 2\n"
      "Shape \"trianglemesh\" \"point3 P\" [-1 -1 0  1 -1 0  0 1 0]\n"));
  const SurfaceInteraction si = hit(*scene, {0, 0, 5}, {0, 0, -1});
  const Rgb back = si.area_light->radiance(si.p, si.ng, si.uv, {0, 0, -1});
  EXPECT_NEAR(back.b, 6, 1e-4f);
}

TEST(PbrtLights, PowerNormalisesEachTriangle) {
  // Area 2, one-sided: L = P / (pi A).
  auto scene =
      load_text(with_camera("AreaLightSource \"diffuse\" \"rgb L\" [1 1 1] \"float power\" 10\n"
                            "Shape \"trianglemesh\" \"point3 P\" [-1 -1 0  1 -1 0  1 1 0]\n"));
  const SurfaceInteraction si = hit(*scene, {0.5f, -0.5f, 5}, {0, 0, -1});
  EXPECT_NEAR(si.area_light->radiance(si.p, si.ng, si.uv, {0, 0, 1}).g, 10 / (kPi * 2), 1e-4f);
}

TEST(PbrtLights, BlackbodyHasLuminanceOne) {
  for (float t : {2700.f, 6500.f, 10000.f})
    EXPECT_NEAR(pbrt::blackbody_rgb(t).luminance(), 1, 0.02f) << t;
  const Rgb warm = pbrt::blackbody_rgb(2700);
  EXPECT_GT(warm.r, warm.b);
  const Rgb d65ish = pbrt::blackbody_rgb(6504);
  EXPECT_NEAR(d65ish.r / d65ish.b, 1, 0.15f);
}

TEST(PbrtLights, SphereAreaLightAndPointLights) {
  auto scene = load_text(with_camera(
      "AttributeBegin\nAreaLightSource \"diffuse\" \"rgb L\" [8 8 8]\nTranslate 0 0 10\n"
      "Shape \"sphere\" \"float radius\" 0.5\nAttributeEnd\n"
      "LightSource \"point\" \"point3 from\" [0 1 0] \"rgb I\" [1 1 1]\n"
      "LightSource \"spot\" \"point3 from\" [0 1 0] \"point3 to\" [0 0 0]\n"
      "LightSource \"distant\" \"point3 from\" [0 1 0] \"point3 to\" [0 0 0]\n"
      "LightSource \"infinite\" \"rgb L\" [0.5 0.5 0.5]\n"));
  EXPECT_EQ(scene->lights().size(), 5u);
  EXPECT_EQ(scene->infinite_lights().size(), 2u);
  const SurfaceInteraction si = hit(*scene, {0, 0, 0}, {0, 0, 1});
  ASSERT_NE(si.area_light, nullptr);
  EXPECT_NEAR(si.area_light->radiance(si.p, si.ng, si.uv, {0, 0, -1}).r, 8, 1e-4f);
}

TEST(PbrtTextures, ImageMapRelativeToTheSceneFileAndLinearForNonPng) {
  test::TempDir dir;
  // A 2x1 PFM (linear): left red, right blue.
  std::string pfm = "PF\n2 1\n-1.0\n";
  const float px[6] = {1, 0, 0, 0, 0, 1};
  pfm.append(reinterpret_cast<const char*>(px), sizeof(px));
  dir.write("tex/t.pfm", pfm);
  const std::string main = dir.write(
      "s.pbrt",
      with_camera(
          "Texture \"t\" \"spectrum\" \"imagemap\" \"string filename\" \"tex/t.pfm\" \"float "
          "uscale\" 2\n"
          "Material \"diffuse\" \"texture reflectance\" \"t\"\n"
          "Shape \"trianglemesh\" \"point3 P\" [0 0 0 1 0 0 0 1 0] \"point2 uv\" [0 0 1 0 0 1]\n"));
  EXPECT_NO_THROW(load_pbrt(main, test::capture_warning));
}

TEST(PbrtInstancing, ObjectInstancesPlaceTheObjectsShapes) {
  auto scene = load_text(
      with_camera("ObjectBegin \"tri\"\nTranslate 0 0 1\n"
                  "Shape \"trianglemesh\" \"point3 P\" [-1 -1 0  1 -1 0  0 1 0]\nObjectEnd\n"
                  "AttributeBegin\nTranslate 0 0 5\nObjectInstance \"tri\"\nAttributeEnd\n"
                  "AttributeBegin\nTranslate 10 0 5\nObjectInstance \"tri\"\nAttributeEnd\n"));
  EXPECT_EQ(scene->triangle_count(), 2u);
  EXPECT_NEAR(hit(*scene, {0, 0, 0}, {0, 0, 1}).p.z, 6, 1e-5f);
}

// --- The shared scenes ---------------------------------------------------------------

std::string shared(const std::string& rel) { return std::string(CAUSTICA_SCENES) + "/" + rel; }

TEST(PbrtSharedScenes, CornellCausticsLoadsAndProjectsLikePbrtV4) {
  test::captured_warnings().clear();
  auto scene = load_pbrt(shared("cornell-caustics.pbrt"), test::capture_warning);
  EXPECT_EQ(scene->camera().width(), 512);
  EXPECT_EQ(scene->settings().spp, 64);
  EXPECT_EQ(scene->settings().max_depth, 10);
  EXPECT_EQ(scene->settings().integrator, "pt");
  EXPECT_EQ(scene->sphere_count(), 2u);
  EXPECT_EQ(scene->lights().size(), 2u);  // the light quad: two triangles
  // Scale -1 1 1 before LookAt: world +x (the red wall) is on the right of the image.
  const auto red = scene->camera().project({1.2f, 0.5f, 0.f});
  const auto green = scene->camera().project({-1.2f, 0.5f, 0.f});
  ASSERT_TRUE(red && green);
  EXPECT_GT(red->x, 256);
  EXPECT_LT(green->x, 256);
  // The light faces down (-z): cross(p1 - p0, p2 - p0) of its first triangle.
  const SurfaceInteraction si = hit(*scene, {0, 0, 0}, {0, 0, 1});
  ASSERT_NE(si.area_light, nullptr);
  EXPECT_LT(si.ng.z, -0.99f);
  EXPECT_NEAR(si.area_light->radiance(si.p, si.ng, si.uv, {0, 0, -1}).r, 25.0333f, 1e-3f);
  // The pixel of the centre of the image looks along the camera's forward direction.
  const Vec3 f = scene->camera().forward();
  EXPECT_NEAR(f.y, 0.998f, 1e-3f);
}

TEST(PbrtSharedScenes, EveryOwnSceneLoads) {
  for (const char* name : {"cornell-caustics", "door-ajar", "material-spheres", "mirror-caustic",
                           "mis-plates", "point-room", "sun-glass", "spot-glass", "sky-spheres",
                           "corner", "lamp", "window", "bulb"}) {
    SCOPED_TRACE(name);
    test::captured_warnings().clear();
    std::unique_ptr<Scene> scene;
    ASSERT_NO_THROW(scene = load_pbrt(shared(std::string(name) + ".pbrt"), test::capture_warning));
    EXPECT_GT(scene->lights().size(), 0u);
    EXPECT_GT(scene->triangle_count() + scene->sphere_count(), 0u);
    for (const std::string& w : test::captured_warnings()) std::printf("  %s\n", w.c_str());
  }
}

TEST(PbrtSharedScenes, EveryThirdPartySceneLoads) {
  namespace fs = std::filesystem;
  int count = 0;
  for (const auto& entry : fs::directory_iterator(shared("pbrt-v4"))) {
    const fs::path file = entry.path() / "scene-v4.pbrt";
    if (!fs::exists(file)) continue;
    SCOPED_TRACE(file.string());
    test::captured_warnings().clear();
    const auto start = std::chrono::steady_clock::now();
    std::unique_ptr<Scene> scene;
    try {
      scene = load_pbrt(file.string(), test::capture_warning);
    } catch (const std::exception& e) {
      ADD_FAILURE() << e.what();
      continue;
    }
    const double seconds =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    std::printf("%-24s %8zu triangles %3zu spheres %6zu lights  %.3f s\n",
                entry.path().filename().c_str(), scene->triangle_count(), scene->sphere_count(),
                scene->lights().size(), seconds);
    for (const std::string& w : test::captured_warnings()) std::printf("  %s\n", w.c_str());
    EXPECT_GT(scene->lights().size(), 0u);
    EXPECT_GT(scene->triangle_count(), 0u);
    ++count;
  }
  EXPECT_EQ(count, 7);
}

// One sample per pixel with pt and a short path: every own scene renders to a finite,
// lit image (the loader produced something an integrator can use).
TEST(PbrtSharedScenes, OwnScenesRenderWithPt) {
  for (const char* name : {"cornell-caustics", "door-ajar", "material-spheres", "mirror-caustic",
                           "mis-plates", "point-room", "sun-glass"}) {
    SCOPED_TRACE(name);
    auto scene = load_pbrt(shared(std::string(name) + ".pbrt"), test::capture_warning);
    IntegratorSettings settings;
    settings.max_depth = 3;
    const RenderResult r = test::render_with(*scene, "pt", 1, settings);
    EXPECT_EQ(r.nonfinite, 0u);
    const Rgb mean = r.image.average();
    EXPECT_TRUE(mean.is_finite());
    EXPECT_GT(mean.average(), 0.f);
  }
}

TEST(PbrtSharedScenes, MaterialTestballEnvironmentIsOrientedAndSquare) {
  auto scene = load_pbrt(shared("pbrt-v4/material-testball/scene-v4.pbrt"), test::capture_warning);
  ASSERT_EQ(scene->infinite_lights().size(), 1u);
  EXPECT_EQ(scene->camera().width(), 384);
  EXPECT_EQ(scene->camera().height(), 216);
}

}  // namespace
}  // namespace caustica
