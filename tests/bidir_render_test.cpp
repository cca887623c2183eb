// The bidirectional family's own end-to-end behaviour: per-technique images add up to the image.
// The oracles every integrator runs (furnaces, agreement with pt, thread determinism) are in
// registry_oracles_test.cpp, driven by the registry.
#include <gtest/gtest.h>

#include <filesystem>

#include "image/image_io.h"
#include "io/builtin_scenes.h"
#include "test_scenes.h"

using namespace caustica;
using namespace caustica::test;

namespace {

Image add(const Image& a, const Image& b) {
  Image out = a;
  for (size_t i = 0; i < out.pixel_count(); ++i) out[i] += b[i];
  return out;
}

}  // namespace

TEST(BidirTechniques, ImagesSumToTheFinalImage) {
  auto scene = make_builtin_scene("cornell-glass", 24, 24);
  for (const char* name : {"vcm", "bpt", "lt"}) {
    const auto dir =
        std::filesystem::temp_directory_path() / ("caustica_bidir_techniques_" + std::string(name));
    std::filesystem::remove_all(dir);
    IntegratorSettings s;
    s.max_depth = 6;
    s.bidir.techniques_dir = dir.string();
    const auto r = render_with(*scene, name, 3, s);
    Image sum(r.image.width(), r.image.height());
    int files = 0;
    for (const auto& entry : std::filesystem::directory_iterator(dir)) {
      sum = add(sum, read_image(entry.path().string()));
      ++files;
    }
    EXPECT_GT(files, 3) << name;
    double max_err = 0;
    for (size_t i = 0; i < sum.pixel_count(); ++i)
      for (int c = 0; c < 3; ++c)
        max_err = std::max(max_err, double(std::abs(sum[i][c] - r.image[i][c])) /
                                        (1e-3 + std::abs(r.image[i][c])));
    EXPECT_LT(max_err, 1e-4) << name;
    std::filesystem::remove_all(dir);
  }
}
