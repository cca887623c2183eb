#include <gtest/gtest.h>

#include <algorithm>
#include <bit>
#include <cmath>
#include <limits>

#include "core/compact_float.h"
#include "core/distribution.h"
#include "core/frame.h"
#include "core/math.h"
#include "core/rng.h"
#include "core/transform.h"
#include "core/warp.h"

using namespace caustica;

TEST(Pcg32, SameKeyGivesSameStreamDifferentKeysDiffer) {
  Pcg32 a = Pcg32::for_sample(5, 3, 1), b = Pcg32::for_sample(5, 3, 1),
        c = Pcg32::for_sample(6, 3, 1);
  int same_as_c = 0;
  for (int i = 0; i < 100; ++i) {
    const uint32_t va = a.next_u32();
    EXPECT_EQ(va, b.next_u32());
    same_as_c += va == c.next_u32();
  }
  EXPECT_LT(same_as_c, 3);
}

TEST(Pcg32, FloatsAreInUnitIntervalWithMeanHalf) {
  Pcg32 r(1, 2);
  double sum = 0;
  for (int i = 0; i < 100000; ++i) {
    const float v = r.next_float();
    ASSERT_GE(v, 0.f);
    ASSERT_LT(v, 1.f);
    sum += v;
  }
  EXPECT_NEAR(sum / 100000, 0.5, 0.005);
}

TEST(Frame, IsOrthonormalAndRoundTrips) {
  Pcg32 r(3, 4);
  for (int i = 0; i < 1000; ++i) {
    const Vec3 n = sample_uniform_sphere(r.next_2d());
    const Frame f = Frame::from_normal(n);
    EXPECT_NEAR(dot(f.s, f.t), 0, 1e-5);
    EXPECT_NEAR(dot(f.s, f.n), 0, 1e-5);
    EXPECT_NEAR(length(f.s), 1, 1e-5);
    EXPECT_NEAR(length(f.t), 1, 1e-5);
    const Vec3 v = sample_uniform_sphere(r.next_2d());
    const Vec3 back = f.to_world(f.to_local(v));
    EXPECT_NEAR(distance(v, back), 0, 1e-5);
    EXPECT_NEAR(f.to_local(n).z, 1, 1e-5);
  }
}

TEST(Transform, InverseUndoesAndComposesLikeMatrices) {
  const Transform t = Transform::translate({1, 2, 3}) * Transform::rotate(30, {1, 1, 0}) *
                      Transform::scale({2, 3, 4});
  const Vec3 p(0.3f, -0.7f, 2.f);
  const Vec3 q = t.inverse().point(t.point(p));
  EXPECT_NEAR(distance(p, q), 0, 1e-5);
  EXPECT_FALSE(t.swaps_handedness());
  EXPECT_TRUE(Transform::scale({-1, 1, 1}).swaps_handedness());
  // Normals stay perpendicular to transformed tangent vectors.
  const Vec3 n(0, 0, 1), tangent(1, 1, 0);
  EXPECT_NEAR(dot(t.normal(n), t.vector(tangent)), 0, 1e-5);
}

TEST(Transform, LookAtIsLeftHandedAsPbrt) {
  // pbrt-v4: camera looks down +z, +y up, +x = cross(up, dir).
  const Transform w2c = Transform::look_at({0, 0, 0}, {0, 1, 0}, {0, 0, 1});
  const Vec3 forward = w2c.point({0, 5, 0});
  EXPECT_NEAR(forward.z, 5, 1e-5);
  const Vec3 up = w2c.point({0, 0, 2});
  EXPECT_NEAR(up.y, 2, 1e-5);
  const Vec3 x = w2c.point({1, 0, 0});  // cross(z, y) = -x: world +x is camera -x
  EXPECT_NEAR(x.x, -1, 1e-5);
}

TEST(Distribution1D, DiscreteSamplingFollowsWeights) {
  Distribution1D d({1, 0, 3, 4});
  EXPECT_FLOAT_EQ(d.pmf(0), 1.f / 8);
  EXPECT_FLOAT_EQ(d.pmf(1), 0.f);
  EXPECT_FLOAT_EQ(d.pmf(3), 0.5f);
  int counts[4] = {};
  Pcg32 r(9, 9);
  for (int i = 0; i < 80000; ++i) {
    float pmf;
    const size_t k = d.sample_discrete(r.next_float(), &pmf);
    EXPECT_FLOAT_EQ(pmf, d.pmf(k));
    counts[k]++;
  }
  EXPECT_EQ(counts[1], 0);
  EXPECT_NEAR(counts[0] / 80000.0, 0.125, 0.006);
  EXPECT_NEAR(counts[3] / 80000.0, 0.5, 0.01);
}

// The guide table only narrows the search: every u must pick the index a search of the whole
// cdf picks (the largest i with cdf[i] <= u, clamped to the last bucket, then past empty
// buckets), bucket edges and their float neighbours included.
TEST(Distribution1D, GuidedSearchPicksWhatAFullSearchPicks) {
  Pcg32 r(17, 3);
  for (int trial = 0; trial < 60; ++trial) {
    const size_t n = 1 + r.next_u32() % (trial < 30 ? 40u : 5000u);
    std::vector<float> w(n);
    for (size_t i = 0; i < n; ++i) {
      const float x = r.next_float();
      w[i] = x < 0.3f ? 0.f : x < 0.35f ? 1e4f * x : x;  // runs of zeros, a few spikes
    }
    const Distribution1D d(w);
    const std::vector<float>& cdf = d.cdf();
    std::vector<float> us = {0.f, 0.5f, kOneMinusEpsilon};
    for (int i = 0; i < 400; ++i) us.push_back(r.next_float());
    for (float c : cdf)
      for (float u : {c, std::nextafter(c, 0.f), std::nextafter(c, 2.f)})
        if (u >= 0 && u < 1) us.push_back(u);
    for (float u : us) {
      size_t want = size_t(std::upper_bound(cdf.begin(), cdf.end(), u) - cdf.begin()) - 1;
      want = std::min(want, n - 1);
      while (d.pmf(want) == 0 && want + 1 < n) ++want;
      float pmf;
      ASSERT_EQ(d.sample_discrete(u, &pmf), want) << "n " << n << " u " << u;
      size_t offset = 0;
      float pdf;
      d.sample_continuous(u, &pdf, &offset);
      ASSERT_EQ(offset, want);
    }
  }
}

TEST(Distribution2D, PdfMatchesSampleAndIntegratesToOne) {
  std::vector<float> v = {1, 2, 0, 4, 1, 1, 8, 0, 3, 3, 1, 2};
  Distribution2D d(v, 4, 3);
  Pcg32 r(2, 5);
  for (int i = 0; i < 1000; ++i) {
    float pdf;
    const Vec2 p = d.sample(r.next_2d(), &pdf);
    EXPECT_NEAR(pdf, d.pdf(p), 1e-4f * pdf);
    EXPECT_GT(pdf, 0);
  }
  double integral = 0;
  for (int y = 0; y < 300; ++y)
    for (int x = 0; x < 400; ++x) integral += d.pdf({(x + 0.5f) / 400, (y + 0.5f) / 300});
  EXPECT_NEAR(integral / (300 * 400), 1.0, 1e-3);
}

TEST(Warp, CosineHemisphereMatchesItsPdf) {
  Pcg32 r(4, 4);
  // Mean of cos over the cosine distribution is 2/3.
  double sum = 0;
  for (int i = 0; i < 100000; ++i) {
    const Vec3 w = sample_cosine_hemisphere(r.next_2d());
    ASSERT_NEAR(length(w), 1, 1e-4);
    ASSERT_GE(w.z, 0);
    sum += w.z;
  }
  EXPECT_NEAR(sum / 100000, 2.0 / 3.0, 0.004);
}

TEST(Warp, ConeSamplesStayInsideTheCone) {
  Pcg32 r(4, 5);
  const float cos_max = 0.9f;
  for (int i = 0; i < 10000; ++i) {
    const Vec3 w = sample_uniform_cone(r.next_2d(), cos_max);
    ASSERT_GE(w.z, cos_max - 1e-5f);
    ASSERT_NEAR(length(w), 1, 1e-4);
  }
}

TEST(Warp, TriangleSamplesAreUniform) {
  Pcg32 r(5, 5);
  // The mean of uniform barycentrics is (1/3, 1/3).
  double b0 = 0, b1 = 0;
  for (int i = 0; i < 100000; ++i) {
    const Vec2 b = sample_uniform_triangle(r.next_2d());
    ASSERT_GE(b.x, 0);
    ASSERT_GE(b.y, 0);
    ASSERT_LE(b.x + b.y, 1.f + 1e-6f);
    b0 += b.x;
    b1 += b.y;
  }
  EXPECT_NEAR(b0 / 100000, 1.0 / 3, 0.003);
  EXPECT_NEAR(b1 / 100000, 1.0 / 3, 0.003);
}

namespace caustica {
namespace {

TEST(NextFloat, MatchesStdNextafterEverywhere) {
  const float values[] = {
      0.f,           -0.f,           1.f,       -1.f,       1e-45f, -1e-45f,   1.17549435e-38f,
      3.4028235e38f, -3.4028235e38f, kInfinity, -kInfinity, 0.1f,   -123.456f, 7e-40f};
  for (float v : values) {
    EXPECT_EQ(std::bit_cast<uint32_t>(next_float_up(v)),
              std::bit_cast<uint32_t>(std::nextafter(v, kInfinity)))
        << v;
    EXPECT_EQ(std::bit_cast<uint32_t>(next_float_down(v)),
              std::bit_cast<uint32_t>(std::nextafter(v, -kInfinity)))
        << v;
  }
}

}  // namespace
}  // namespace caustica

// bfloat16 (core/compact_float.h): round to nearest even within 2^-8, float's range, infinities and
// NaN kept. A truncating conversion (bits >> 16) fails the ties and the error bound.
TEST(BFloat16, RoundsToNearestEvenAndKeepsTheRange) {
  EXPECT_EQ(from_bfloat16(to_bfloat16(1.f)), 1.f);
  // 1 + 2^-8 lies halfway between 1 and 1 + 2^-7: ties to the even 1; 1 + 3 * 2^-8 to 1 + 2^-6.
  EXPECT_EQ(from_bfloat16(to_bfloat16(1.f + 0x1p-8f)), 1.f);
  EXPECT_EQ(from_bfloat16(to_bfloat16(1.f + 3 * 0x1p-8f)), 1.f + 0x1p-6f);
  EXPECT_EQ(from_bfloat16(to_bfloat16(1.f + 0x1p-8f + 0x1p-20f)), 1.f + 0x1p-7f);
  EXPECT_EQ(from_bfloat16(to_bfloat16(-2.5f)), -2.5f);
  const float inf = std::numeric_limits<float>::infinity();
  EXPECT_EQ(from_bfloat16(to_bfloat16(inf)), inf);
  EXPECT_EQ(from_bfloat16(to_bfloat16(-inf)), -inf);
  EXPECT_TRUE(std::isnan(from_bfloat16(to_bfloat16(std::numeric_limits<float>::quiet_NaN()))));
  EXPECT_EQ(from_bfloat16(to_bfloat16(std::numeric_limits<float>::max())), inf);
  Pcg32 rng(3, 4);
  for (int i = 0; i < 100000; ++i) {
    const float v = std::ldexp(rng.next_float() + 0.5f, int(rng.next_float() * 200) - 100);
    const float r = from_bfloat16(to_bfloat16(v));
    ASSERT_LE(std::abs(r - v), 0x1p-8f * std::abs(v)) << v;
  }
}

// float24 (core/compact_float.h): within 2^-16, infinities and NaN kept, and a long sum keeps
// growing (adaptive-vcm's moments add thousands of terms; in bfloat16 this sum stalls at 256).
TEST(Float24, RoundsWithin2ToTheMinus16AndLongSumsKeepGrowing) {
  uint8_t b[3];
  auto round_trip = [&](float v) {
    put_float24(b, v);
    return get_float24(b);
  };
  EXPECT_EQ(round_trip(1.f), 1.f);
  EXPECT_EQ(round_trip(-0.375f), -0.375f);
  const float inf = std::numeric_limits<float>::infinity();
  EXPECT_EQ(round_trip(inf), inf);
  EXPECT_TRUE(std::isnan(round_trip(std::numeric_limits<float>::quiet_NaN())));
  Pcg32 rng(5, 6);
  for (int i = 0; i < 100000; ++i) {
    const float v = std::ldexp(rng.next_float() + 0.5f, int(rng.next_float() * 200) - 100);
    ASSERT_LE(std::abs(round_trip(v) - v), 0x1p-16f * std::abs(v)) << v;
  }
  float sum24 = 0, sum16 = 0;
  for (int i = 0; i < 10000; ++i) {
    sum24 = round_trip(sum24 + 1.f);
    sum16 = from_bfloat16(to_bfloat16(sum16 + 1.f));
  }
  EXPECT_NEAR(sum24, 10000.f, 1.f);
  EXPECT_EQ(sum16, 256.f);  // why the moments are not bfloat16
}
