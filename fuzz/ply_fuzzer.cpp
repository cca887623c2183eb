// libFuzzer target for the PLY reader: any outcome other than a mesh or std::runtime_error
// is a bug. See README.md.
#include <cstddef>
#include <cstdint>
#include <stdexcept>
#include <string>

#include "io/pbrt/ply_reader.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  try {
    caustica::pbrt::parse_ply(std::string(reinterpret_cast<const char*>(data), size));
  } catch (const std::runtime_error&) {
  }
  return 0;
}
