// The camera subpaths' radiance records of guided-bpt / guided-vcm (subpath_records.h):
// what a pixel's estimate gains after a guided vertex is that vertex's incident radiance times
// its throughput, and only what comes after it.
#include "integrators/bidir/subpath_records.h"

#include <gtest/gtest.h>

#include <vector>

namespace caustica::bidir {
namespace {

SubpathRecords::Vertex vertex(int depth, float per_pdf, Rgb weight, Rgb beta_after) {
  SubpathRecords::Vertex v;
  v.depth = depth;
  v.per_pdf = per_pdf;
  v.weight = weight;
  v.beta_after = beta_after;
  return v;
}

struct Pushed {
  int depth;
  float radiance, product;
};

TEST(SubpathRecords, EachVertexGetsWhatArrivedAfterItOverItsThroughput) {
  ScratchArena arena;
  SubpathRecords records(arena, 8);
  Rgb sum(0.f);
  sum += Rgb(5.f);  // found at the first vertex (e.g. its next event): before any record
  records.gained(sum);
  records.add(vertex(1, 0.5f, Rgb(0.8f), Rgb(0.8f)));
  sum += Rgb(0.4f, 0.8f, 1.6f);  // at the second vertex: arrives at vertex 1 only
  records.gained(sum);
  records.add(vertex(2, 2.f, Rgb(0.5f), Rgb(0.4f)));
  sum += Rgb(0.2f);  // at the third: arrives at both
  std::vector<Pushed> pushed;
  records.finish(sum, [&](const SubpathRecords::Vertex& v, float radiance, float product) {
    pushed.push_back({v.depth, radiance, product});
  });
  ASSERT_EQ(pushed.size(), 2u);
  EXPECT_EQ(pushed[0].depth, 1);
  EXPECT_EQ(pushed[1].depth, 2);
  // Vertex 1: (0.4, 0.8, 1.6) / 0.8 + 0.2 / 0.8 = (0.75, 1.25, 2.25).
  const Rgb incident1(0.75f, 1.25f, 2.25f);
  EXPECT_NEAR(pushed[0].radiance, incident1.luminance() * 0.5f, 1e-5f);
  EXPECT_NEAR(pushed[0].product, (incident1 * 0.8f).luminance(), 1e-5f);
  // Vertex 2: 0.2 / 0.4 = 0.5.
  EXPECT_NEAR(pushed[1].radiance, 0.5f * 2.f, 1e-5f);
  EXPECT_NEAR(pushed[1].product, 0.25f, 1e-5f);
}

TEST(SubpathRecords, VerticesThatReceivedNothingStillCount) {
  // Every guided vertex counts for the spatial split rule, so each goes out, with zeros.
  ScratchArena arena;
  SubpathRecords records(arena, 4);
  records.gained(Rgb(0.f));
  records.add(vertex(1, 1.f, Rgb(1.f), Rgb(1.f)));
  records.add(vertex(2, 1.f, Rgb(1.f), Rgb(0.f)));  // a zero throughput receives nothing
  int count = 0;
  records.finish(Rgb(3.f), [&](const SubpathRecords::Vertex& v, float radiance, float) {
    EXPECT_FLOAT_EQ(radiance, v.depth == 1 ? 3.f : 0.f);
    ++count;
  });
  EXPECT_EQ(count, 2);
}

TEST(SubpathRecords, KeepsAtMostItsCapacityAndNoUnusableDensities) {
  ScratchArena arena;
  SubpathRecords records(arena, 2);
  records.add(vertex(1, 0.f, Rgb(1.f), Rgb(1.f)));  // no density: not a record
  records.add(vertex(2, 1.f, Rgb(1.f), Rgb(1.f)));
  records.add(vertex(3, 1.f, Rgb(1.f), Rgb(1.f)));
  records.add(vertex(4, 1.f, Rgb(1.f), Rgb(1.f)));  // beyond the capacity
  int count = 0;
  records.finish(Rgb(1.f), [&](const SubpathRecords::Vertex&, float, float) { ++count; });
  EXPECT_EQ(count, 2);
}

}  // namespace
}  // namespace caustica::bidir
