// Every input the fuzzers (fuzz/pbrt_fuzzer.cpp, fuzz/ply_fuzzer.cpp) found to crash or hang the
// loader stays here as a regression test: each must now load or fail with a located SceneLoadError.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <sstream>

#include "io/pbrt/pbrt_loader.h"
#include "io/pbrt/ply_reader.h"
#include "io/scene_builder.h"

namespace caustica {
namespace {

void ignore_warning(const std::string&) {}

TEST(PbrtCrashers, EveryFuzzerFindingFailsCleanly) {
  const std::filesystem::path dir = std::filesystem::path(CAUSTICA_TEST_DATA) / "pbrt_crashers";
  int count = 0;
  for (const auto& entry : std::filesystem::directory_iterator(dir)) {
    if (entry.path().filename() == "README.md") continue;
    std::ifstream in(entry.path(), std::ios::binary);
    std::stringstream s;
    s << in.rdbuf();
    SCOPED_TRACE(entry.path().filename().string());
    if (entry.path().filename().string().rfind("ply-", 0) == 0) {
      // Findings of fuzz/ply_fuzzer.cpp: a mesh or a std::runtime_error, nothing else.
      try {
        pbrt::parse_ply(s.str());
      } catch (const std::runtime_error&) {
      }
      ++count;
      continue;
    }
    SceneBuilder builder;
    try {
      parse_pbrt_string(s.str(), "crasher.pbrt", builder, ignore_warning, 1000000);
    } catch (const SceneLoadError& e) {
      EXPECT_EQ(std::string(e.what()).rfind("crasher.pbrt", 0), 0u) << e.what();
    }
    ++count;
  }
  std::printf("%d crasher inputs\n", count);
}

}  // namespace
}  // namespace caustica
