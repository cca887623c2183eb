// The glTF loader on a file written by the test: node transforms, the camera convention
// (glTF looks down -z), emissive materials as area lights, KHR_lights_punctual.
#include "io/gltf/gltf_loader.h"

#include <gtest/gtest.h>

#include <cstring>
#include <string>
#include <vector>

#include "geometry/interaction.h"
#include "lights/light.h"
#include "pbrt_test_util.h"

namespace caustica {
namespace {

std::string base64(const std::vector<unsigned char>& in) {
  static const char* table = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
  std::string out;
  for (size_t i = 0; i < in.size(); i += 3) {
    const uint32_t n = (uint32_t(in[i]) << 16) |
                       (i + 1 < in.size() ? uint32_t(in[i + 1]) << 8 : 0) |
                       (i + 2 < in.size() ? uint32_t(in[i + 2]) : 0);
    out += table[(n >> 18) & 63];
    out += table[(n >> 12) & 63];
    out += i + 1 < in.size() ? table[(n >> 6) & 63] : '=';
    out += i + 2 < in.size() ? table[n & 63] : '=';
  }
  return out;
}

// One triangle in the z = 0 plane (counter-clockwise seen from +z), emissive; a camera at
// z = 5 looking down -z; a point light.
std::string triangle_gltf() {
  std::vector<unsigned char> buf;
  const float p[9] = {-1, -1, 0, 1, -1, 0, 0, 1, 0};
  const uint16_t idx[4] = {0, 1, 2, 0};  // padded to 4 bytes
  buf.resize(sizeof(p) + sizeof(idx));
  std::memcpy(buf.data(), p, sizeof(p));
  std::memcpy(buf.data() + sizeof(p), idx, sizeof(idx));
  return R"({
  "asset": {"version": "2.0"},
  "extensionsUsed": ["KHR_lights_punctual", "KHR_materials_emissive_strength"],
  "scene": 0,
  "scenes": [{"nodes": [0, 1, 2]}],
  "nodes": [
    {"mesh": 0, "translation": [0, 0, 0]},
    {"camera": 0, "translation": [0, 0, 5]},
    {"translation": [0, 3, 0], "extensions": {"KHR_lights_punctual": {"light": 0}}}
  ],
  "cameras": [{"type": "perspective", "perspective": {"yfov": 0.8, "aspectRatio": 1.5, "znear": 0.1}}],
  "extensions": {"KHR_lights_punctual": {"lights": [{"type": "point", "color": [1, 1, 1], "intensity": 10}]}},
  "materials": [{"pbrMetallicRoughness": {"baseColorFactor": [0.5, 0.5, 0.5, 1], "metallicFactor": 0},
                 "emissiveFactor": [1, 2, 3],
                 "extensions": {"KHR_materials_emissive_strength": {"emissiveStrength": 2}}}],
  "meshes": [{"primitives": [{"attributes": {"POSITION": 0}, "indices": 1, "material": 0}]}],
  "buffers": [{"byteLength": 44, "uri": "data:application/octet-stream;base64,)" +
         base64(buf) + R"("}],
  "bufferViews": [{"buffer": 0, "byteOffset": 0, "byteLength": 36}, {"buffer": 0, "byteOffset": 36, "byteLength": 6}],
  "accessors": [
    {"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3", "min": [-1, -1, 0], "max": [1, 1, 0]},
    {"bufferView": 1, "componentType": 5123, "count": 3, "type": "SCALAR"}
  ]
})";
}

TEST(GltfLoader, TriangleCameraEmissionAndPunctualLight) {
  test::TempDir dir;
  const std::string path = dir.write("tri.gltf", triangle_gltf());
  test::captured_warnings().clear();
  auto scene = load_gltf(path, test::capture_warning);
  EXPECT_EQ(scene->triangle_count(), 1u);
  EXPECT_EQ(scene->lights().size(), 2u);  // the emissive triangle and the point light
  EXPECT_EQ(scene->camera().height(), 720);
  EXPECT_EQ(scene->camera().width(), 1080);
  const auto centre = scene->camera().project({0, 0, 0});
  ASSERT_TRUE(centre);
  EXPECT_NEAR(centre->x, 540, 1e-2f);
  EXPECT_NEAR(centre->y, 360, 1e-2f);
  const auto right = scene->camera().project({1, 0, 0});
  const auto up = scene->camera().project({0, 1, 0});
  ASSERT_TRUE(right && up);
  EXPECT_GT(right->x, 540);  // glTF: +x is to the right of a camera looking down -z
  EXPECT_LT(up->y, 360);
  // yfov 0.8 rad spans the 720 pixels: (0, 1, 0) at distance 5.
  EXPECT_NEAR(up->y, 360 - 360 * (1.f / 5) / std::tan(0.4f), 1e-2f);

  SurfaceInteraction si;
  ASSERT_TRUE(scene->intersect({{0, 0, 5}, {0, 0, -1}, kInfinity}, &si));
  ASSERT_NE(si.area_light, nullptr);
  const Rgb front = si.area_light->radiance(si.p, si.ng, si.uv, {0, 0, 1});
  EXPECT_NEAR(front.b, 6, 1e-4f);  // emissiveFactor x emissiveStrength
  EXPECT_TRUE(si.area_light->radiance(si.p, si.ng, si.uv, {0, 0, -1}).is_black());
}

TEST(GltfLoader, InvalidFilesFailWithTheFileName) {
  test::TempDir dir;
  const std::string path = dir.write("bad.gltf", "{ \"asset\": ");
  try {
    load_gltf(path, test::capture_warning);
    FAIL();
  } catch (const SceneLoadError& e) {
    EXPECT_EQ(std::string(e.what()).rfind(path + ": error: ", 0), 0u) << e.what();
  }
  EXPECT_THROW(load_gltf(dir.file("missing.gltf"), test::capture_warning), SceneLoadError);
}

TEST(GltfLoader, AccessorsOutOfBoundsAreErrors) {
  test::TempDir dir;
  std::string text = triangle_gltf();
  const std::string from = "\"count\": 3, \"type\": \"VEC3\"";
  text.replace(text.find(from), from.size(), "\"count\": 30, \"type\": \"VEC3\"");
  EXPECT_THROW(load_gltf(dir.write("oob.gltf", text), test::capture_warning), SceneLoadError);
}

}  // namespace
}  // namespace caustica
