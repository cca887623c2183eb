// Every input fuzz/gltf_fuzzer.cpp found to crash, hang or exhaust memory stays here as a
// regression test: each must now load or fail with a SceneLoadError naming the file. The
// fuzzer's seeds (fuzz/gltf_seeds/) are valid files and must load.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <sstream>

#include "io/gltf/gltf_loader.h"
#include "io/scene_builder.h"

namespace caustica {
namespace {

void ignore_warning(const std::string&) {}

std::string read_bytes(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

// Same call as the fuzzer (from memory, no file access, a triangle bound).
void parse_like_the_fuzzer(const std::string& bytes, SceneBuilder& builder) {
  parse_gltf_memory(bytes, "crasher.gltf", builder, ignore_warning, -1, 200000);
}

TEST(GltfCrashers, EveryFuzzerFindingFailsCleanly) {
  const std::filesystem::path dir = std::filesystem::path(CAUSTICA_TEST_DATA) / "gltf_crashers";
  int count = 0;
  for (const auto& entry : std::filesystem::directory_iterator(dir)) {
    if (entry.path().filename() == "README.md") continue;
    SCOPED_TRACE(entry.path().filename().string());
    SceneBuilder builder;
    try {
      parse_like_the_fuzzer(read_bytes(entry.path()), builder);
    } catch (const SceneLoadError& e) {
      EXPECT_EQ(std::string(e.what()).rfind("crasher.gltf: error: ", 0), 0u) << e.what();
    }
    ++count;
  }
  std::printf("%d crasher inputs\n", count);
}

TEST(GltfCrashers, FuzzerSeedsLoad) {
  const std::filesystem::path dir =
      std::filesystem::path(CAUSTICA_TEST_DATA).parent_path().parent_path() / "fuzz" / "gltf_seeds";
  int count = 0;
  for (const auto& entry : std::filesystem::directory_iterator(dir)) {
    SCOPED_TRACE(entry.path().filename().string());
    SceneBuilder builder;
    EXPECT_NO_THROW(parse_like_the_fuzzer(read_bytes(entry.path()), builder));
    ++count;
  }
  EXPECT_GE(count, 8);
}

}  // namespace
}  // namespace caustica
