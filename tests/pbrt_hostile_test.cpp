// Hostile and broken input for the pbrt-v4 loader, and scene paths that are directories for
// every loader: every case must end in a SceneLoadError that says where and what
// ("file:line:col: error: ..."), before any rendering and without a crash. glTF's hostile input:
// gltf_hostile_test.cpp.
#include <gtest/gtest.h>

#include <cstring>
#include <filesystem>
#include <string>

#include "io/gltf/gltf_loader.h"
#include "io/load_error.h"
#include "io/scene_loader.h"
#include "lights/light.h"
#include "loader_hostile_helpers.h"
#include "pbrt_test_util.h"

namespace caustica {
namespace {

using test::collect;
using test::contains;
namespace fs = std::filesystem;

// ---------------------------------------------------------------------------------------------
// Scene paths that are directories

TEST(LoaderHostile, SceneFileThatIsADirectoryIsAnError) {
  test::TempDir dir;
  for (const char* name : {"scene.pbrt", "scene.gltf", "scene.glb", "plain"}) {
    SCOPED_TRACE(name);
    const std::string path = dir.file(name);
    fs::create_directories(path);
    try {
      load_scene(path, LoadOptions{collect, -1});
      FAIL() << "expected an error";
    } catch (const SceneLoadError& e) {
      EXPECT_EQ(std::string(e.what()), path +
                                           ": error: is a directory, not a scene file "
                                           "(.pbrt, .gltf or .glb)");
    }
  }
  // The format loaders on their own say so too.
  fs::create_directories(dir.file("direct.pbrt"));
  EXPECT_THROW(
      {
        try {
          load_pbrt(dir.file("direct.pbrt"), collect);
        } catch (const SceneLoadError& e) {
          EXPECT_TRUE(contains(e.what(), "cannot open the scene file: is a directory"));
          throw;
        }
      },
      SceneLoadError);
  fs::create_directories(dir.file("direct.gltf"));
  EXPECT_THROW(
      {
        try {
          load_gltf(dir.file("direct.gltf"), collect);
        } catch (const SceneLoadError& e) {
          EXPECT_TRUE(contains(e.what(), "cannot open the scene file: is a directory"));
          throw;
        }
      },
      SceneLoadError);
}

// ---------------------------------------------------------------------------------------------
// pbrt-v4

using test::load_error;
using test::with_camera;

// Line 4 is the first line after with_camera()'s three.
TEST(PbrtHostile, IncludeOrImportOfADirectoryIsALocatedError) {
  for (const char* directive : {"Include", "Import"}) {
    SCOPED_TRACE(directive);
    test::TempDir dir;
    fs::create_directories(dir.file("parts"));
    const std::string main =
        dir.write("main.pbrt", with_camera(std::string(directive) + " \"parts\"\n"));
    try {
      load_pbrt(main, collect);
      FAIL() << "expected an error";
    } catch (const SceneLoadError& e) {
      EXPECT_EQ(e.where().file, main);
      EXPECT_EQ(e.where().line, 4);
      EXPECT_EQ(e.where().column, int(std::strlen(directive)) + 2);
      EXPECT_TRUE(contains(e.message(), ": is a directory")) << e.what();
    }
  }
}

TEST(PbrtHostile, NumbersOutsideTheFloatRangeAreErrors) {
  // 1e39 is a finite double but an infinite float.
  EXPECT_EQ(load_error(with_camera("LightSource \"point\" \"float scale\" [ 1e39 ]\n")),
            "test.pbrt:4:37: error: \"float scale\": \"1e39\" is not a finite number in the "
            "range of a 32-bit float");
  EXPECT_EQ(load_error(with_camera("LightSource \"point\" \"rgb I\" [ 1 inf 1 ]\n")),
            "test.pbrt:4:33: error: \"rgb I\": \"inf\" is not a finite number in the range of "
            "a 32-bit float");
  EXPECT_EQ(load_error(with_camera("Material \"diffuse\" \"rgb reflectance\" [ nan 0.5 0.5 ]\n")),
            "test.pbrt:4:40: error: \"rgb reflectance\": \"nan\" is not a finite number in the "
            "range of a 32-bit float");
}

TEST(PbrtHostile, NonFiniteNumbersInSpectrumFilesAreErrors) {
  test::TempDir dir;
  dir.write("bad.spd", "400 1\n500 nan\n");
  const std::string main =
      dir.write("main.pbrt", with_camera("LightSource \"point\" \"spectrum I\" \"bad.spd\"\n"));
  try {
    load_pbrt(main, collect);
    FAIL() << "expected an error";
  } catch (const SceneLoadError& e) {
    EXPECT_EQ(e.where().line, 4);
    EXPECT_EQ(e.where().column, 21);
    EXPECT_TRUE(contains(e.message(),
                         "expected finite numbers (wavelength, value pairs), got "
                         "\"nan\""))
        << e.what();
  }
}

TEST(PbrtHostile, EmissionThatOverflowsIsALocatedError) {
  EXPECT_EQ(load_error(with_camera("LightSource \"point\" \"rgb I\" [ 1e38 1e38 1e38 ] "
                                   "\"float scale\" 1e10\n")),
            "test.pbrt:4:48: error: \"float scale\": makes the emission overflow to infinity");
  EXPECT_EQ(load_error(with_camera("AttributeBegin\nAreaLightSource \"diffuse\" \"rgb L\" [ 1e38 "
                                   "1e38 1e38 ] \"float scale\" [ 1e10 ]\n"
                                   "Shape \"sphere\"\nAttributeEnd\n")),
            "test.pbrt:5:54: error: \"float scale\": makes the emission overflow to infinity");
  EXPECT_EQ(load_error(with_camera("LightSource \"point\" \"rgb I\" [ 1e10 1e10 1e10 ] "
                                   "\"float power\" 3e38\n")),
            "test.pbrt:4:48: error: \"float power\": makes the emission overflow to infinity");
  // Finite intensity, infinite power (4 pi I).
  EXPECT_EQ(load_error(with_camera("LightSource \"point\" \"rgb I\" [ 3e38 1 1 ]\n")),
            "test.pbrt:4:1: error: the light's total power overflows to infinity");
  // "power" spread over a tiny shape.
  EXPECT_EQ(
      load_error(with_camera("AttributeBegin\nAreaLightSource \"diffuse\" \"float power\" "
                             "3e38\nShape \"sphere\" \"float radius\" 1e-20\nAttributeEnd\n")),
      "test.pbrt:5:1: error: \"power\" over the area of a shape makes its radiance "
      "overflow to infinity");
  EXPECT_EQ(load_error(with_camera("LightSource \"point\" \"float scale\" -2\n")),
            "test.pbrt:4:21: error: \"float scale\": must not be negative");
}

TEST(PbrtHostile, BlackbodyTemperatureMustBePositive) {
  EXPECT_EQ(load_error(with_camera("LightSource \"point\" \"blackbody I\" [ -100 ]\n")),
            "test.pbrt:4:21: error: \"blackbody I\": expected a positive temperature in "
            "kelvin, got -100");
  EXPECT_TRUE(contains(load_error(with_camera("LightSource \"point\" \"blackbody I\" 0\n")),
                       "expected a positive temperature"));
  EXPECT_EQ(load_error(with_camera("LightSource \"point\" \"blackbody I\" 2\n")),
            "test.pbrt:4:21: error: \"blackbody I\": a blackbody at 2 K emits no visible light");
}

TEST(PbrtHostile, HugeBlackbodyTemperatureGivesAFiniteColour) {
  // exp(x) - 1 rounded to 0 for hot bodies (a NaN colour); expm1 keeps the Rayleigh-Jeans
  // limit, so any positive float temperature is a valid, bluish light of luminance 1.
  for (const char* kelvin : {"1e6", "1e30", "3e38"}) {
    SCOPED_TRACE(kelvin);
    auto scene = test::load_text(
        with_camera(std::string("LightSource \"point\" \"blackbody I\" [ ") + kelvin + " ]\n"));
    ASSERT_EQ(scene->lights().size(), 1u);
    const Rgb power = scene->lights()[0]->power();
    EXPECT_TRUE(power.is_finite());
    EXPECT_NEAR(power.luminance(), 4 * kPi, 1e-3f * 4 * kPi);
    EXPECT_GT(power.b, power.r);
  }
}

// A Material is only created for the shapes that use it.
std::string with_sphere(const std::string& material) {
  return with_camera(material + "Shape \"sphere\"\n");
}

TEST(PbrtHostile, NegativeRoughnessIsAnError) {
  EXPECT_EQ(load_error(with_sphere("Material \"conductor\" \"float roughness\" -0.1\n")),
            "test.pbrt:4:22: error: \"float roughness\": expected a roughness >= 0, got -0.1");
  EXPECT_EQ(load_error(with_sphere("Material \"dielectric\" \"float uroughness\" 0.1 "
                                   "\"float vroughness\" -2\n")),
            "test.pbrt:4:46: error: \"float vroughness\": expected a roughness >= 0, got -2");
  EXPECT_EQ(load_error(with_sphere("Material \"coatedconductor\" \"float conductor.roughness\" "
                                   "-1\n")),
            "test.pbrt:4:28: error: \"float conductor.roughness\": expected a roughness >= 0, "
            "got -1");
}

TEST(PbrtHostile, CoatedConductorWithReflectanceAndEtaIsAnError) {
  EXPECT_EQ(load_error(with_sphere("Material \"coatedconductor\" \"rgb reflectance\" [0.5 0.5 0.5] "
                                   "\"spectrum conductor.eta\" \"metal-Au-eta\"\n")),
            "test.pbrt:4:1: error: coatedconductor: \"reflectance\" cannot be combined with "
            "\"conductor.eta\" or \"conductor.k\"");
  EXPECT_EQ(load_error(with_sphere("Material \"coatedconductor\" \"float interface.eta\" 0\n")),
            "test.pbrt:4:28: error: \"float interface.eta\": interface.eta must be positive");
}

TEST(PbrtHostile, MixAmountOutsideZeroOneIsAnError) {
  const std::string two =
      "MakeNamedMaterial \"a\" \"string type\" \"diffuse\"\n"
      "MakeNamedMaterial \"b\" \"string type\" \"conductor\"\n";
  EXPECT_EQ(load_error(with_sphere(two + "Material \"mix\" \"string materials\" [ \"a\" \"b\" ] "
                                         "\"float amount\" 1.5\n")),
            "test.pbrt:6:47: error: \"float amount\": expected an amount between 0 and 1, got 1.5");
  EXPECT_EQ(
      load_error(with_camera("Texture \"t\" \"spectrum\" \"mix\" \"float amount\" -0.5\n")),
      "test.pbrt:4:30: error: \"float amount\": expected an amount between 0 and 1, got -0.5");
}

TEST(PbrtHostile, TokensInMessagesAreShortAndEscaped) {
  // A 200-byte shape name with an escape sequence in it: the message quotes 40 bytes and
  // escapes the control byte.
  const std::string name = "\x1b[2J" + std::string(200, 'x');
  const std::string e = load_error(with_camera("Shape \"" + name + "\"\n"));
  EXPECT_EQ(e, "test.pbrt:4:1: error: unknown shape \"\\x1B[2J" + std::string(36, 'x') +
                   "...\" (expected trianglemesh, plymesh, bilinearmesh, sphere, disk, "
                   "cylinder, curve or loopsubdiv)");
  // Bare words and strings described by the tokenizer.
  const std::string w = load_error(with_camera(std::string(100, 'y') + "\x07\n"));
  EXPECT_TRUE(contains(w, "unknown directive \"" + std::string(40, 'y') + "...\"")) << w;
  const std::string s = load_error(with_camera("Shape \"sphere\" \"float radius\" \"ab\x01\"\n"));
  EXPECT_TRUE(contains(s, "got string \"ab\\x01\"")) << s;
  // Valid UTF-8 stays readable; a lone continuation byte does not.
  EXPECT_EQ(quote_excerpt("caf\xc3\xa9 \x80"), "\"caf\xc3\xa9 \\x80\"");
  EXPECT_EQ(quote_excerpt("a\"b\\c"), "\"a\\\"b\\\\c\"");
}

}  // namespace
}  // namespace caustica
