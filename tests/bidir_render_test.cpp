// The bidirectional family's own end-to-end behaviour: per-technique images add up to the image.
// The oracles every integrator runs (furnaces, agreement with pt, thread determinism) are in
// registry_oracles_test.cpp, driven by the registry.
#include <gtest/gtest.h>

#include <filesystem>

#include "image/image_io.h"
#include "integrators/bidir/mis.h"
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

// --merge-mis-scale changes only how the techniques share a path (the merges' count in the
// weights), never what they estimate: inside the furnace (radiance Le / (1 - a) everywhere, so
// merging has no kernel bias) vcm stays unbiased whether merging is trusted 4x less or 4x more,
// and the images differ from the balance heuristic's at the same seed.
TEST(BidirMergeMisScale, WeightsChangeButTheFurnaceStaysExact) {
  const FurnaceParams p{0.5f, 1.5f};  // radiance 3
  auto scene = make_furnace_scene(p, 24, 24);
  IntegratorSettings s;
  s.max_depth = 200;
  s.bidir.radius = 0.05f;
  const Image balance = render_with(*scene, "vcm", 4, s).image;
  for (float scale : {0.25f, 4.f}) {
    s.bidir.merge_mis_scale = scale;
    s.seed = 0;
    const Image scaled = render_with(*scene, "vcm", 4, s).image;
    double moved = 0;
    for (size_t i = 0; i < scaled.pixel_count(); ++i)
      moved += std::abs(scaled[i].average() - balance[i].average());
    EXPECT_GT(moved / double(scaled.pixel_count()), 1e-3) << "scale " << scale << " was ignored";
    const auto [m, se] = over_seeds(6, [&](uint64_t seed) {
      s.seed = seed;
      return pixel_stats(render_with(*scene, "vcm", 8, s).image).mean;
    });
    EXPECT_NEAR(m, p.expected_radiance(), 3 * se + 1e-5) << "scale " << scale;
  }
}

// --merge-mis correlation-aware (Grittmann et al. 2021) lowers each merge's count by how much
// of its path the merges around it share; the weights still sum to one (BidirMisPartition's
// correlated cases check the terms against the brute-force oracle), so inside the furnace vcm
// stays unbiased, the images differ from the balance heuristic's at the same seed, and the
// stored light vertices' merges make the render bit-identical for one and two threads.
TEST(BidirCorrelationAwareMis, WeightsChangeButTheFurnaceStaysExact) {
  const FurnaceParams p{0.5f, 1.5f};  // radiance 3
  auto scene = make_furnace_scene(p, 24, 24);
  IntegratorSettings s;
  s.max_depth = bidir::CorrelationTrack::kMaxEntries;  // the most it takes
  s.bidir.radius = 0.05f;
  const Image balance = render_with(*scene, "vcm", 4, s).image;
  s.bidir.correlation_aware = true;
  const Image correlated = render_with(*scene, "vcm", 4, s).image;
  double moved = 0;
  for (size_t i = 0; i < correlated.pixel_count(); ++i)
    moved += std::abs(correlated[i].average() - balance[i].average());
  EXPECT_GT(moved / double(correlated.pixel_count()), 1e-3) << "correlation-aware MIS was ignored";
  const auto [m, se] = over_seeds(6, [&](uint64_t seed) {
    s.seed = seed;
    return pixel_stats(render_with(*scene, "vcm", 8, s).image).mean;
  });
  EXPECT_NEAR(m, p.expected_radiance(), 3 * se + 1e-5);
}

TEST(BidirCorrelationAwareMis, BitIdenticalForOneAndTwoThreads) {
  auto scene = make_builtin_scene("cornell-glass", 40, 40);
  IntegratorSettings s;
  s.bidir.light_paths = 3000;  // not a multiple of the light-path chunk size
  s.bidir.correlation_aware = true;
  const auto a = render_with(*scene, "vcm", 3, s, 1);
  const auto b = render_with(*scene, "vcm", 3, s, 2);
  size_t differing = 0;
  for (size_t i = 0; i < a.image.pixel_count(); ++i) differing += !(a.image[i] == b.image[i]);
  EXPECT_EQ(differing, 0u);
}
