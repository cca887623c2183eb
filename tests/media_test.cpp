// Absorbing media (geometry/medium.h): which medium a segment is in, Beer-Lambert transmittance,
// and what the pbrt loader makes of MakeNamedMedium and MediumInterface. The integrators'
// oracles (Beer-Lambert for each, agreement with pt on cornell-absorbing) are in
// registry_oracles_test.cpp.
#include <gtest/gtest.h>

#include <cmath>

#include "geometry/medium.h"
#include "pbrt_test_util.h"
#include "scene/scene.h"

namespace caustica {
namespace {

using test::load_error;
using test::load_text;
using test::with_camera;

TEST(Media, SegmentEndsNameTheMediumOnTheirSide) {
  const MediumInterface glass{0, kNoMedium};  // medium 0 behind the normal
  const Vec3 n(0, 0, 1);
  EXPECT_FALSE(segment_end({}, n, n).known);  // no transition: says nothing
  EXPECT_FALSE(segment_end({2, 2}, n, n).known);
  const SegmentEnd out = segment_end(glass, n, Vec3(0.3f, 0, 0.9f));
  const SegmentEnd in = segment_end(glass, n, Vec3(0.3f, 0, -0.9f));
  EXPECT_TRUE(out.known && in.known);
  EXPECT_EQ(out.medium, kNoMedium);
  EXPECT_EQ(in.medium, 0);
  // A known end decides, in either direction; with none, the default (camera's) medium.
  const SegmentEnd none;
  EXPECT_EQ(medium_between(in, none, 3), 0);
  EXPECT_EQ(medium_between(none, in, 3), 0);
  EXPECT_EQ(medium_between(none, none, 3), 3);
  EXPECT_EQ(medium_between(out, none, 3), kNoMedium);
  // Two known ends that disagree (an inconsistent scene) give the same answer both ways.
  EXPECT_EQ(medium_between(in, out, 3), medium_between(out, in, 3));
}

TEST(Media, TransmittanceIsBeerLambertPerChannel) {
  const HomogeneousMedium m{Rgb(0.5f, 0.f, 2.f)};
  const Rgb t = m.transmittance(1.5f);
  EXPECT_NEAR(t.r, std::exp(-0.75f), 1e-6f);
  EXPECT_EQ(t.g, 1.f);
  EXPECT_NEAR(t.b, std::exp(-3.f), 1e-6f);
  // A ray that escapes: nothing left where the medium absorbs, all of it where it does not.
  const Rgb escaped = m.transmittance(kInfinity);
  EXPECT_EQ(escaped.r, 0.f);
  EXPECT_EQ(escaped.g, 1.f);  // not 0 * infinity = NaN
  EXPECT_EQ(escaped.b, 0.f);
}

const char* kInk =
    "MakeNamedMedium \"ink\" \"string type\" \"homogeneous\" \"rgb sigma_a\" [0.5 1 2] "
    "\"rgb sigma_s\" [0 0 0] \"float scale\" 2\n";

TEST(PbrtMedia, InterfaceShapesBoundTheNamedMedium) {
  auto scene = load_text(with_camera(std::string(kInk) +
                                     "AttributeBegin\nMediumInterface \"ink\" \"\"\n"
                                     "Material \"interface\"\nShape \"sphere\"\nAttributeEnd\n"
                                     "Material \"diffuse\"\nTranslate 0 0 5\nShape \"sphere\"\n"));
  EXPECT_TRUE(test::captured_warnings().empty());
  ASSERT_EQ(scene->medium_count(), 1u);
  EXPECT_EQ(scene->default_medium(), kNoMedium);
  SurfaceInteraction si;
  ASSERT_TRUE(scene->intersect({{0, 0, -3}, {0, 0, 1}, kInfinity}, &si));
  EXPECT_EQ(si.material, nullptr);  // the interface is there, and has no material
  EXPECT_EQ(si.media.inside, 0);
  EXPECT_EQ(si.media.outside, kNoMedium);
  // sigma_a times "scale", per unit length.
  const Rgb t = scene->transmittance(si.medium_toward({0, 0, 1}), {}, 1.f);
  EXPECT_NEAR(t.r, std::exp(-1.f), 1e-6f);
  EXPECT_NEAR(t.b, std::exp(-4.f), 1e-6f);
  // The diffuse sphere behind it names no medium: its segments take the camera's.
  ASSERT_TRUE(scene->intersect({{0, 0, 1.5f}, {0, 0, 1}, kInfinity}, &si));
  EXPECT_NE(si.material, nullptr);
  EXPECT_FALSE(si.media.transition());
  // A shadow ray passes the interface and absorbs inside it; a material blocks it.
  const Rgb through = scene->shadow_transmittance({{0, 0, -3}, {0, 0, 1}, 6.f}, {}, {});
  EXPECT_NEAR(through.g, std::exp(-2.f * 2.f), 1e-5f);  // two units of sigma 1 x scale 2
  EXPECT_TRUE(scene->shadow_transmittance({{0, 0, -3}, {0, 0, 1}, kInfinity}, {}, {}).is_black());
}

TEST(PbrtMedia, TheCameraIsInTheOutsideMediumAtCamera) {
  auto scene = load_text(std::string(kInk) + "MediumInterface \"\" \"ink\"\n" +
                         with_camera("Shape \"sphere\"\n"));
  EXPECT_EQ(scene->default_medium(), 0);
  // One name is both sides: no transition, so an interface there is left out.
  auto same =
      load_text(with_camera(std::string(kInk) + "MediumInterface \"ink\"\nMaterial \"interface\"\n"
                                                "Shape \"sphere\"\n"));
  EXPECT_EQ(same->triangle_count() + same->sphere_count(), 0u);
}

TEST(PbrtMedia, MistakesAreLocatedErrors) {
  EXPECT_EQ(load_error(with_camera("MediumInterface \"fog\" \"\"\nShape \"sphere\"\n")),
            "test.pbrt:4:1: error: MediumInterface: medium \"fog\" is not defined (no "
            "MakeNamedMedium of that name)");
  EXPECT_EQ(load_error(with_camera(std::string(kInk) + kInk)),
            "test.pbrt:5:17: error: medium \"ink\" is defined twice");
  EXPECT_EQ(load_error(with_camera("MakeNamedMedium \"m\" \"rgb sigma_a\" [1 1 1]\n")),
            "test.pbrt:4:1: error: MakeNamedMedium: \"string type\" is required");
  EXPECT_NE(load_error(with_camera("MakeNamedMedium \"m\" \"string type\" \"homogeneous\" "
                                   "\"rgb sigma_a\" [1 -1 1]\n"))
                .find("test.pbrt:4:"),
            std::string::npos);
  EXPECT_NE(load_error(with_camera("MakeNamedMedium \"m\" \"string type\" \"homogeneous\" "
                                   "\"float scale\" -2\n"))
                .find("expected a finite value >= 0"),
            std::string::npos);
}

TEST(PbrtMedia, OtherKindsWarnAndAreLeftOut) {
  auto scene = load_text(with_camera(
      "MakeNamedMedium \"smoke\" \"string type\" \"nanovdb\" \"string filename\" \"x.nvdb\"\n"
      "MediumInterface \"smoke\" \"\"\nMaterial \"interface\"\nShape \"sphere\"\n"));
  EXPECT_EQ(test::count_containing(test::captured_warnings(),
                                   "test.pbrt:4:25: warning: medium type \"nanovdb\" is not "
                                   "supported (only \"homogeneous\"); the medium is left out"),
            1);
  EXPECT_FALSE(scene->has_media());
  EXPECT_EQ(scene->sphere_count(), 0u);
}

}  // namespace
}  // namespace caustica
