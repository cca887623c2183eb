// Hostile and broken glTF input: every case must end in a SceneLoadError that says where and
// what (the file and a JSON path such as "accessors[0]"), before any rendering, without a crash,
// and without allocating memory for a size that the input claims but does not back with data.
// The pbrt-v4 loader's hostile input, and scene paths that are directories for every loader:
// pbrt_hostile_test.cpp.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <limits>
#include <new>
#include <nlohmann/json.hpp>
#include <string>

#include "io/gltf/gltf_loader.h"
#include "io/scene_builder.h"
#include "io/scene_loader.h"
#include "loader_hostile_helpers.h"
#include "pbrt_test_util.h"

// ---------------------------------------------------------------------------------------------
// Allocation probe. The test binary's global operator new records the largest request made
// on a thread while a probe is armed there, and refuses (std::bad_alloc) any request above
// kRefuseAbove, so that a loader that would allocate gigabytes for a lie in its input shows
// it here without touching that memory. Peak RSS (getrusage) would be a weaker check: it is
// a process-wide high-water mark that earlier tests may already have raised. Unarmed, this
// is plain malloc/free.
namespace alloc_probe {
thread_local bool armed = false;
thread_local size_t largest = 0;
constexpr size_t kRefuseAbove = size_t(64) << 20;

struct Scope {
  Scope() {
    largest = 0;
    armed = true;
  }
  ~Scope() { armed = false; }
};

void* allocate(size_t size) {
  if (armed) {
    largest = std::max(largest, size);
    if (size > kRefuseAbove) return nullptr;
  }
  return std::malloc(size ? size : 1);
}
void* allocate_or_throw(size_t size) {
  if (void* p = allocate(size)) return p;
  throw std::bad_alloc();
}
}  // namespace alloc_probe

// Every non-aligned form is replaced, all on malloc/free, so that whichever pair the library
// uses (nothrow new with plain delete, sized delete, ...) matches: under ASan, whose runtime
// supplies the forms left out, a malloc'd block reaching its operator delete is reported as a
// mismatch. The aligned forms are left alone; they pair among themselves.
void* operator new(size_t size) { return alloc_probe::allocate_or_throw(size); }
void* operator new[](size_t size) { return alloc_probe::allocate_or_throw(size); }
void* operator new(size_t size, const std::nothrow_t&) noexcept {
  return alloc_probe::allocate(size);
}
void* operator new[](size_t size, const std::nothrow_t&) noexcept {
  return alloc_probe::allocate(size);
}
// GCC sees operator new's pointer reach free() once these are inlined and warns; new is
// malloc here, so they match.
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wpragmas"
#pragma GCC diagnostic ignored "-Wmismatched-new-delete"
void operator delete(void* p) noexcept { std::free(p); }
void operator delete[](void* p) noexcept { std::free(p); }
void operator delete(void* p, size_t) noexcept { std::free(p); }
void operator delete[](void* p, size_t) noexcept { std::free(p); }
void operator delete(void* p, const std::nothrow_t&) noexcept { std::free(p); }
void operator delete[](void* p, const std::nothrow_t&) noexcept { std::free(p); }
#pragma GCC diagnostic pop

namespace caustica {
namespace {

using nlohmann::json;
using test::collect;
using test::contains;
using test::g_warnings;
namespace fs = std::filesystem;

// ---------------------------------------------------------------------------------------------
// glTF

std::string base64(const std::string& in) {
  static const char* t = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
  std::string out;
  for (size_t i = 0; i < in.size(); i += 3) {
    const uint32_t n = (uint32_t(uint8_t(in[i])) << 16) |
                       (i + 1 < in.size() ? uint32_t(uint8_t(in[i + 1])) << 8 : 0) |
                       (i + 2 < in.size() ? uint32_t(uint8_t(in[i + 2])) : 0);
    out += t[(n >> 18) & 63];
    out += t[(n >> 12) & 63];
    out += i + 1 < in.size() ? t[(n >> 6) & 63] : '=';
    out += i + 2 < in.size() ? t[n & 63] : '=';
  }
  return out;
}

// One triangle (positions: 36 bytes, then 3 uint16 indices padded to 8), a camera looking
// at it, a point light, in a 44-byte buffer; `buffer_uri` set to a data: URI.
json triangle_model() {
  std::string bin(44, '\0');
  const float p[9] = {-1, -1, 0, 1, -1, 0, 0, 1, 0};
  const uint16_t idx[4] = {0, 1, 2, 0};
  std::memcpy(bin.data(), p, 36);
  std::memcpy(bin.data() + 36, idx, 8);
  return {
      {"asset", {{"version", "2.0"}}},
      {"scene", 0},
      {"scenes", {{{"nodes", {0, 1, 2}}}}},
      {"nodes",
       {{{"mesh", 0}},
        {{"camera", 0}, {"translation", {0, 0, 5}}},
        {{"translation", {0, 3, 0}}, {"extensions", {{"KHR_lights_punctual", {{"light", 0}}}}}}}},
      {"cameras", {{{"type", "perspective"}, {"perspective", {{"yfov", 0.8}, {"znear", 0.1}}}}}},
      {"extensionsUsed", {"KHR_lights_punctual"}},
      {"extensions",
       {{"KHR_lights_punctual", {{"lights", {{{"type", "point"}, {"intensity", 10}}}}}}}},
      {"meshes", {{{"primitives", {{{"attributes", {{"POSITION", 0}}}, {"indices", 1}}}}}}},
      {"accessors",
       {{{"bufferView", 0}, {"componentType", 5126}, {"count", 3}, {"type", "VEC3"}},
        {{"bufferView", 1}, {"componentType", 5123}, {"count", 3}, {"type", "SCALAR"}}}},
      {"bufferViews",
       {{{"buffer", 0}, {"byteOffset", 0}, {"byteLength", 36}},
        {{"buffer", 0}, {"byteOffset", 36}, {"byteLength", 6}}}},
      {"buffers",
       {{{"byteLength", 44}, {"uri", "data:application/octet-stream;base64," + base64(bin)}}}},
  };
}

// The message of parsing `bytes` from memory, or "" if it parses.
std::string gltf_error(const std::string& bytes, int camera_index = -1) {
  g_warnings.clear();
  SceneBuilder builder;
  try {
    parse_gltf_memory(bytes, "hostile.gltf", builder, collect, camera_index);
  } catch (const SceneLoadError& e) {
    return e.what();
  }
  return "";
}

// The message, also checking that the load allocated nothing near what the input claims.
std::string gltf_error_small_allocations(const std::string& bytes, size_t* largest) {
  std::string message;
  {
    alloc_probe::Scope probe;
    message = gltf_error(bytes);
  }
  *largest = alloc_probe::largest;
  return message;
}

TEST(GltfHostile, TheBaseModelLoads) {
  // The cases below each break one thing in this model.
  EXPECT_EQ(gltf_error(triangle_model().dump()), "");
}

TEST(GltfHostile, AccessorCountBeyondItsBufferFailsBeforeAllocating) {
  // The case: under 1 KB of JSON whose POSITION accessor claims 2^27 VEC3 floats
  // (1.6 GB). The old loader sized its output vector from the count before checking it.
  json j = triangle_model();
  j["accessors"][0]["count"] = 134217728;
  const std::string text = j.dump();
  ASSERT_LT(text.size(), 1024u);
  size_t largest = 0;
  const std::string e = gltf_error_small_allocations(text, &largest);
  EXPECT_EQ(e.rfind("hostile.gltf: error: accessors[0]: count 134217728", 0), 0u) << e;
  EXPECT_TRUE(contains(e, "36 bytes of bufferViews[0]")) << e;
  EXPECT_LT(largest, size_t(1) << 20) << "largest allocation during the load";
}

TEST(GltfHostile, AccessorCountThatWrapsSizeArithmeticIsCaught) {
  // count * 3 and count * 12 wrap around 2^64 to small numbers (2 and 8): a check written
  // as begin + (count - 1) * stride + size <= length passes, and the reads run off the heap.
  json j = triangle_model();
  j["accessors"][0]["count"] = 6148914691236517206ull;
  size_t largest = 0;
  const std::string e = gltf_error_small_allocations(j.dump(), &largest);
  EXPECT_TRUE(contains(e, "accessors[0]: count 6148914691236517206")) << e;
  EXPECT_LT(largest, size_t(1) << 20);
}

TEST(GltfHostile, AccessorAndBufferViewOffsetsAreCheckedWithoutOverflow) {
  json j = triangle_model();
  j["accessors"][1]["byteOffset"] = 18446744073709551615ull;  // indices
  EXPECT_TRUE(contains(gltf_error(j.dump()), "accessors[1]: count 3")) << gltf_error(j.dump());
  j = triangle_model();
  j["bufferViews"][0]["byteOffset"] = 18446744073709551612ull;
  EXPECT_TRUE(contains(gltf_error(j.dump()), "bufferViews[0]: byteOffset 18446744073709551612"));
  j = triangle_model();
  j["bufferViews"][0]["byteStride"] = 252;  // 3 elements 252 bytes apart need 516 bytes
  EXPECT_TRUE(contains(gltf_error(j.dump()), "accessors[0]: count 3")) << gltf_error(j.dump());
}

TEST(GltfHostile, IndexCountBeyondItsBufferFailsBeforeAllocating) {
  json j = triangle_model();
  j["accessors"][1]["count"] = 1000000000;
  size_t largest = 0;
  const std::string e = gltf_error_small_allocations(j.dump(), &largest);
  EXPECT_TRUE(contains(e, "accessors[1]: count 1000000000")) << e;
  EXPECT_LT(largest, size_t(1) << 20);
}

TEST(GltfHostile, AccessorWithoutBufferViewAllocatesNothing) {
  // The spec's "all zeros" accessor (meant for sparse ones): nothing backs its count. Its
  // primitive is skipped with a warning instead of a billion vertices at the origin.
  json j = triangle_model();
  j["accessors"][0].erase("bufferView");
  j["accessors"][0]["count"] = 1000000000;
  size_t largest = 0;
  EXPECT_EQ(gltf_error_small_allocations(j.dump(), &largest), "");
  EXPECT_LT(largest, size_t(1) << 20);
  EXPECT_EQ(test::count_containing(g_warnings, "accessors[0] has no bufferView"), 1);
}

TEST(GltfHostile, NonFiniteVertexIsAnError) {
  json j = triangle_model();
  std::string bin(44, '\0');
  const float nan = std::numeric_limits<float>::quiet_NaN();
  const float p[9] = {-1, -1, 0, 1, nan, 0, 0, 1, 0};
  std::memcpy(bin.data(), p, 36);
  j["buffers"][0]["uri"] = "data:application/octet-stream;base64," + base64(bin);
  EXPECT_TRUE(contains(gltf_error(j.dump()),
                       "accessors[0]: meshes[0].primitives[0] POSITION "
                       "element 1 is not a finite number"))
      << gltf_error(j.dump());
}

TEST(GltfHostile, NegativeOrHugeYfovIsAnError) {
  json j = triangle_model();
  j["cameras"][0]["perspective"]["yfov"] = -0.8;
  EXPECT_TRUE(contains(gltf_error(j.dump()),
                       "cameras[0].perspective.yfov: expected an angle "
                       "in radians in (0, pi), got -0.8"))
      << gltf_error(j.dump());
  j["cameras"][0]["perspective"]["yfov"] = 4.0;
  EXPECT_TRUE(contains(gltf_error(j.dump()), "cameras[0].perspective.yfov"))
      << gltf_error(j.dump());
  j["cameras"][0]["perspective"]["yfov"] = 0.8;
  j["cameras"][0]["perspective"]["aspectRatio"] = -1.5;
  EXPECT_TRUE(contains(gltf_error(j.dump()), "cameras[0].perspective.aspectRatio"))
      << gltf_error(j.dump());
}

TEST(GltfHostile, CameraIndexOutOfRangeNamesTheCameraCount) {
  const std::string text = triangle_model().dump();
  EXPECT_EQ(gltf_error(text, 0), "");
  EXPECT_EQ(gltf_error(text, -1), "");  // the default camera
  EXPECT_EQ(gltf_error(text, -2),
            "hostile.gltf: error: camera index -2 is out of range: the file has 1 camera "
            "(index 0)");
  EXPECT_TRUE(contains(gltf_error(text, 1),
                       "camera index 1 is out of range: the file has 1 "
                       "camera"));
  json j = triangle_model();
  j.erase("cameras");
  j["nodes"][1].erase("camera");
  EXPECT_TRUE(contains(gltf_error(j.dump(), 0), "the file has no cameras"));
  // Through load_scene and LoadOptions, as the command line passes it.
  test::TempDir dir;
  LoadOptions options;
  options.warn = collect;
  options.camera_index = 7;
  try {
    load_scene(dir.write("cams.gltf", text), options);
    FAIL() << "expected an error";
  } catch (const SceneLoadError& e) {
    EXPECT_TRUE(contains(e.what(), "camera index 7 is out of range: the file has 1 camera"))
        << e.what();
  }
}

TEST(GltfHostile, NodeReachedTwiceIsAnError) {
  // Two references to one child: with a chain of such nodes a few hundred bytes would ask
  // for 2^depth copies of a mesh.
  json j = triangle_model();
  j["nodes"].push_back({{"children", {0, 0}}});
  j["scenes"][0]["nodes"] = {3, 1};
  EXPECT_TRUE(contains(gltf_error(j.dump()), "nodes[0] is reached twice")) << gltf_error(j.dump());
  j = triangle_model();
  j["scenes"][0]["nodes"] = {0, 1, 2, 0};
  EXPECT_TRUE(contains(gltf_error(j.dump()), "nodes[0] is reached twice"));
}

TEST(GltfHostile, LightIntensityThatOverflowsIsAnError) {
  json j = triangle_model();
  j["extensions"]["KHR_lights_punctual"]["lights"][0]["intensity"] = 1e39;  // a double, not a float
  EXPECT_TRUE(contains(gltf_error(j.dump()), "KHR_lights_punctual.lights[0].intensity"))
      << gltf_error(j.dump());
  j["extensions"]["KHR_lights_punctual"]["lights"][0]["intensity"] = -5;
  EXPECT_TRUE(contains(gltf_error(j.dump()), "lights[0].intensity: expected a finite number >= 0"));
  j["extensions"]["KHR_lights_punctual"]["lights"][0]["intensity"] = 1e38;  // 4 pi I overflows
  EXPECT_TRUE(contains(gltf_error(j.dump()), "lights[0]: intensity overflows to infinity"))
      << gltf_error(j.dump());
}

TEST(GltfHostile, GlbBinChunkPastTheEndIsAnError) {
  // tinygltf 2.7 compares the BIN chunk's length with the file without its 8-byte header,
  // so a chunk claiming 8 bytes more than there are was read past the end of the file.
  json j = triangle_model();
  j["buffers"][0].erase("uri");
  j["buffers"][0]["byteLength"] = 52;
  std::string text = j.dump();
  while (text.size() % 4) text += ' ';
  std::string bin(44, '\0');
  const float p[9] = {-1, -1, 0, 1, -1, 0, 0, 1, 0};
  std::memcpy(bin.data(), p, 36);
  std::string glb;
  auto u32 = [&](uint32_t v) { glb.append(reinterpret_cast<const char*>(&v), 4); };
  u32(0x46546C67);
  u32(2);
  u32(uint32_t(12 + 8 + text.size() + 8 + bin.size()));
  u32(uint32_t(text.size()));
  u32(0x4E4F534A);
  glb += text;
  u32(uint32_t(bin.size() + 8));  // the lie
  u32(0x004E4942);
  glb += bin;
  EXPECT_EQ(gltf_error(glb),
            "hostile.gltf: error: GLB: the BIN chunk (52 bytes) runs past the end");
}

TEST(GltfHostile, DeeplyNestedJsonIsAnError) {
  // tinygltf converts extras recursively; 100000 levels would overflow the stack.
  std::string text = triangle_model().dump();
  text.pop_back();
  text += ",\"extras\":" + std::string(100000, '[') + std::string(100000, ']') + "}";
  EXPECT_TRUE(contains(gltf_error(text), "JSON nested deeper than 256 levels"));
}

TEST(GltfHostile, ImageHeaderClaimingMorePixelsThanItsDataIsAnError) {
  // A PNG header for 16000 x 16000 RGBA pixels in a 57-byte file: stb_image would allocate
  // the 1 GB image before finding that the data is missing. (Above 2^30 bytes stb_image
  // refuses by itself.)
  std::string png = "\x89PNG\r\n\x1a\n";
  auto be32 = [&](uint32_t v) {
    for (int s = 24; s >= 0; s -= 8) png += char((v >> s) & 0xFF);
  };
  be32(13);
  png += "IHDR";
  be32(16000);
  be32(16000);
  png += std::string("\x08\x06\x00\x00\x00", 5);
  be32(0);  // CRC, which stb_image does not check
  be32(0);
  png += "IEND";
  be32(0);
  json j = triangle_model();
  j["images"] = {{{"uri", "data:image/png;base64," + base64(png)}}};
  const std::string e = gltf_error(j.dump());
  EXPECT_TRUE(contains(e, "images[0]: its header claims 16000x16000 pixels, more than its")) << e;
}

TEST(GltfHostile, ImageBufferViewOutsideItsBufferIsAnError) {
  // tinygltf hands the image decoder &buffer.data[byteOffset] and byteLength unchecked.
  json j = triangle_model();
  j["bufferViews"].push_back({{"buffer", 0}, {"byteOffset", 4096}, {"byteLength", 100000}});
  j["images"] = {{{"bufferView", 2}, {"mimeType", "image/png"}}};
  EXPECT_TRUE(contains(gltf_error(j.dump()),
                       "images[0]: bufferViews[2] lies outside its buffer "
                       "(44 bytes)"))
      << gltf_error(j.dump());
}

TEST(GltfHostile, TinygltfMessagesAreEscapedAndShort) {
  // tinygltf quotes a whole undecodable data: URI in its message.
  json j = triangle_model();
  j["buffers"][0]["uri"] =
      "data:application/octet-stream;base64,!!" + std::string(5000, 'A') + "\x1b[31m";
  const std::string e = gltf_error(j.dump());
  EXPECT_EQ(e.rfind("hostile.gltf: error: ", 0), 0u);
  EXPECT_LT(e.size(), 400u) << e;
  EXPECT_EQ(e.find('\x1b'), std::string::npos);
}

TEST(GltfHostile, BufferUriThatIsADirectoryIsAnError) {
  test::TempDir dir;
  fs::create_directories(dir.file("buffer.bin"));
  json j = triangle_model();
  j["buffers"][0]["uri"] = "buffer.bin";
  const std::string path = dir.write("dir.gltf", j.dump());
  try {
    load_gltf(path, collect);
    FAIL() << "expected an error";
  } catch (const SceneLoadError& e) {
    EXPECT_EQ(std::string(e.what()).rfind(path + ": error: ", 0), 0u) << e.what();
    EXPECT_TRUE(contains(e.what(), "buffer.bin : is a directory")) << e.what();
  }
  // The same bytes from memory: no file access at all.
  EXPECT_TRUE(contains(gltf_error(j.dump()), "file access is disabled")) << gltf_error(j.dump());
}

TEST(GltfHostile, ExternalBufferLoadsNextToTheFile) {
  // The positive case of the file callbacks that replaced tinygltf's own.
  test::TempDir dir;
  std::string bin(44, '\0');
  const float p[9] = {-1, -1, 0, 1, -1, 0, 0, 1, 0};
  const uint16_t idx[4] = {0, 1, 2, 0};
  std::memcpy(bin.data(), p, 36);
  std::memcpy(bin.data() + 36, idx, 8);
  dir.write("mesh.bin", bin);
  json j = triangle_model();
  j["buffers"][0]["uri"] = "mesh.bin";
  auto scene = load_gltf(dir.write("external.gltf", j.dump()), collect);
  EXPECT_EQ(scene->triangle_count(), 1u);
}

}  // namespace
}  // namespace caustica
