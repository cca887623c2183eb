// glTF 2.0 import: files are built here, ASCII (.gltf, buffer as a data URI) and binary (.glb).
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>

#include "io/gltf/gltf_loader.h"
#include "io/scene_loader.h"
#include "lights/light.h"
#include "materials/material.h"
#include "test_scenes.h"

using namespace caustica;
namespace fs = std::filesystem;

namespace {

std::string base64(const std::string& in) {
  static const char* t = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
  std::string out;
  size_t i = 0;
  for (; i + 2 < in.size(); i += 3) {
    const uint32_t v = (uint8_t(in[i]) << 16) | (uint8_t(in[i + 1]) << 8) | uint8_t(in[i + 2]);
    out += {t[v >> 18], t[(v >> 12) & 63], t[(v >> 6) & 63], t[v & 63]};
  }
  if (i + 1 == in.size()) {
    const uint32_t v = uint8_t(in[i]) << 16;
    out += {t[v >> 18], t[(v >> 12) & 63], '=', '='};
  } else if (i + 2 == in.size()) {
    const uint32_t v = (uint8_t(in[i]) << 16) | (uint8_t(in[i + 1]) << 8);
    out += {t[v >> 18], t[(v >> 12) & 63], t[(v >> 6) & 63], '='};
  }
  return out;
}

template <typename T>
void append(std::string& buf, const std::vector<T>& v) {
  buf.append(reinterpret_cast<const char*>(v.data()), v.size() * sizeof(T));
}

// A floor quad (y = 0, 4x4) with a white material, an emissive quad above it facing down
// (y = 3), a perspective camera at (0, 1, 5) looking down -z, and a point light. Returns
// the JSON and the binary buffer.
std::pair<nlohmann::json, std::string> test_model() {
  std::string bin;
  const std::vector<float> floor = {-2, 0, -2, 2, 0, -2, 2, 0, 2, -2, 0, 2};
  const std::vector<float> lamp = {-0.5f, 3, -0.5f, 0.5f, 3, -0.5f, 0.5f, 3, 0.5f, -0.5f, 3, 0.5f};
  const std::vector<uint16_t> floor_idx = {0, 2, 1, 0, 3, 2};  // counter-clockwise seen from +y
  const std::vector<uint16_t> lamp_idx = {0, 1, 2, 0, 2, 3};   // faces -y
  append(bin, floor);                                          // offset 0, 48 bytes
  append(bin, lamp);                                           // offset 48, 48 bytes
  append(bin, floor_idx);                                      // offset 96, 12 bytes
  append(bin, lamp_idx);                                       // offset 108, 12 bytes
  nlohmann::json j = {
      {"asset", {{"version", "2.0"}}},
      {"extensionsUsed",
       {"KHR_lights_punctual", "KHR_materials_emissive_strength", "KHR_materials_transmission"}},
      {"scene", 0},
      {"scenes", {{{"nodes", {0, 1, 2, 3}}}}},
      {"nodes",
       {{{"mesh", 0}},
        {{"mesh", 1}},
        {{"camera", 0}, {"translation", {0, 1, 5}}},
        {{"translation", {1, 2, 0}}, {"extensions", {{"KHR_lights_punctual", {{"light", 0}}}}}}}},
      {"cameras",
       {{{"type", "perspective"},
         {"perspective", {{"yfov", 0.8}, {"aspectRatio", 1.5}, {"znear", 0.1}}}}}},
      {"extensions",
       {{"KHR_lights_punctual",
         {{"lights", {{{"type", "point"}, {"color", {1, 0.5, 0.25}}, {"intensity", 4}}}}}}}},
      {"meshes",
       {{{"primitives", {{{"attributes", {{"POSITION", 0}}}, {"indices", 2}, {"material", 0}}}}},
        {{"primitives", {{{"attributes", {{"POSITION", 1}}}, {"indices", 3}, {"material", 1}}}}}}},
      {"materials",
       {{{"pbrMetallicRoughness",
          {{"baseColorFactor", {0.8, 0.8, 0.8, 1}},
           {"metallicFactor", 0.0},
           {"roughnessFactor", 1.0}}}},
        {{"pbrMetallicRoughness", {{"baseColorFactor", {0, 0, 0, 1}}}},
         {"emissiveFactor", {1, 1, 1}},
         {"extensions", {{"KHR_materials_emissive_strength", {{"emissiveStrength", 5}}}}}}}},
      {"accessors",
       {{{"bufferView", 0},
         {"componentType", 5126},
         {"count", 4},
         {"type", "VEC3"},
         {"min", {-2, 0, -2}},
         {"max", {2, 0, 2}}},
        {{"bufferView", 1},
         {"componentType", 5126},
         {"count", 4},
         {"type", "VEC3"},
         {"min", {-0.5, 3, -0.5}},
         {"max", {0.5, 3, 0.5}}},
        {{"bufferView", 2}, {"componentType", 5123}, {"count", 6}, {"type", "SCALAR"}},
        {{"bufferView", 3}, {"componentType", 5123}, {"count", 6}, {"type", "SCALAR"}}}},
      {"bufferViews",
       {{{"buffer", 0}, {"byteOffset", 0}, {"byteLength", 48}},
        {{"buffer", 0}, {"byteOffset", 48}, {"byteLength", 48}},
        {{"buffer", 0}, {"byteOffset", 96}, {"byteLength", 12}},
        {{"buffer", 0}, {"byteOffset", 108}, {"byteLength", 12}}}},
      {"buffers", {{{"byteLength", bin.size()}}}},
  };
  return {j, bin};
}

fs::path write_gltf(const std::string& name) {
  auto [j, bin] = test_model();
  j["buffers"][0]["uri"] = "data:application/octet-stream;base64," + base64(bin);
  const fs::path p = fs::path(testing::TempDir()) / name;
  std::ofstream(p) << j.dump();
  return p;
}

fs::path write_glb(const std::string& name) {
  auto [j, bin] = test_model();
  std::string json = j.dump();
  while (json.size() % 4) json += ' ';
  while (bin.size() % 4) bin += '\0';
  const uint32_t total = 12 + 8 + uint32_t(json.size()) + 8 + uint32_t(bin.size());
  std::string out;
  auto u32 = [&](uint32_t v) { out.append(reinterpret_cast<const char*>(&v), 4); };
  u32(0x46546C67);  // "glTF"
  u32(2);
  u32(total);
  u32(uint32_t(json.size()));
  u32(0x4E4F534A);  // "JSON"
  out += json;
  u32(uint32_t(bin.size()));
  u32(0x004E4942);  // "BIN\0"
  out += bin;
  const fs::path p = fs::path(testing::TempDir()) / name;
  std::ofstream(p, std::ios::binary) << out;
  return p;
}

std::vector<std::string> g_warnings;
void collect(const std::string& w) { g_warnings.push_back(w); }

}  // namespace

TEST(GltfImport, LoadsMeshesLightsAndCamera) {
  const fs::path p = write_gltf("scene.gltf");
  auto scene = load_gltf(p.string(), collect, 0);
  EXPECT_EQ(scene->triangle_count(), 4u);
  // Two emissive triangles become area lights, plus the punctual point light.
  ASSERT_EQ(scene->lights().size(), 3u);
  // The camera: 720 high, aspect 1.5, yfov 0.8 rad on the (shorter) vertical axis.
  EXPECT_EQ(scene->camera().height(), 720);
  EXPECT_EQ(scene->camera().width(), 1080);
  // It sits at (0, 1, 5) looking down -z: a point straight ahead lands in the image centre,
  // +x (right-handed glTF) on the right, +y at the top.
  const auto centre = scene->camera().project({0, 1, 0});
  ASSERT_TRUE(centre.has_value());
  EXPECT_NEAR(centre->x, 540, 0.5);
  EXPECT_NEAR(centre->y, 360, 0.5);
  EXPECT_GT(scene->camera().project({1, 1, 0})->x, 540.f);
  EXPECT_LT(scene->camera().project({0, 2, 0})->y, 360.f);
  // Vertical fov: the top edge of the image is yfov/2 above the axis.
  const Ray top = scene->camera().generate_ray({540, 0}, {0.5f, 0.5f});
  EXPECT_NEAR(std::acos(dot(top.d, Vec3(0, 0, -1))), 0.4, 1e-3);
}

TEST(GltfImport, EmissiveStrengthScalesAreaLightsAndMaterialsMap) {
  auto scene = load_gltf(write_gltf("scene2.gltf").string(), collect, 0);
  SurfaceInteraction si;
  // From the floor straight up we hit the lamp's emitting (downward) side.
  ASSERT_TRUE(scene->intersect({{0, 0.01f, 0}, {0, 1, 0}, kInfinity}, &si));
  ASSERT_NE(si.area_light, nullptr);
  EXPECT_NEAR(si.area_light->radiance(si.p, si.ng, si.uv, si.wo).r, 5.f, 1e-5);
  ASSERT_TRUE(scene->intersect({{0, 1, 0}, {0, -1, 0}, kInfinity}, &si));
  ASSERT_NE(si.material, nullptr);
  EXPECT_EQ(std::string(si.material->name()), "coateddiffuse");  // metallic 0: plastic
}

TEST(GltfImport, BinaryGlbLoadsTheSameScene) {
  auto a = load_gltf(write_gltf("same.gltf").string(), collect, 0);
  auto b = load_gltf(write_glb("same.glb").string(), collect, 0);
  EXPECT_EQ(a->triangle_count(), b->triangle_count());
  EXPECT_EQ(a->lights().size(), b->lights().size());
  EXPECT_EQ(a->camera().project({0.3f, 1.2f, -1})->x, b->camera().project({0.3f, 1.2f, -1})->x);
}

TEST(GltfImport, RendersWithPathTracer) {
  auto scene = load_scene(write_gltf("render.gltf").string());
  scene->override_resolution(32, 24);
  const auto r = test::render_with(*scene, "pt", 4);
  EXPECT_EQ(r.nonfinite, 0u);
  EXPECT_GT(test::pixel_stats(r.image).mean, 0.01);
}

TEST(GltfImport, MalformedFilesGiveLocatedErrors) {
  const fs::path bad = fs::path(testing::TempDir()) / "bad.gltf";
  std::ofstream(bad) << "{ \"asset\": { \"version\": \"2.0\" }, \"nodes\": [ { \"mesh\": 7 } ], ";
  try {
    load_gltf(bad.string(), collect, 0);
    FAIL() << "expected an error";
  } catch (const SceneLoadError& e) {
    EXPECT_NE(std::string(e.what()).find(bad.string() + ": error:"), std::string::npos) << e.what();
  }
  // A camera index beyond the file's cameras is an error naming the count.
  try {
    load_gltf(write_gltf("cams.gltf").string(), collect, 3);
    FAIL() << "expected an error";
  } catch (const SceneLoadError& e) {
    EXPECT_NE(std::string(e.what()).find("camera index 3"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("1 camera"), std::string::npos) << e.what();
  }
}
