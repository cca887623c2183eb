// libFuzzer target for the pbrt-v4 tokenizer, parser and scene conversion. It parses bytes
// from memory (no file access; Include/plymesh/imagemap are errors) into a SceneBuilder
// without building the Embree scene. Any outcome other than success or a SceneLoadError
// (a crash, a sanitizer report, another exception, a hang) is a bug. See README.md.
#include <cstddef>
#include <cstdint>
#include <string>

#include "io/load_error.h"
#include "io/pbrt/pbrt_loader.h"
#include "io/scene_builder.h"

namespace {
void ignore_warning(const std::string&) {}
}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string text(reinterpret_cast<const char*>(data), size);
  caustica::SceneBuilder builder;
  try {
    // The triangle bound keeps tessellated shapes times instances from exhausting memory.
    caustica::parse_pbrt_string(text, "fuzz.pbrt", builder, ignore_warning, 200000);
  } catch (const caustica::SceneLoadError&) {
  }
  return 0;
}
