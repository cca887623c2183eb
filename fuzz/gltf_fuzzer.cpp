// libFuzzer target for the glTF loader: tinygltf's parser (JSON and GLB), the image header
// checks and decoding, and our conversion into a SceneBuilder, from memory (external URIs are
// errors) and without building the Embree scene. Any outcome other than success or a
// SceneLoadError (a crash, a sanitizer report, another exception, a hang, an allocation
// beyond -rss_limit_mb) is a bug. See README.md.
#include <cstddef>
#include <cstdint>
#include <string>

#include "io/gltf/gltf_loader.h"
#include "io/load_error.h"
#include "io/scene_builder.h"

namespace {
void ignore_warning(const std::string&) {}
}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string bytes(reinterpret_cast<const char*>(data), size);
  caustica::SceneBuilder builder;
  try {
    // The triangle bound keeps large meshes instanced by many nodes from exhausting memory.
    caustica::parse_gltf_memory(bytes, "fuzz.gltf", builder, ignore_warning, -1, 200000);
  } catch (const caustica::SceneLoadError&) {
  }
  return 0;
}
