// Tokenizer, typed parameter lists and the directive grammar of the pbrt-v4 loader, and the
// exact positions of its error messages.
#include <gtest/gtest.h>

#include "io/pbrt/parameters.h"
#include "io/pbrt/parser.h"
#include "io/pbrt/tokenizer.h"
#include "pbrt_test_util.h"

namespace caustica::pbrt {
namespace {

using test::load_error;
using test::with_camera;

std::vector<Token> tokenize(const std::string& text) {
  Tokenizer t(text, "t.pbrt");
  std::vector<Token> out;
  for (Token tok = t.next(); tok.kind != Token::Kind::End; tok = t.next()) out.push_back(tok);
  return out;
}

TEST(PbrtTokenizer, KeepsLineAndColumnOfEveryToken) {
  const auto t = tokenize("Shape \"sphere\"\n  \"float radius\" [ 2.5 ] # comment [ \"x\"\n]");
  ASSERT_EQ(t.size(), 7u);
  EXPECT_EQ(t[0].text, "Shape");
  EXPECT_EQ(t[0].line, 1);
  EXPECT_EQ(t[0].column, 1);
  EXPECT_EQ(t[1].kind, Token::Kind::String);
  EXPECT_EQ(t[1].text, "sphere");
  EXPECT_EQ(t[1].column, 7);
  EXPECT_EQ(t[2].line, 2);
  EXPECT_EQ(t[2].column, 3);
  EXPECT_EQ(t[3].kind, Token::Kind::OpenBracket);
  EXPECT_EQ(t[4].text, "2.5");
  EXPECT_EQ(t[5].kind, Token::Kind::CloseBracket);
  EXPECT_EQ(t[6].kind, Token::Kind::CloseBracket);
  EXPECT_EQ(t[6].line, 3);
  EXPECT_EQ(t[6].column, 1);
}

TEST(PbrtTokenizer, BracketsNeedNoSpaces) {
  const auto t = tokenize("[1 2]\"a\"[\"b\"]");
  ASSERT_EQ(t.size(), 8u);
  EXPECT_EQ(t[1].text, "1");
  EXPECT_EQ(t[2].text, "2");
  EXPECT_EQ(t[3].kind, Token::Kind::CloseBracket);
  EXPECT_EQ(t[4].text, "a");
  EXPECT_EQ(t[6].text, "b");
}

TEST(PbrtTokenizer, UnescapesStrings) {
  const auto t = tokenize(R"("a\"b\\c\n")");
  ASSERT_EQ(t.size(), 1u);
  EXPECT_EQ(t[0].text, "a\"b\\c\n");
}

TEST(PbrtTokenizer, UnterminatedStringIsAnErrorAtItsStart) {
  try {
    tokenize("Shape\n   \"sphere\n");
    FAIL();
  } catch (const SceneLoadError& e) {
    EXPECT_EQ(e.where().line, 2);
    EXPECT_EQ(e.where().column, 4);
    EXPECT_NE(e.message().find("unterminated string"), std::string::npos);
  }
}

TEST(PbrtTokenizer, BadEscapeIsAnError) { EXPECT_THROW(tokenize(R"("a\qb")"), SceneLoadError); }

ParamList params(const std::string& text) {
  Tokenizer t(text, "p.pbrt");
  return ParamList::parse(t);
}

TEST(PbrtParams, ParsesEveryType) {
  const ParamList p = params(
      "\"integer n\" [ 1 2 3 ] \"float f\" 2.5 \"point2 uv\" [0 1 1 0] \"vector2 v2\" [1 2]"
      " \"point3 P\" [1 2 3] \"point from\" [4 5 6] \"vector3 d\" [0 0 1] \"vector dd\" [1 0 0]"
      " \"normal N\" [0 1 0] \"normal3 N3\" [0 0 1] \"rgb L\" [1 2 3] \"color c\" [0.1 0.2 0.3]"
      " \"spectrum s\" [300 1 800 2] \"spectrum named\" \"metal-Cu-eta\" \"blackbody b\" 6500"
      " \"bool t\" true \"bool f2\" \"false\" \"string name\" \"x\" \"texture tex\" \"checks\"");
  EXPECT_EQ(p.get_ints("n"), (std::vector<int>{1, 2, 3}));
  EXPECT_FLOAT_EQ(p.get_float("f", 0), 2.5f);
  EXPECT_EQ(p.get_point2s("uv").size(), 2u);
  EXPECT_EQ(p.find("v2")->type, ParamType::Vector2);
  EXPECT_EQ(p.get_point3("P", {}), Vec3(1, 2, 3));
  EXPECT_EQ(p.get_point3("from", {}), Vec3(4, 5, 6));
  EXPECT_EQ(p.get_vector3("d", {}), Vec3(0, 0, 1));
  EXPECT_EQ(p.get_vector3("dd", {}), Vec3(1, 0, 0));
  EXPECT_EQ(p.get_normals("N")[0], Vec3(0, 1, 0));
  EXPECT_EQ(p.find("N3")->type, ParamType::Normal3);
  EXPECT_EQ(p.find("L")->type, ParamType::Rgb);
  EXPECT_EQ(p.find("c")->type, ParamType::Rgb);
  EXPECT_EQ(p.find("s")->numbers.size(), 4u);
  EXPECT_EQ(p.find("named")->strings[0], "metal-Cu-eta");
  EXPECT_EQ(p.find("b")->numbers[0], 6500);
  EXPECT_TRUE(p.get_bool("t", false));
  EXPECT_FALSE(p.get_bool("f2", true));
  EXPECT_EQ(p.get_string("name", ""), "x");
  EXPECT_EQ(p.find("tex")->strings[0], "checks");
}

TEST(PbrtParams, DefaultsWhenAbsent) {
  const ParamList p = params("");
  EXPECT_EQ(p.get_float("fov", 90), 90);
  EXPECT_EQ(p.get_int("maxdepth", 5), 5);
  EXPECT_TRUE(p.get_ints("indices").empty());
}

TEST(PbrtParams, WrongTypeAtLookupNamesTheParameter) {
  const ParamList p = params("\n  \"integer fov\" [ 45 ]");
  try {
    p.get_float("fov", 90);
    FAIL();
  } catch (const SceneLoadError& e) {
    EXPECT_STREQ(e.what(), "p.pbrt:2:3: error: \"integer fov\": expected type float");
  }
}

TEST(PbrtParams, UnusedParametersWarnOnce) {
  const ParamList p = params("\"float fov\" 45 \"float fvo\" 45");
  p.get_float("fov", 0);
  test::captured_warnings().clear();
  Warnings w(test::capture_warning);
  p.report_unused(w, "Camera \"perspective\"");
  p.report_unused(w, "Camera \"perspective\"");
  ASSERT_EQ(test::captured_warnings().size(), 1u);
  EXPECT_EQ(test::captured_warnings()[0],
            "p.pbrt:1:16: warning: Camera \"perspective\": parameter \"float fvo\" is unknown or "
            "not supported; ignored");
}

struct ErrorCase {
  const char* text;
  const char* expected;
};

TEST(PbrtErrors, ReportExactPositionAndWhatWasExpected) {
  const ErrorCase cases[] = {
      {"Frobnicate 1 2", "test.pbrt:1:1: error: unknown directive \"Frobnicate\""},
      {"WorldBegin\n  Shape \"sphere\" \"flaot radius\" 1",
       "test.pbrt:2:18: error: unknown parameter type \"flaot\" in \"flaot radius\""},
      {"WorldBegin\nShape \"sphere\" \"float radius\" [ 1 abc ]",
       "test.pbrt:2:35: error: \"float radius\": expected a number, got \"abc\""},
      {"WorldBegin\nShape \"sphere\" \"float radius\" [ 1",
       "test.pbrt:2:31: error: missing \"]\" to close the \"[\" of \"float radius\""},
      {"WorldBegin\nShape \"sphere\" \"float radius\" ]",
       "test.pbrt:2:31: error: \"float radius\": expected a value or \"[\", got \"]\""},
      {"WorldBegin\nAttributeEnd",
       "test.pbrt:2:1: error: AttributeEnd without a matching AttributeBegin"},
      {"WorldBegin\nAttributeBegin\nShape \"sphere\"\n",
       "test.pbrt:2:1: error: AttributeBegin has no matching AttributeEnd before the end of the "
       "file"},
      {"WorldBegin\nAttributeBegin\nTransformEnd",
       "test.pbrt:3:1: error: TransformEnd does not match the AttributeBegin at test.pbrt:2:1"},
      {"Translate 1 2", "test.pbrt:1:14: error: Translate: expected 3 numbers, got end of file"},
      {"Translate 1 x 2", "test.pbrt:1:13: error: Translate: expected 3 numbers, got \"x\""},
      {"Transform [ 1 0 0 0 1 ]", "test.pbrt:1:23: error: Transform: expected 16 numbers, got 5"},
      {"Transform 1 0 0",
       "test.pbrt:1:11: error: Transform: expected \"[\" followed by 16 numbers, got \"1\""},
      {"WorldBegin\nShape \"trianglemesh\" \"point3 P\" [ 0 0 0 1 0 0 0 1 ]",
       "test.pbrt:2:22: error: \"point3 P\": expected a multiple of 3 values, got 8"},
      {"WorldBegin\nShape \"trianglemesh\" \"point3 P\" [ 0 0 0 1 0 0 0 1 0 ] \"integer indices\" "
       "[ 0 1 3 ]",
       "test.pbrt:2:55: error: \"integer indices\": vertex index 3 is out of range (3 vertices in "
       "\"point3 P\")"},
      {"WorldBegin\nShape \"trianglemesh\" \"point3 P\" [ 0 0 0 1 0 0 0 1 0 ] \"integer indices\" "
       "[ 0 1 ]",
       "test.pbrt:2:55: error: \"integer indices\": expected a multiple of 3 indices (3 per "
       "triangle), got 2"},
      {"WorldBegin\nShape \"sphere\" \"integer radius\" 1.5",
       "test.pbrt:2:33: error: \"integer radius\": expected an integer, got \"1.5\""},
      {"WorldBegin\nShape \"sphere\" \"rgb L\" [ 1 2 ]",
       "test.pbrt:2:16: error: \"rgb L\": expected exactly 3 values, got 2"},
      {"WorldBegin\nShape \"sphere\" \"bool b\" yes",
       "test.pbrt:2:25: error: \"bool b\": expected true or false, got \"yes\""},
      {"WorldBegin\nShape \"teapot\"",
       "test.pbrt:2:1: error: unknown shape \"teapot\" (expected trianglemesh, plymesh, "
       "bilinearmesh, sphere, disk, cylinder, curve or loopsubdiv)"},
      {"WorldBegin\nNamedMaterial \"nope\"\nShape \"sphere\"",
       "test.pbrt:2:15: error: no material named \"nope\""},
      {"WorldBegin\nMaterial \"plastic\"\nShape \"sphere\"",
       "test.pbrt:2:1: error: unknown material type \"plastic\""},
      {"Shape \"sphere\"", "test.pbrt:1:1: error: Shape is only allowed after WorldBegin"},
      {"WorldBegin\nCamera \"perspective\"",
       "test.pbrt:2:1: error: Camera is only allowed before WorldBegin (it sets a rendering "
       "option)"},
      {"WorldBegin\nShape \"plymesh\" \"string filename\" \"x.ply\"",
       "test.pbrt:2:17: error: cannot read \"x.ply\": file access is disabled when parsing from "
       "memory"},
      {"Include \"other.pbrt\"",
       "test.pbrt:1:9: error: Include: file access is disabled when parsing from memory"},
      {"\"float fov\" 3",
       "test.pbrt:1:1: error: expected a directive (such as Shape or AttributeBegin), got string "
       "\"float fov\""},
      {"WorldBegin\nShape \"sphere\" \"float radius\" 1 \"float radius\" 2",
       "test.pbrt:2:33: error: parameter \"radius\" given twice (first at test.pbrt:2:16)"},
      {"WorldBegin\nMakeNamedMaterial \"m\" \"string type\" \"mix\" \"string materials\" [ \"m\" "
       "\"m\" ]",
       "test.pbrt:2:43: error: material \"m\" contains itself (through \"mix\")"},
      {"LookAt 0 0 0  0 0 0  0 1 0",
       "test.pbrt:1:1: error: LookAt: the eye and the look-at point are the same"},
      {"WorldBegin\nLightSource \"sun\"",
       "test.pbrt:2:1: error: unknown light type \"sun\" (expected point, spot, distant, "
       "infinite, goniometric or projection)"},
      {"WorldBegin\nObjectInstance \"tree\"",
       "test.pbrt:2:16: error: ObjectInstance: no object named \"tree\""},
      {"WorldBegin\nTexture \"t\" \"spectrum\" \"imagemap\"",
       "test.pbrt:2:1: error: imagemap: \"string filename\" is required"},
      {"WorldBegin\nMaterial \"diffuse\" \"texture reflectance\" \"nope\"\nShape \"sphere\"",
       "test.pbrt:2:20: error: \"texture reflectance\": no spectrum texture named \"nope\""},
  };
  for (const ErrorCase& c : cases)
    EXPECT_EQ(load_error(c.text), c.expected) << "input:\n" << c.text;
}

TEST(PbrtErrors, PositionsInIncludedFilesNameThatFile) {
  test::TempDir dir;
  dir.write("inc/bad.pbrt",
            "AttributeBegin\n  Shape \"sphere\" \"float radius\" [ x ]\nAttributeEnd\n");
  const std::string main = dir.write("main.pbrt", with_camera("Include \"inc/bad.pbrt\"\n"));
  try {
    load_pbrt(main, test::capture_warning);
    FAIL();
  } catch (const SceneLoadError& e) {
    EXPECT_EQ(e.where().file, dir.file("inc/bad.pbrt"));
    EXPECT_EQ(e.where().line, 2);
    EXPECT_EQ(e.where().column, 35);
  }
}

TEST(PbrtErrors, MissingIncludeFileIsAnError) {
  test::TempDir dir;
  const std::string main = dir.write("main.pbrt", with_camera("Include \"missing.pbrt\"\n"));
  try {
    load_pbrt(main, test::capture_warning);
    FAIL();
  } catch (const SceneLoadError& e) {
    EXPECT_EQ(e.where().line, 4);
    EXPECT_EQ(e.where().column, 9);
    EXPECT_NE(e.message().find("cannot read"), std::string::npos);
  }
}

TEST(PbrtErrors, SelfIncludeStopsWithAnError) {
  test::TempDir dir;
  const std::string main = dir.write("loop.pbrt", "Include \"loop.pbrt\"\n");
  EXPECT_THROW(load_pbrt(main, test::capture_warning), SceneLoadError);
}

TEST(PbrtErrors, MissingSceneFile) {
  try {
    load_pbrt("/nonexistent/scene.pbrt", test::capture_warning);
    FAIL();
  } catch (const SceneLoadError& e) {
    EXPECT_STREQ(e.what(),
                 "/nonexistent/scene.pbrt: error: cannot open the scene file: No such file or "
                 "directory");
  }
}

TEST(PbrtWarnings, UnsupportedConstructsWarnOnceWithPosition) {
  const std::string text = with_camera(
      "MakeNamedMedium \"fog\" \"string type\" \"homogeneous\"\n"
      "MediumInterface \"fog\" \"\"\n"
      "MakeNamedMedium \"fog2\" \"string type\" \"homogeneous\"\n"
      "Shape \"curve\" \"point3 P\" [0 0 0 1 1 1 2 2 2 3 3 3]\n"
      "Shape \"curve\" \"point3 P\" [0 0 0 1 1 1 2 2 2 3 3 3]\n"
      "Material \"hair\"\n"
      "Shape \"sphere\" \"float radius\" 1 \"float frobnicate\" 2\n"
      "Shape \"sphere\" \"float radius\" 1 \"float frobnicate\" 2\n"
      "LightSource \"point\"\n");
  test::load_text(text);
  const auto& w = test::captured_warnings();
  // pbrt-v4's default medium scatters (sigma_s 1): absorption alone is rendered, warned once.
  EXPECT_EQ(test::count_containing(w,
                                   "test.pbrt:4:1: warning: scattering in media is not "
                                   "supported; medium \"fog\" only absorbs (sigma_a)"),
            1);
  EXPECT_EQ(test::count_containing(w, "scattering in media"), 1);
  EXPECT_EQ(test::count_containing(w, "MediumInterface"), 0);
  EXPECT_EQ(test::count_containing(
                w, "test.pbrt:7:1: warning: shape \"curve\" is not supported; skipped"),
            1);
  EXPECT_EQ(test::count_containing(w, "curve"), 1);
  EXPECT_EQ(test::count_containing(w, "material \"hair\" is not supported"), 1);
  EXPECT_EQ(test::count_containing(
                w, "test.pbrt:10:33: warning: Shape \"sphere\": parameter \"float frobnicate\""),
            1);
  EXPECT_EQ(test::count_containing(w, "frobnicate"), 1);
}

TEST(PbrtDirectives, EveryDirectiveParses) {
  const std::string text =
      "# every pbrt-v4 directive\n"
      "Option \"bool disablepixeljitter\" true\n"
      "ColorSpace \"srgb\"\n"
      "Accelerator \"bvh\" \"integer maxnodeprims\" 4\n"
      "LookAt 0 0 -5  0 0 0  0 1 0\n"
      "CoordinateSystem \"eye\"\n"
      "Camera \"perspective\" \"float fov\" 45 \"float lensradius\" 0.01 \"float focaldistance\" "
      "5\n"
      "Film \"rgb\" \"integer xresolution\" 32 \"integer yresolution\" 16 \"string filename\" "
      "\"out.exr\"\n"
      "Sampler \"zsobol\" \"integer pixelsamples\" 8\n"
      "Integrator \"bdpt\" \"integer maxdepth\" 7\n"
      "PixelFilter \"gaussian\"\n"
      "WorldBegin\n"
      "Attribute \"shape\" \"float radius\" 0.25\n"
      "AttributeBegin\n"
      "  Identity\n  Translate 1 0 0\n  Scale 2 2 2\n  Rotate 90 0 0 1\n"
      "  ConcatTransform [1 0 0 0 0 1 0 0 0 0 1 0 0 0 0 1]\n"
      "  Transform [1 0 0 0 0 1 0 0 0 0 1 0 0 0 0 1]\n"
      "  ActiveTransform StartTime\n  TransformTimes 0 1\n  ActiveTransform All\n"
      "  CoordSysTransform \"eye\"\n"
      "  ReverseOrientation\n"
      "  TransformBegin\n  TransformEnd\n"
      "  Texture \"c\" \"spectrum\" \"constant\" \"rgb value\" [0.5 0.5 0.5]\n"
      "  Texture \"f\" \"float\" \"constant\" \"float value\" 0.1\n"
      "  Texture \"s\" \"spectrum\" \"scale\" \"texture tex\" \"c\" \"float scale\" 2\n"
      "  Texture \"k\" \"spectrum\" \"checkerboard\" \"texture tex1\" \"c\"\n"
      "  Texture \"m\" \"spectrum\" \"mix\" \"texture tex1\" \"c\" \"texture tex2\" \"k\" \"float "
      "amount\" 0.3\n"
      "  MakeNamedMaterial \"a\" \"string type\" \"diffuse\" \"texture reflectance\" \"m\"\n"
      "  MakeNamedMaterial \"b\" \"string type\" \"conductor\" \"spectrum eta\" \"metal-Au-eta\" "
      "\"spectrum k\" \"metal-Au-k\""
      " \"texture roughness\" \"f\"\n"
      "  MakeNamedMaterial \"ab\" \"string type\" \"mix\" \"string materials\" [\"a\" \"b\"] "
      "\"float amount\" 0.5\n"
      "  NamedMaterial \"ab\"\n"
      "  Shape \"sphere\"\n"
      "  Material \"dielectric\" \"spectrum eta\" \"glass-BK7\" \"float roughness\" 0.1\n"
      "  Shape \"disk\" \"float radius\" 2\n"
      "  Material \"thindielectric\" \"float eta\" 1.4\n"
      "  Shape \"bilinearmesh\" \"point3 P\" [0 0 0 1 0 0 0 1 0 1 1 0]\n"
      "  Material \"coateddiffuse\" \"rgb reflectance\" [0.2 0.3 0.4] \"float roughness\" 0.1 "
      "\"float thickness\" 0.02\n"
      "  Shape \"trianglemesh\" \"point3 P\" [0 0 0 1 0 0 0 1 0]\n"
      "  Material \"diffusetransmission\" \"rgb transmittance\" [0.5 0.5 0.5]\n"
      "  Material \"interface\"\n"
      "  Shape \"sphere\"\n"
      "AttributeEnd\n"
      "ObjectBegin \"thing\"\n  Material \"diffuse\"\n  Shape \"sphere\" \"float radius\" "
      "0.1\nObjectEnd\n"
      "AttributeBegin\n  Translate 0 3 0\n  ObjectInstance \"thing\"\nAttributeEnd\n"
      "AttributeBegin\n"
      "  AreaLightSource \"diffuse\" \"blackbody L\" 3000 \"float scale\" 2 \"bool twosided\" "
      "true\n"
      "  Shape \"trianglemesh\" \"point3 P\" [0 0 3 1 0 3 0 1 3] \"integer indices\" [0 1 2]\n"
      "AttributeEnd\n"
      "LightSource \"point\" \"point3 from\" [0 5 0] \"rgb I\" [1 1 1]\n"
      "LightSource \"spot\" \"point3 from\" [0 5 0] \"point3 to\" [0 0 0] \"float coneangle\" 20\n"
      "LightSource \"distant\" \"point3 from\" [0 1 0] \"point3 to\" [0 0 0] \"blackbody L\" 5500\n"
      "LightSource \"infinite\" \"rgb L\" [0.1 0.1 0.1]\n"
      "MakeNamedMedium \"fog\" \"string type\" \"homogeneous\"\n"
      "MediumInterface \"fog\"\n";
  auto scene = test::load_text(text);
  ASSERT_TRUE(scene);
  EXPECT_EQ(scene->settings().spp, 8);
  EXPECT_EQ(scene->settings().max_depth, 7);
  EXPECT_EQ(scene->settings().integrator, "bpt");
  EXPECT_EQ(scene->settings().output_name, "out.exr");
  EXPECT_EQ(scene->camera().width(), 32);
  EXPECT_EQ(scene->camera().height(), 16);
  EXPECT_FALSE(scene->camera().is_pinhole());
  // sphere (mix), instanced sphere; the interface sphere is dropped.
  EXPECT_EQ(scene->sphere_count(), 2u);
  // 1 area-light triangle + 4 lights.
  EXPECT_EQ(scene->lights().size(), 5u);
}

}  // namespace
}  // namespace caustica::pbrt
