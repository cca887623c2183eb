// Hostile and broken input for the scene loaders: every case must end in a SceneLoadError
// that says where and what ("file:line:col: error: ..."; for glTF the file and a JSON path
// such as "accessors[0]"), before any rendering, without a crash, and without allocating
// memory for a size that the input claims but does not back with data.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <new>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "io/gltf/gltf_loader.h"
#include "io/scene_builder.h"
#include "io/scene_loader.h"
#include "lights/light.h"
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
namespace fs = std::filesystem;

std::vector<std::string> g_warnings;
void collect(const std::string& w) { g_warnings.push_back(w); }

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

bool contains(const std::string& text, const std::string& part) {
  return text.find(part) != std::string::npos;
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
