// The learned radiance field of path guiding (guiding/, after Müller et al. 2017 and Müller
// 2019): its directional distribution is a density over the sphere whose samples follow it,
// trained on a known radiance field it learns that field, its memory stays under the cap, its
// filtered splats conserve energy and its training does not depend on the order of the records;
// the learned selection probability follows the better technique, and passes combine by inverse
// variance. guided-pt's furnace, agreement with pt and thread determinism come from the registry
// oracles.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <nlohmann/json.hpp>
#include <span>
#include <tuple>
#include <utility>
#include <vector>

#include "chi2.h"
#include "core/math.h"
#include "guiding/guiding_field.h"
#include "guiding/training_schedule.h"
#include "image/inverse_variance.h"
#include "integrators/bidir/bidir_core.h"
#include "integrators/guided_path_tracer.h"
#include "io/builtin_scenes.h"
#include "test_scenes.h"

using namespace caustica;

namespace {

// A synthetic incident radiance field: `inside` within a cone of half-angle `angle` around
// `axis`, 1 elsewhere.
struct ConeField {
  Vec3 axis;
  float cos_angle;
  float inside;
  float radiance(Vec3 w) const { return dot(w, axis) >= cos_angle ? inside : 1.f; }
  // The share of the sphere's incident energy inside the cone.
  double cone_fraction() const {
    const double cone = 2 * kPi * (1 - double(cos_angle));
    return inside * cone / (inside * cone + (4 * kPi - cone));
  }
};

// Trains field at point p for `iterations` doubling iterations of `base` samples each, drawing
// directions from the mixture the integrator uses (half learned, half uniform on the sphere) and
// splatting radiance / pdf.
void train(GuidingField& field, const std::function<ConeField(Vec3)>& scene, int iterations,
           int base, uint64_t seed) {
  Pcg32 rng(seed, 11);
  for (int k = 0; k < iterations; ++k) {
    for (int i = 0; i < (base << k); ++i) {
      const Vec3 p(rng.next_float(), rng.next_float(), rng.next_float());
      const DirectionalQuadtree& learned = field.sampling(field.leaf_at(p));
      const bool guided = learned.total() > 0;
      const Vec2 u = rng.next_2d();
      const Vec3 w = guided && rng.next_float() < 0.5f ? learned.sample(u) : square_to_direction(u);
      const float pdf = guided ? 0.5f * kInv4Pi + 0.5f * learned.pdf(w) : kInv4Pi;
      GuidingRecord r;
      r.key = (uint64_t(k) << 32) + uint64_t(i);  // unique: the filter's jitter is hashed from it
      r.leaf = field.leaf_at(p);
      r.square = direction_to_square(w);
      r.radiance = scene(p).radiance(w) / pdf;
      field.record(r);
    }
    field.end_pass(k);
  }
}

GuidingField trained_cone(const ConeField& cone, int iterations = 6,
                          const GuidingSettings& settings = {}) {
  GuidingField field(Bounds3{{0, 0, 0}, {1, 1, 1}}, settings);
  train(
      field, [&](Vec3) { return cone; }, iterations, 20000, 3);
  return field;
}

const ConeField kCone{normalize(Vec3(0.3f, -0.5f, 0.8f)), std::cos(radians(15.f)), 100.f};

}  // namespace

TEST(Guiding, CylindricalMappingRoundTrips) {
  Pcg32 rng(1, 2);
  for (int i = 0; i < 1000; ++i) {
    const Vec2 p = rng.next_2d();
    const Vec2 q = direction_to_square(square_to_direction(p));
    EXPECT_NEAR(p.x, q.x, 1e-5f);
    EXPECT_NEAR(p.y, q.y, 1e-5f);
  }
}

// A density over the sphere: its integral (quadrature on a fine (cos theta, phi) grid whose
// cells the quadtree's dyadic leaves align with) is 1.
TEST(Guiding, LearnedDistributionIntegratesToOne) {
  const GuidingField field = trained_cone(kCone);
  const DirectionalQuadtree& d = field.sampling(field.leaf_at({0.5f, 0.5f, 0.5f}));
  ASSERT_GT(d.total(), 0);
  EXPECT_GT(d.depth(), 3) << "the test should see a refined tree";
  const double integral =
      test::integrate_sphere([&](Vec3 w) { return double(d.pdf(w)); }, 512, 1024);
  EXPECT_NEAR(integral, 1.0, 2e-3);
}

// Chi-square goodness of fit of sample() against pdf() (tests/chi2.h).
TEST(Guiding, SamplingFollowsPdfChiSquare) {
  const GuidingField field = trained_cone(kCone);
  const DirectionalQuadtree& d = field.sampling(field.leaf_at({0.5f, 0.5f, 0.5f}));
  test::Chi2Options o;
  o.theta_bins = 20;
  o.phi_bins = 40;
  o.sample_count = 400000;
  const auto r = test::chi2_test(
      [&](Pcg32& rng) -> std::optional<test::DirectionSample> {
        const Vec3 w = d.sample(rng.next_2d());
        return test::DirectionSample{w, d.pdf(w)};
      },
      [&](Vec3 w) { return d.pdf(w); }, o);
  EXPECT_TRUE(r.passed) << r.message << " p " << r.p_value;
}

// The density sample_square() reports is, bit for bit, pdf_square() at the sampled point.
TEST(Guiding, SampledDensityIsThePdfAtTheSample) {
  const GuidingField field = trained_cone(kCone);
  const DirectionalQuadtree& d = field.sampling(field.leaf_at({0.5f, 0.5f, 0.5f}));
  Pcg32 rng(9, 9);
  for (int i = 0; i < 10000; ++i) {
    float pdf = 0;
    const Vec2 p = d.sample_square(rng.next_2d(), &pdf);
    ASSERT_EQ(pdf, d.pdf_square(p));
  }
}

// Quadrants without energy, and one whose probability rounds to zero in float, are never
// sampled and have density 0: every sample's density is positive, and the density is that of
// the sampling (its integral is 1 and it is 0 exactly where nothing is drawn).
TEST(Guiding, EmptyQuadrantsAreNeitherSampledNorDense) {
  DirectionalQuadtree t;
  t.record({0.25f, 0.25f}, 1.0);    // quadrant 0
  t.record({0.75f, 0.25f}, 1e-30);  // quadrant 1: a share that rounds to 0
  t.record({0.3f, 0.2f}, 1.0);      // two more in quadrant 0, so that it refines
  t.record({0.1f, 0.45f}, 2.0);
  t.propagate();
  size_t budget = 1000;
  DirectionalQuadtree d = t.refined(0.01, 8, &budget, 1.0);
  for (Vec2 p : {Vec2(0.3f, 0.2f), Vec2(0.1f, 0.45f), Vec2(0.2f, 0.1f)}) d.record(p, 1.0);
  d.propagate();
  ASSERT_GT(d.depth(), 1);
  EXPECT_EQ(d.pdf_square({0.75f, 0.25f}), 0.f) << "the rounded-away quadrant";
  EXPECT_EQ(d.pdf_square({0.75f, 0.75f}), 0.f);
  Pcg32 rng(5, 6);
  for (int i = 0; i < 100000; ++i) {
    float pdf = 0;
    const Vec2 p = d.sample_square(rng.next_2d(), &pdf);
    ASSERT_GT(pdf, 0.f) << p.x << " " << p.y;
    ASSERT_TRUE(p.x < 0.5f && p.y < 0.5f) << p.x << " " << p.y;
  }
  double integral = 0;
  constexpr int kN = 512;
  for (int i = 0; i < kN; ++i)
    for (int j = 0; j < kN; ++j) integral += d.pdf_square(Vec2((i + 0.5f) / kN, (j + 0.5f) / kN));
  EXPECT_NEAR(integral / (kN * kN), 1.0, 1e-5);
}

// Trained on radiance concentrated in a cone, the learned density is much higher in the cone
// than outside, and the cone's probability tends to its share of the energy as the quadtree
// refines (smaller rho): leaves straddling the cone's rim spread its energy outside.
TEST(Guiding, LearnsARadianceCone) {
  auto cone_probability = [](double rho, int iterations) {
    GuidingSettings s;
    s.rho = rho;
    const GuidingField field = trained_cone(kCone, iterations, s);
    const DirectionalQuadtree& d = field.sampling(field.leaf_at({0.5f, 0.5f, 0.5f}));
    EXPECT_GT(d.pdf(kCone.axis), 50 * d.pdf(-kCone.axis));
    const double p = test::integrate_sphere(
        [&](Vec3 w) { return dot(w, kCone.axis) >= kCone.cos_angle ? double(d.pdf(w)) : 0.0; }, 512,
        1024);
    std::printf("[ guiding ] rho %.4f, %d iterations: cone probability %.4f (share %.4f)\n", rho,
                iterations, p, kCone.cone_fraction());
    return p;
  };
  const double coarse = cone_probability(0.01, 6), fine = cone_probability(0.001, 8);
  EXPECT_LT(std::abs(fine - kCone.cone_fraction()), 0.5 * std::abs(coarse - kCone.cone_fraction()));
  EXPECT_NEAR(coarse, kCone.cone_fraction(), 0.06);
  EXPECT_NEAR(fine, kCone.cone_fraction(), 0.02);
  // Before training it knows nothing (and is not used).
  EXPECT_EQ(GuidingField().sampling(0).total(), 0);
}

// Two halves of space with light from different cones: the spatial tree splits (with a low
// threshold c) and each side learns its own cone.
TEST(Guiding, SpatialTreeSeparatesRegions) {
  GuidingSettings s;
  s.spatial_threshold = 2000;
  GuidingField field(Bounds3{{0, 0, 0}, {2, 1, 1}}, s);  // x is the longest axis
  const ConeField left = kCone, right{-kCone.axis, kCone.cos_angle, 100.f};
  train(
      field, [&](Vec3 p) { return p.x < 0.5f ? left : right; }, 6, 20000, 5);
  // Training points are in the unit cube: x < 0.5 is left, x in [0.5, 1) right.
  EXPECT_GT(field.leaf_count(), 2u);
  const DirectionalQuadtree& a = field.sampling(field.leaf_at({0.2f, 0.5f, 0.5f}));
  const DirectionalQuadtree& b = field.sampling(field.leaf_at({0.8f, 0.5f, 0.5f}));
  EXPECT_GT(a.pdf(left.axis), 20 * a.pdf(right.axis));
  EXPECT_GT(b.pdf(right.axis), 20 * b.pdf(left.axis));
}

// leaf_at() starts its descent at a cell of the start grid: it must still find the leaf whose
// box holds the point, for points anywhere (on split planes, where the descent goes to the upper
// side; outside the box, which go to the nearest leaf), in a tree of many unequal leaves.
TEST(Guiding, LeafAtFindsTheLeafWhoseBoxHoldsThePoint) {
  GuidingSettings s;
  s.spatial_threshold = 300;
  const Bounds3 root{{-1.3f, 0.1f, 2}, {2.9f, 1.07f, 2.53f}};  // not dyadic: planes round
  GuidingField field(root, s);
  Pcg32 rng(5, 3);
  // Vertex counts concentrated at one corner: leaves there are far deeper than a grid cell.
  for (int k = 0; k < 4; ++k) {
    std::vector<uint32_t> counts(field.leaf_count(), 0);
    for (int i = 0; i < 40000; ++i) {
      const float scale = rng.next_float() < 0.9f ? 1e-4f : 1.f;
      const Vec3 u(rng.next_float(), rng.next_float(), rng.next_float());
      const Vec3 p = root.lo + (root.hi - root.lo) * u * scale;
      ++counts[field.leaf_at(p)];
    }
    field.add_vertex_counts(counts);
    field.end_pass(k);
  }
  ASSERT_GT(field.leaf_count(), 50u);
  auto holds = [&](uint32_t leaf, Vec3 p) {
    const Bounds3& b = field.leaf_box(leaf);
    for (int a = 0; a < 3; ++a) {
      const float q = std::clamp(p[a], root.lo[a], root.hi[a]);
      if (!(b.lo[a] <= q && (q < b.hi[a] || b.hi[a] == root.hi[a]))) return false;
    }
    return true;
  };
  int wrong = 0;
  for (int i = 0; i < 200000; ++i) {
    Vec3 p;
    if (i % 2) {  // anywhere, up to half the box beyond it
      const Vec3 u(rng.next_float(), rng.next_float(), rng.next_float());
      p = root.lo + (root.hi - root.lo) * (u * 2.f - Vec3(0.5f, 0.5f, 0.5f));
    } else {  // on a plane of some leaf's box
      const Bounds3& b = field.leaf_box(rng.next_bounded(uint32_t(field.leaf_count())));
      const Vec3 u(rng.next_float(), rng.next_float(), rng.next_float());
      p = b.lo + (b.hi - b.lo) * u;
      const int a = int(rng.next_bounded(3));
      p[a] = rng.next_float() < 0.5f ? b.lo[a] : b.hi[a];
    }
    if (!holds(field.leaf_at(p), p)) ++wrong;
  }
  EXPECT_EQ(wrong, 0);
}

// A sided field learns the two faces of a zero-thickness wall separately: radiance recorded on
// the +x face (class 0) from +x and on the -x face (class 1) from -x, at the same points, gives
// each face its own distribution, and a point outside the box still stays in its class.
TEST(Guiding, SidedFieldSeparatesTheFacesOfAThinWall) {
  GuidingSettings s;
  s.filter = false;
  GuidingField field(Bounds3{{0, 0, 0}, {1, 1, 1}}, s, /*sided=*/true);
  EXPECT_EQ(GuidingField::side_class({1, 0.2f, 0.1f}), 0);
  EXPECT_EQ(GuidingField::side_class({-1, 0.2f, 0.1f}), 1);
  EXPECT_EQ(GuidingField::side_class({0.1f, -0.9f, 0.3f}), 3);
  EXPECT_EQ(GuidingField::side_class({0.1f, 0.2f, 0.9f}), 4);
  std::vector<GuidingRecord> records;
  for (uint64_t i = 0; i < 2000; ++i) {
    const Vec3 p(0.5f, float(i % 40) / 40.f, float(i / 40) / 50.f);  // the wall x = 1/2
    for (int side = 0; side < 2; ++side) {
      GuidingRecord r;
      r.key = 2 * i + uint64_t(side);
      r.leaf = field.leaf_at(p, side);
      r.square = direction_to_square(side == 0 ? Vec3(1, 0, 0) : Vec3(-1, 0, 0));
      r.radiance = 1;
      records.push_back(r);
    }
  }
  field.splat(records);
  field.end_pass(0);
  const Vec3 p(0.5f, 0.5f, 0.5f);
  ASSERT_NE(field.leaf_at(p, 0), field.leaf_at(p, 1));
  const DirectionalQuadtree& front = field.sampling(field.leaf_at(p, 0));
  const DirectionalQuadtree& back = field.sampling(field.leaf_at(p, 1));
  EXPECT_GT(front.pdf({1, 0, 0}), 10 * front.pdf({-1, 0, 0}));
  EXPECT_GT(back.pdf({-1, 0, 0}), 10 * back.pdf({1, 0, 0}));
  // Nothing was recorded for the other classes, and points beyond the box keep their class.
  EXPECT_EQ(field.sampling(field.leaf_at(p, 2)).total(), 0);
  EXPECT_EQ(field.leaf_at({7.f, 0.5f, 0.5f}, 0), field.leaf_at({0.99f, 0.5f, 0.5f}, 0));
  EXPECT_EQ(field.leaf_at({-3.f, 0.5f, 0.5f}, 1), field.leaf_at({0.01f, 0.5f, 0.5f}, 1));
}

// The memory cap bounds the whole structure, and memory is reported.
TEST(Guiding, MemoryCapBoundsTheStructure) {
  GuidingSettings s;
  s.spatial_threshold = 500;
  s.max_bytes = 40000;
  GuidingField field(Bounds3{{0, 0, 0}, {1, 1, 1}}, s);
  train(
      field, [&](Vec3) { return kCone; }, 5, 20000, 7);
  EXPECT_LE(field.memory_bytes(), s.max_bytes);
  EXPECT_GT(field.memory_bytes(), s.max_bytes / 2) << "the cap was reached";
  EXPECT_GE(field.memory_bytes(), field.quadtree_node_count() * DirectionalQuadtree::kNodeBytes);
}

// Filtered splatting spreads a record over neighbouring quadrants without losing or creating
// energy, also where the box crosses phi = 0 (it wraps) or the poles (it is moved inside).
TEST(Guiding, FilteredSplatConservesEnergy) {
  GuidingField field = trained_cone(kCone, 3);
  size_t budget = 1000;
  DirectionalQuadtree d = field.sampling(0).refined(0.01, 20, &budget);
  const Vec2 points[] = {
      {0.5f, 0.5f}, {0.3f, 0.001f}, {0.3f, 0.999f}, {0.0001f, 0.5f}, {0.9999f, 0.9999f}};
  double expected = 0;
  for (Vec2 p : points) {
    d.record_filtered(p, 2.5);
    expected += 2.5;
  }
  d.propagate();
  EXPECT_NEAR(d.total(), expected, 1e-9 * expected);
  // A point in the middle of a leaf of an unrefined tree (leaf side 1/2) stays in that leaf.
  DirectionalQuadtree flat;
  flat.record_filtered({0.25f, 0.25f}, 1.0);
  flat.propagate();
  EXPECT_NEAR(flat.pdf_square({0.25f, 0.25f}), 4.0, 1e-6);
}

// A refined tree that carries the energy (--guiding-carry) keeps the distribution: a quadrant
// refined deeper spreads its energy evenly (the same density), a subtree that collapses keeps
// its sum, and the total is scaled by the carried share.
TEST(Guiding, RefinedTreeCarriesTheDistribution) {
  DirectionalQuadtree flat;
  const Vec2 centre[4] = {{0.25f, 0.25f}, {0.75f, 0.25f}, {0.25f, 0.75f}, {0.75f, 0.75f}};
  const double energy[4] = {5, 3, 1.5, 0.5};
  for (int q = 0; q < 4; ++q) flat.record(centre[q], energy[q]);
  flat.propagate();
  size_t budget = 1000;
  DirectionalQuadtree carried = flat.refined(0.2, 20, &budget, 0.5);
  EXPECT_EQ(carried.node_count(), 3u) << "the quadrants holding 50% and 30% are refined";
  carried.propagate();
  EXPECT_NEAR(carried.total(), 0.5 * flat.total(), 1e-6);
  Pcg32 rng(3, 4);
  for (int i = 0; i < 100; ++i) {
    const Vec2 p = rng.next_2d();
    ASSERT_NEAR(carried.pdf_square(p), flat.pdf_square(p), 1e-5) << p.x << " " << p.y;
  }
  // Collapsing: refined with rho = 1 the tree is one node again, each quadrant its subtree's sum.
  budget = 1000;
  DirectionalQuadtree collapsed = carried.refined(1.0, 20, &budget, 1.0);
  EXPECT_EQ(collapsed.node_count(), 1u);
  collapsed.propagate();
  EXPECT_NEAR(collapsed.total(), carried.total(), 1e-6);
  for (int q = 0; q < 4; ++q)
    EXPECT_NEAR(collapsed.pdf_square(centre[q]), 4 * energy[q] / 10, 1e-5) << q;
  // Without carry the energies are zero (Müller 2017).
  budget = 1000;
  DirectionalQuadtree fresh = flat.refined(0.2, 20, &budget);
  fresh.propagate();
  EXPECT_EQ(fresh.total(), 0);
}

// The stochastic directional filter (the one the field uses) is the deterministic box filter
// in expectation: many jittered splats of one point match one box-filtered splat.
TEST(Guiding, JitteredSplatsAverageToTheBoxFilter) {
  const GuidingField field = trained_cone(kCone, 4);
  size_t budget = 100000;
  const DirectionalQuadtree refined = field.sampling(0).refined(0.01, 20, &budget);
  const Vec2 points[] = {direction_to_square(kCone.axis), {0.4f, 0.999f}, {0.001f, 0.3f}};
  for (Vec2 p : points) {
    DirectionalQuadtree box = refined, jittered = refined;
    box.record_filtered(p, 1.0);
    Pcg32 rng(4, 5);
    const int n = 200000;
    for (int i = 0; i < n; ++i) jittered.record_jittered(p, 1.0 / n, rng.next_2d());
    box.propagate();
    jittered.propagate();
    for (int i = 0; i < 200; ++i) {
      const Vec2 q = rng.next_2d();
      const float a = box.pdf_square(q), b = jittered.pdf_square(q);
      ASSERT_NEAR(a, b, 0.02 * std::max(a, 1.f))
          << p.x << " " << p.y << " at " << q.x << " " << q.y;
    }
  }
}

// The same records handed to splat() as one run, or cut into runs of assorted sizes (empty ones
// too) that alternate between two buffers, as two threads leave them (pixel_records.h), give the
// same field, bit for bit: splat reads the runs in order and groups each leaf's records in it.
TEST(Guiding, SplatReadsRunsInOrderWhereverTheyAreStored) {
  GuidingField untrained = trained_cone(kCone, 2);
  const uint32_t leaves = uint32_t(untrained.leaf_count());
  ASSERT_GE(leaves, 2u);
  std::vector<GuidingRecord> records;
  Pcg32 rng(5, 6);
  for (uint64_t i = 0; i < 20000; ++i) {
    GuidingRecord r;
    r.key = i;
    r.leaf = uint32_t(i % leaves);
    r.square = rng.next_2d();
    r.radiance = rng.next_float() * 10;
    r.product = r.radiance * 0.3f;
    r.bsdf_pdf = rng.next_float();
    r.guide_pdf = rng.next_float();
    records.push_back(r);
  }
  std::vector<GuidingRecord> buffers[2];
  std::vector<std::pair<int, size_t>> cuts;  // (buffer, first record) per run
  for (size_t i = 0, size = 0; i < records.size(); i += size, size = (size + 13) % 38) {
    const int b = int(cuts.size() % 2);
    cuts.emplace_back(b, buffers[b].size());
    for (size_t j = i; j < std::min(records.size(), i + size); ++j)
      buffers[b].push_back(records[j]);
  }
  std::vector<std::span<const GuidingRecord>> runs;
  for (size_t c = 0; c < cuts.size(); ++c) {
    const auto [b, first] = cuts[c];
    size_t end = buffers[b].size();
    for (size_t d = c + 1; d < cuts.size(); ++d)
      if (cuts[d].first == b) {
        end = cuts[d].second;
        break;
      }
    runs.emplace_back(buffers[b].data() + first, end - first);
  }
  GuidingField one = untrained, cut = untrained;
  one.splat(std::span<const GuidingRecord>(records));
  cut.splat(runs);
  one.end_pass(2);
  cut.end_pass(2);
  ASSERT_EQ(one.leaf_count(), cut.leaf_count());
  for (uint32_t l = 0; l < one.leaf_count(); ++l) {
    const DirectionalQuadtree &a = one.sampling(l), &b = cut.sampling(l);
    ASSERT_GT(a.total(), 0);
    ASSERT_EQ(a.total(), b.total()) << "leaf " << l;
    ASSERT_EQ(one.bsdf_fraction(l), cut.bsdf_fraction(l));
    for (int i = 0; i < 200; ++i) {
      const Vec3 w = square_to_direction(rng.next_2d());
      ASSERT_EQ(a.pdf(w), b.pdf(w));
    }
  }
}

// The learned selection probability moves toward the technique whose density matches the
// product f |cos| L_i: toward the BSDF when the product follows it, toward the guide when the
// product follows the guide (samples drawn from the current mixture, as the integrator does).
// Next event estimation's learned probability (GuidingSettings::nee_floor): a leaf that took
// kNeeEvidence light samples and saw no light drops to the floor, the children of a split
// inherit it, a leaf with fewer samples keeps what it had and one that saw light goes back to 1.
TEST(Guiding, NextEventProbabilityDropsWhereNoLightIsSeen) {
  GuidingSettings settings;
  settings.spatial_threshold = 10;
  GuidingField field(Bounds3{{0, 0, 0}, {1, 1, 1}}, settings);
  ASSERT_EQ(field.leaf_count(), 1u);
  EXPECT_EQ(field.guide(0).probability[GuidingField::kNextEvent], 1.f);
  field.add_nee_counts({GuidingField::kNeeEvidence, 0});
  field.add_vertex_counts({100});  // the leaf splits at the end of the pass
  field.end_pass(0);
  ASSERT_GT(field.leaf_count(), 1u);
  EXPECT_EQ(field.reduced_nee_leaves(), field.leaf_count());
  for (uint32_t l = 0; l < field.leaf_count(); ++l)
    EXPECT_EQ(field.guide(l).probability[GuidingField::kNextEvent], settings.nee_floor) << l;
  const uint32_t a = field.leaf_at(Vec3(0.1f, 0.1f, 0.1f)),
                 b = field.leaf_at(Vec3(0.9f, 0.9f, 0.9f));
  const uint32_t c = field.leaf_at(Vec3(0.1f, 0.9f, 0.9f));
  ASSERT_TRUE(a != b && b != c && a != c);
  std::vector<uint32_t> counts(2 * field.leaf_count(), 0);
  counts[2 * a] = GuidingField::kNeeEvidence - 1;  // too few to tell: stays at the floor
  counts[2 * b] = 3;                               // saw light once: back to 1
  counts[2 * b + 1] = 1;
  field.add_nee_counts(counts);
  field.end_pass(1);
  EXPECT_EQ(field.guide(a).probability[GuidingField::kNextEvent], settings.nee_floor);
  EXPECT_EQ(field.guide(b).probability[GuidingField::kNextEvent], 1.f);
  EXPECT_EQ(field.guide(c).probability[GuidingField::kNextEvent], settings.nee_floor);
  // Seeing light in a few of many samples counts as light unless nee_visible_share allows it.
  for (const float share : {0.f, 0.1f}) {
    settings.nee_visible_share = share;
    GuidingField f(Bounds3{{0, 0, 0}, {1, 1, 1}}, settings);
    f.add_nee_counts({1000, 50});
    f.end_pass(0);
    EXPECT_EQ(f.guide(0).probability[GuidingField::kNextEvent],
              share > 0 ? settings.nee_floor : 1.f)
        << share;
  }
}

TEST(Guiding, SelectionProbabilityFollowsTheBetterTechnique) {
  // Densities on [0, 1]: the BSDF is uniform, the guide is 1.9 on [0, 1/2) and 0.1 elsewhere.
  auto guide_pdf = [](float x) { return x < 0.5f ? 1.9f : 0.1f; };
  auto learn = [&](auto product) {
    SelectionOptimizer opt;
    Pcg32 rng(3, 4);
    for (int i = 0; i < 20000; ++i) {
      const float a = opt.bsdf_fraction();
      const float x = rng.next_float() < a
                          ? rng.next_float()
                          : (rng.next_float() < 0.95f ? 0.5f * rng.next_float()
                                                      : 0.5f + 0.5f * rng.next_float());
      const float pdf = a * 1.f + (1 - a) * guide_pdf(x);
      opt.add(product(x) / pdf, 1.f, guide_pdf(x), 1.f);
    }
    return opt.bsdf_fraction();
  };
  const float follows_guide = learn([&](float x) { return guide_pdf(x); });
  const float follows_bsdf = learn([](float) { return 1.f; });
  std::printf("[ guiding ] learned BSDF fraction: %.3f (product = guide), %.3f (product = BSDF)\n",
              follows_guide, follows_bsdf);
  EXPECT_LT(follows_guide, 0.2f);
  EXPECT_GT(follows_bsdf, 0.8f);
}

// Passes combine by inverse variance: a pass with four times the variance gets a quarter of the
// weight; a pass of one sample per pixel has no estimate and no weight.
TEST(Guiding, InverseVarianceCombinationWeightsPasses) {
  InverseVarianceCombiner c(1, 2);
  c.add(0, Rgb(100.f));  // one sample per pixel: ignored
  c.add(1, Rgb(100.f));
  c.end_iteration();
  EXPECT_TRUE(c.image().empty()) << "no variance estimate yet";
  c.end_pass();
  // Pass 1: samples 0 and 2 (mean 1, variance of the mean 1); pass 2: 0 and 4 (mean 2, 4).
  for (float v : {0.f, 2.f}) {
    c.add(0, Rgb(v));
    c.add(1, Rgb(v));
    c.end_iteration();
  }
  c.end_pass();
  for (float v : {0.f, 4.f}) {
    c.add(0, Rgb(v));
    c.add(1, Rgb(v));
    c.end_iteration();
  }
  const Image image = c.image();
  ASSERT_FALSE(image.empty());
  // (1 / 1 + 2 / 4) / (1 / 1 + 1 / 4) = 1.2
  EXPECT_NEAR(image[0].r, 1.2f, 1e-5f);
  EXPECT_NEAR(image[1].g, 1.2f, 1e-5f);
  const auto passes = c.passes();
  ASSERT_EQ(passes.size(), 3u);
  EXPECT_LT(passes[0].variance, 0);
  EXPECT_NEAR(passes[1].variance, 1.0, 1e-9);
  EXPECT_NEAR(passes[2].variance, 4.0, 1e-9);
}

// A pass's variance comes with its standard error as a mean over pixels: pixel variances of the
// mean 1 and 4 (samples 0, 2 and 0, 4) give V = 2.5 and an error of sqrt(4.5 / 2) = 1.5 (their
// unbiased spread 4.5 over two pixels); equal pixels give 0, one sample per pixel none.
TEST(Guiding, InverseVarianceReportsTheErrorOfAPassVariance) {
  InverseVarianceCombiner c(2, 1);
  c.add(0, Rgb(0.f));
  c.add(1, Rgb(0.f));
  c.end_iteration();
  EXPECT_LT(c.passes().back().variance_error, 0);
  c.add(0, Rgb(2.f));
  c.add(1, Rgb(4.f));
  c.end_iteration();
  EXPECT_NEAR(c.passes().back().variance, 2.5, 1e-9);
  EXPECT_NEAR(c.passes().back().variance_error, 1.5, 1e-9);
  c.end_pass();
  for (float v : {0.f, 2.f}) {
    c.add(0, Rgb(v));
    c.add(1, Rgb(v));
    c.end_iteration();
  }
  EXPECT_NEAR(c.passes().back().variance_error, 0.0, 1e-12);
  EXPECT_NEAR(c.passes().front().variance_error, 1.5, 1e-9);
}

// The current pass split over two processes (each rendered some of its iterations) and summed
// exactly gives one process's combination bit for bit (MPI ranks: sums_over_ranks). Values
// chosen so that a double sum in another order rounds differently; a firefly far above the
// fixed-point clamp of a single value (2^31) keeps its square in the variance.
TEST(Guiding, InverseVarianceCurrentPassSumsOverProcessesExactly) {
  const float samples[6][2] = {{0.1f, 3e4f},  {1e-3f, 0.7f}, {1e7f, 0.3f},
                               {0.2f, 1e-5f}, {0.3f, 2.f},   {1e-7f, 5.f}};
  InverseVarianceCombiner one(2, 1), a(2, 1), b(2, 1);
  auto add = [](InverseVarianceCombiner& c, const float* v) {
    c.add(0, Rgb(v[0]));
    c.add(1, Rgb(v[1], v[0], 1.f));
    c.end_iteration();
  };
  for (int i = 0; i < 6; ++i) {
    add(one, samples[i]);
    add(i % 2 ? b : a, samples[i]);
  }
  const std::span<FixedSum> sa = a.current_sums(), sb = b.current_sums();
  ASSERT_EQ(sa.size(), 2 * InverseVarianceCombiner::kSumsPerPixel + 1);
  for (size_t i = 0; i < sa.size(); ++i) sa[i] += sb[i];
  const Image x = one.image(), y = a.image();
  ASSERT_FALSE(x.empty());
  for (size_t i = 0; i < x.pixel_count(); ++i) EXPECT_TRUE(x[i] == y[i]) << i;
  ASSERT_EQ(a.passes().size(), 1u);
  EXPECT_EQ(a.passes()[0].samples, 6u);
  EXPECT_EQ(a.passes()[0].variance, one.passes()[0].variance);
  // Pixel 0's variance of the mean is about (1e14 - 1e14 / 6) / 5 / 6 (the 1e7 sample), pixel
  // 1's 0.7152^2 of that (the 1e7 in green), the pass's their mean (with the squares clamped at
  // 2^31 it came out 0).
  const double pixel0 = (1e14 - 1e14 / 6) / 5 / 6;
  EXPECT_NEAR(one.passes()[0].variance, 0.5 * (1 + 0.7152 * 0.7152) * pixel0, 0.01 * pixel0);
  a.clear_current();
  EXPECT_TRUE(a.passes().empty());
}

// Without a budget, passes double forever: two unguided iterations, then iteration i >= 2 in
// pass floor(log2(i)).
TEST(TrainingSchedule, PassesDoubleInLength) {
  TrainingSchedule s;
  const int expected[] = {0, 0, 1, 1, 2, 2, 2, 2, 3, 3, 3, 3, 3, 3, 3, 3, 4};
  for (uint32_t i = 0; i < 17; ++i) {
    if (s.starts_pass(i, 0.0)) s.end_pass(1.0 / double(i));
    EXPECT_EQ(s.pass(), expected[i]) << i;
    EXPECT_TRUE(s.learning());
    EXPECT_EQ(s.guided(), i >= 2);
  }
}

// A sample budget: the last pass takes the rest rather than leaving a sliver (64 spp: 2 + 2 + 4
// + 8 + 16 training, then 32 in the final pass), records nothing and is guided.
TEST(TrainingSchedule, LastPassTakesTheRestOfASampleBudget) {
  for (auto [spp, final_from, passes] :
       {std::tuple{64, 32, 5}, std::tuple{16, 8, 3}, std::tuple{5, 2, 1}, std::tuple{2, -1, 0}}) {
    TrainingSchedule s(spp, 0);
    for (uint32_t i = 0; i < uint32_t(spp); ++i)
      if (s.starts_pass(i, 0.0)) s.end_pass(1.0 / sqr(double(i)));  // falls: keeps learning
    EXPECT_EQ(s.rendering_from(), final_from) << spp;
    EXPECT_EQ(s.pass(), passes) << spp;
    if (final_from >= 0) {
      EXPECT_STREQ(s.reason(), "budget");
      EXPECT_FALSE(s.learning());
      EXPECT_TRUE(s.guided());
    }
  }
}

// Training stops when the predicted final variance V^_k = V_k B_k / R_k rises (Müller 2017, sec.
// 5.2) twice in a row, from pass 5 on: with 1000 spp and guided passes whose per-sample variance
// stops falling after pass 4, pass 6 (V^_6 > V^_5 > V^_4) is the last to learn and rendering
// starts with pass 7 at iteration 128. The unguided pass 0 is not a point of the curve.
TEST(TrainingSchedule, StopsLearningWhenItStopsPaying) {
  TrainingSchedule s(1000, 0);
  const double per_sample[] = {1, 16, 8, 4, 2, 2, 2, 2, 2, 2};
  const uint32_t length[] = {2, 2, 4, 8, 16, 32, 64, 128, 256, 512};
  for (uint32_t i = 0; i < 1000; ++i)
    if (s.starts_pass(i, 0.0)) {
      const int k = s.pass() - 1;  // the pass that ended
      s.end_pass(per_sample[k] / double(length[k]));
    }
  EXPECT_STREQ(s.reason(), "variance");
  EXPECT_EQ(s.rendering_from(), 128);
  const auto& v = s.predicted_final_variances();
  ASSERT_EQ(v.size(), 7u);
  EXPECT_LT(v[0], 0);
  EXPECT_LT(v[4], v[3]);
  EXPECT_GT(v[5], v[4]);
  EXPECT_GT(v[6], v[5]);
  EXPECT_TRUE(s.guided());
}

// A time budget: after training pass 3 a trial renders a guided and an unguided pass of equal
// length, and variance x seconds decides. Guided passes with 1.2x lower variance per sample that
// take 1.5x the time lose: rendering goes on unguided at once. At equal cost guiding wins,
// training goes on, and the render stays guided.
TEST(TrainingSchedule, TimeBudgetSwitchesGuidingOffWhenItDoesNotPay) {
  for (const double guided_cost : {1.5, 1.0}) {
    TrainingSchedule s(0, 10.0);
    double t = 0;
    uint32_t start = 0, trial_length[2] = {0, 0};
    for (uint32_t i = 0; !s.final_pass() && i < 100000; ++i) {
      const bool was_guided = s.guided(), was_trial = s.in_trial();
      if (s.starts_pass(i, t)) {
        if (was_trial) trial_length[was_guided] = i - start;
        s.end_pass((was_guided ? 1.0 : 1.2) / double(i - start));
        start = i;
      }
      t += s.guided() ? 0.001 * guided_cost : 0.001;  // seconds per iteration
    }
    ASSERT_TRUE(s.final_pass()) << guided_cost;
    EXPECT_EQ(trial_length[1], 8u);
    EXPECT_EQ(trial_length[0], 8u);
    EXPECT_EQ(s.guided(), guided_cost == 1.0) << guided_cost;
    EXPECT_GT(s.trial_guided_tau(), 0);
    EXPECT_GT(s.trial_unguided_tau(), 0);
    if (guided_cost > 1) {
      EXPECT_STREQ(s.reason(), "trial");
      EXPECT_EQ(s.rendering_from(), 32);  // training 2 + 2 + 4 + 8, trial 8 + 8
      EXPECT_EQ(s.training_passes(), 4);
    } else {
      EXPECT_STREQ(s.reason(), "variance");  // no gain per sample after the trial
      EXPECT_EQ(s.training_passes(), 6);
    }
  }
}

// A time budget of `seconds` whose iterations take 1 ms guided or not, plus `delay(s)` seconds
// after each (and `after_learning` after a training pass ends, while the field learns), and
// whose passes report the per-sample variance `per_sample(guided, round)` (round: the trial
// round the pass belongs to, -1 outside trials) with a relative standard error `rel_error`
// (negative: none): the finished schedule.
template <typename PerSample, typename Delay>
TrainingSchedule drive_schedule(PerSample&& per_sample, double rel_error, double seconds,
                                Delay&& delay, double after_learning = 0) {
  TrainingSchedule s(0, seconds);
  double t = 0;
  int round = 0;
  for (uint32_t i = 0, start = 0; !s.final_pass() && i < 100000; ++i) {
    const bool was_guided = s.guided(), was_trial = s.in_trial();
    if (s.starts_pass(i, t)) {
      if (s.ended_learning()) t += after_learning;
      const double v = per_sample(was_guided, was_trial ? round : -1) / double(i - start);
      s.end_pass(v, rel_error < 0 ? -1.0 : rel_error * v);
      if (was_trial && !was_guided) ++round;
      start = i;
    }
    t += 0.001 + delay(s);
  }
  return s;
}

// Guided iterations as costly as unguided ones with 1.2x lower variance, no errors, and the
// delays as above.
template <typename Delay>
TrainingSchedule schedule_with_delays(Delay&& delay, double after_learning = 0) {
  return drive_schedule([](bool guided, int) { return guided ? 1.0 : 1.2; }, -1, 10.0, delay,
                        after_learning);
}

// Per-sample variances and their errors as above, no delays.
template <typename PerSample>
TrainingSchedule schedule_with_variances(PerSample&& per_sample, double rel_error,
                                         double seconds = 10) {
  return drive_schedule(per_sample, rel_error, seconds,
                        [](const TrainingSchedule&) { return 0.0; });
}

// A trial pass's seconds are its median iteration's times its iterations, so guiding that pays
// wins its trial although (a) building the field after a training pass takes as long as 20
// iterations, time the clock gives to the first iteration of the next pass (for the early
// trial: its guided pass), or (b) one iteration of the guided trial pass stalls for as long as
// 40 (on door-ajar at 60 s a guided trial pass once took 3.1x its unguided one, 1.6x in the
// next run). Timed by the passes' wall seconds, guiding lost both.
TEST(TrainingSchedule, TrialIsNotDecidedByABuildOrAStalledIteration) {
  bool stalled = false;
  const TrainingSchedule stall = schedule_with_delays([&](const TrainingSchedule& s) {
    if (stalled || !s.in_trial() || !s.guided()) return 0.0;
    stalled = true;
    return 0.04;
  });
  const TrainingSchedule build = schedule_with_delays([](const TrainingSchedule&) { return 0.0; },
                                                      /*after_learning=*/0.02);
  ASSERT_TRUE(stalled);
  for (const TrainingSchedule* s : {&stall, &build}) {
    ASSERT_TRUE(s->final_pass());
    EXPECT_TRUE(s->guided());
    EXPECT_LT(s->trial_guided_tau(), s->trial_unguided_tau());
    EXPECT_STRNE(s->reason(), "trial");
  }
}

// A trial is a sequential test. A difference of 2x against errors of 10% decides in one round;
// a near tie (5%, well inside twice the ratio's error) renders the four rounds. An early trial
// that found no clear difference (a tie) trains on, and the trial after training (the same
// variances here) decides by the pooled rounds. Without errors the first round decides; without
// the time for another round (a 150 ms budget: 118 ms, less than eight rounds of 16 ms, would be
// left) the first round is a tie, and the trial after training decides.
TEST(TrainingSchedule, NearTiesRenderMoreTrialRounds) {
  for (const auto& [guided, unguided, rel_error, seconds, rounds, verdict] :
       {std::tuple{1.0, 2.0, 0.1, 10.0, 1, "won"}, std::tuple{2.0, 1.0, 0.1, 10.0, 1, "lost"},
        std::tuple{1.0, 1.05, 0.1, 10.0, 4, "tie"}, std::tuple{1.05, 1.0, 0.1, 10.0, 4, "tie"},
        std::tuple{1.0, 1.05, -1.0, 10.0, 1, "won"}, std::tuple{1.05, 1.0, -1.0, 10.0, 1, "lost"},
        std::tuple{1.0, 1.05, 0.1, 0.15, 1, "tie"}}) {
    const TrainingSchedule s = schedule_with_variances(
        [&](bool g, int) { return g ? guided : unguided; }, rel_error, seconds);
    const std::string what = std::to_string(guided) + " " + std::to_string(unguided) + " " +
                             std::to_string(rel_error) + " " + std::to_string(seconds);
    ASSERT_TRUE(s.final_pass()) << what;
    EXPECT_STREQ(s.early_trial(), verdict) << what;
    EXPECT_EQ(s.trial_rounds(), rounds) << what;  // of the last trial
    EXPECT_EQ(s.guided(), guided < unguided) << what;
    EXPECT_NEAR(s.trial_guided_tau(), guided * 0.001, 1e-12) << what;
    EXPECT_NEAR(s.trial_unguided_tau(), unguided * 0.001, 1e-12) << what;
    if (std::string(verdict) == "lost") {
      EXPECT_STREQ(s.reason(), "trial") << what;
      EXPECT_EQ(s.rendering_from(), 16 + 16 * rounds) << what;  // training 16, then the rounds
    } else {
      EXPECT_STRNE(s.reason(), "trial") << what;  // training went on
      EXPECT_GT(s.training_passes(), 4) << what;
    }
  }
}

// The rounds pool: a first round where guiding looks 1.2x worse per sample (at equal cost), then
// rounds where it is 0.6x: after three rounds the pooled variances (0.8 against 1) differ by more
// than twice the ratio's error (0.22 against 0.17 in the log) and guiding wins. The first round
// alone (no errors) switches it off. A schedule that kept only the last round's variance would
// decide after the second (2 x 0.14 < 0.51) with tau 0.6 ms.
TEST(TrainingSchedule, TrialRoundsArePooled) {
  auto per_sample = [](bool g, int round) { return g ? (round <= 0 ? 1.2 : 0.6) : 1.0; };
  const TrainingSchedule pooled = schedule_with_variances(per_sample, 0.1);
  EXPECT_EQ(pooled.trial_rounds(), 3);
  EXPECT_TRUE(pooled.guided());
  EXPECT_NEAR(pooled.trial_guided_tau(), 0.8 * 0.001, 1e-12);
  EXPECT_NEAR(pooled.trial_log_ratio_error(),
              0.1 * std::hypot(std::sqrt(1.44 + 0.36 + 0.36) / 2.4, 1 / std::sqrt(3.0)), 1e-9);
  const TrainingSchedule first = schedule_with_variances(per_sample, -1);
  EXPECT_EQ(first.trial_rounds(), 1);
  EXPECT_FALSE(first.guided());
  EXPECT_STREQ(first.reason(), "trial");
}

// Renders `spp` samples per pixel with the render loop (which gives the integrator its budget)
// and returns its statistics.
static nlohmann::json render_and_report(const Scene& scene, Integrator& integrator, int spp) {
  RenderBudget budget;
  budget.spp = spp;
  RenderCallbacks cb;
  cb.quiet = true;
  render(scene, integrator, budget, cb);
  nlohmann::json stats;
  integrator.report(stats);
  return stats;
}

// Rendering trains the field: 16 spp are passes of 2 (unguided), 2 and 4 samples per pixel and a
// final pass of 8; the field has learned radiance and refined its quadtrees, and the statistics
// report it.
TEST(GuidedPathTracer, RenderingTrainsTheField) {
  auto scene = make_builtin_scene("cornell", 32, 32);
  IntegratorSettings settings;
  GuidedPathTracer integrator(settings);
  const nlohmann::json stats = render_and_report(*scene, integrator, 16);
  const GuidingField& field = integrator.field();
  const DirectionalQuadtree& d = field.sampling(field.leaf_at(scene->bounds().center()));
  EXPECT_GT(d.total(), 0);
  EXPECT_GT(d.node_count(), 1u);
  EXPECT_EQ(stats["guiding"]["passes_started"], 4);
  EXPECT_EQ(stats["guiding"]["rendering_from_iteration"], 8);
  EXPECT_EQ(stats["guiding"]["rendering_guided"], true);
  EXPECT_GT(stats["guiding"]["guiding_bytes"].get<size_t>(), 0u);
  // Each pass: its samples per pixel, variance and seconds.
  const nlohmann::json& passes = stats["guiding"]["passes"];
  ASSERT_EQ(passes.size(), 4u);
  int spp = 0;
  for (const auto& p : passes) {
    spp += p["spp"].get<int>();
    EXPECT_GE(p["seconds"].get<double>(), 0.0);
  }
  EXPECT_EQ(spp, 16);
  EXPECT_GT(passes[3]["variance"].get<double>(), 0.0);
  // The report's views of the learned field (guide_views.h): 9 pixels; where something was
  // learned, a density over the sphere that integrates to about 1 (midpoints of 32 x 16 cells).
  const nlohmann::json& views = stats["guiding"]["views"];
  ASSERT_EQ(views["views"].size(), 9u);
  int learned = 0;
  for (const auto& v : views["views"]) {
    if (!v.contains("density")) continue;
    ++learned;
    double integral = 0;
    for (const auto& x : v["density"]) integral += x.get<double>();
    integral *= 4 * kPi / double(views["width"].get<int>() * views["height"].get<int>());
    EXPECT_NEAR(integral, 1.0, 0.15) << v["pixel"];
  }
  EXPECT_GE(learned, 5);
}

// With the product with the cosine (the default), the guide at the middle of the cornell box's
// floor (normal +z, the cylindrical mapping's axis) puts much less of its upper-hemisphere mass at
// grazing angles (cos < 0.3) than the radiance-only guide of Mueller 2017 (under radiance that
// arrives evenly, 0.09 of it against 0.3; here, with the light overhead, measured 0.03 against
// 0.12). A record weight that ignored the setting, or used the wrong normal, fails this.
TEST(GuidedPathTracer, CosineProductGuidesAwayFromGrazingAngles) {
  auto scene = make_builtin_scene("cornell", 32, 32);
  auto grazing_share = [&](bool cosine) {
    IntegratorSettings settings;
    settings.guiding.cosine_product = cosine;
    GuidedPathTracer integrator(settings);
    render_and_report(*scene, integrator, 16);
    const Vec3 c = scene->bounds().center();
    const Vec3 floor_point(c.x, c.y, scene->bounds().lo.z + 1e-3f);
    const GuidingField& field = integrator.field();
    const DirectionalQuadtree& d =
        field.sampling(field.leaf_at(floor_point, GuidingField::side_class(Vec3(0, 0, 1))));
    EXPECT_GT(d.total(), 0);
    double upper = 0, grazing = 0;
    constexpr int kN = 128;
    for (int i = kN / 2; i < kN; ++i)  // square x = (cos + 1) / 2 >= 1/2: the upper hemisphere
      for (int j = 0; j < kN; ++j) {
        const double p = d.pdf_square(Vec2((i + 0.5f) / kN, (j + 0.5f) / kN));
        upper += p;
        if ((i + 0.5) / kN < 0.65) grazing += p;
      }
    return grazing / upper;
  };
  const double radiance = grazing_share(false), cosine = grazing_share(true);
  EXPECT_GT(radiance, 0.08) << cosine;
  EXPECT_LT(cosine, 0.6 * radiance) << radiance;
}

// The registry's determinism oracle renders 3 iterations (one splat feeds the sampling); here
// the 12-spp schedule (passes of 2, 2, then a final 8) samples with fields learned from
// multi-threaded splats and decides when to stop learning from the passes' variances: still
// bit-identical.
TEST(GuidedPathTracer, TrainedFieldBitIdenticalForOneAndTwoThreads) {
  auto scene = make_builtin_scene("cornell", 24, 24);
  const auto a = test::render_with(*scene, "guided-pt", 12, {}, 1);
  const auto b = test::render_with(*scene, "guided-pt", 12, {}, 2);
  size_t differing = 0;
  for (size_t i = 0; i < a.image.pixel_count(); ++i)
    if (!(a.image[i] == b.image[i])) ++differing;
  EXPECT_EQ(differing, 0u);
}

// Next event estimation at a learned probability q stays unbiased: the light sample's density
// is q p_light in its own weight and in the emitter hits' weights (the MIS weights still sum to
// one). In the furnace (a closed emitting sphere of albedo 1/2: radiance Le / (1 - a)
// everywhere) every light sample sees light, so the floor is forced onto every leaf
// (nee_visible_share 1), and the light and BSDF densities are alike, so the weights matter.
TEST(GuidedPathTracer, NextEventProbabilityKeepsTheEstimateUnbiased) {
  const FurnaceParams p{0.5f, 1.5f};  // radiance 3
  auto scene = make_furnace_scene(p, 24, 24);
  IntegratorSettings s;
  s.max_depth = 200;
  s.guiding.nee_floor = 0.25f;
  s.guiding.nee_visible_share = 1;
  GuidedPathTracer integrator(s);
  const nlohmann::json stats = render_and_report(*scene, integrator, 16);
  EXPECT_EQ(stats["guiding"]["nee_reduced_leaves"].get<size_t>(), 6u);  // the six side classes
  const auto st = test::over_seeds(6, [&](uint64_t seed) {
    s.seed = seed;
    const auto r = test::render_with(*scene, "guided-pt", 16, s);
    EXPECT_EQ(r.nonfinite, 0u);
    return test::pixel_stats(r.image).mean;
  });
  std::printf("[ nee floor ] guided-pt mean %.5f se %.5f (expected %.5f)\n", st.mean,
              st.standard_error, p.expected_radiance());
  EXPECT_NEAR(st.mean, p.expected_radiance(), 3 * st.standard_error + 1e-5);
  EXPECT_LT(st.standard_error, 0.01 * p.expected_radiance()) << "the test has power";
}

// The record buffers do not grow with the resolution: beyond kMaxRecords records per iteration,
// one pixel in k records (weighted by k). 400x400 stays under the cap (about 20 MB); 4x the
// pixels must not take 4x the memory (measured: 1.8x).
TEST(GuidedPathTracer, RecordBuffersAreBoundedAtHighResolution) {
  auto peak = [](int size) {
    auto scene = make_builtin_scene("cornell", size, size);
    IntegratorSettings settings;
    settings.max_depth = 4;
    GuidedPathTracer integrator(settings);
    const nlohmann::json stats = render_and_report(*scene, integrator, 3);
    std::printf("[ records ] %dx%d: peak %.1f MB, stride %d\n", size, size,
                stats["guiding"]["record_buffer_peak_bytes"].get<double>() * 1e-6,
                stats["guiding"]["record_pixel_stride_last"].get<int>());
    return stats["guiding"]["record_buffer_peak_bytes"].get<double>();
  };
  const double small = peak(400), large = peak(800);
  EXPECT_LT(large, 0.6 * 4 * small);
  EXPECT_LT(large, 3 * 40.0 * double(1 << 20));  // records, their copy by leaf, vector slack
}

// guided-vcm learns the importance that light subpaths are guided by from camera vertices reached
// through a diffuse or glossy bounce only. Importance arriving straight from the lens is what
// light tracing connects to: a light subpath scattered toward the pinhole finds nothing. Learned
// from the first camera vertices too, the guide at the visible back wall pointed at the camera
// (its pdf toward the lens 21.5x that of a uniform density on cornell); without them, 3.1x.
TEST(GuidedVcm, ImportanceIsNotLearnedStraightFromTheLens) {
  auto scene = make_builtin_scene("cornell", 32, 32);
  IntegratorSettings settings;
  bidir::BidirIntegrator integrator(BidirAlgorithm::GuidedVcm, settings);
  RenderBudget budget;
  budget.spp = 16;
  RenderCallbacks cb;
  cb.quiet = true;
  render(*scene, integrator, budget, cb);
  const Ray ray = scene->camera().generate_ray({16, 16}, {0.5f, 0.5f});
  SurfaceInteraction si;
  ASSERT_TRUE(scene->intersect(ray, &si));
  const GuidingField& importance = integrator.guiding().importance();
  const int side = GuidingField::side_class(face_forward(si.ng, si.wo));
  const DirectionalQuadtree& guide = importance.sampling(importance.leaf_at(si.p, side));
  ASSERT_GT(guide.total(), 0);
  const float toward_lens = guide.pdf(si.wo) * 4 * kPi;  // 1: uniform over the sphere
  std::printf("[ importance ] toward the lens %.2f x uniform\n", toward_lens);
  EXPECT_LT(toward_lens, 6.f);
}

// guided-bpt and guided-vcm sample the guided mixtures and weight every technique either with the
// mixtures' densities (--guiding-mis mixture) or with the BSDFs' alone (bsdf, the default), as
// unguided bpt/vcm would. Both weightings sum to one over the techniques of every path, so both
// stay unbiased: on the Cornell box (its light small enough for the learned radiance to point at
// it, unlike the BSDFs) the image mean after 16 samples per pixel (the last 8 guided) agrees with
// bpt's over six seeds each. A mixture's forward density left in the BSDF weighting's sums moved
// the mean by 1% (0.3051 against 0.3084, se 0.0004).
TEST(GuidedVcm, BothMisWeightingsStayUnbiased) {
  auto scene = make_builtin_scene("cornell", 24, 24);
  auto mean_of = [&](const char* name, bool guided_mis) {
    IntegratorSettings s;
    s.max_depth = 6;
    s.guiding.guided_mis = guided_mis;
    return test::over_seeds(6, [&](uint64_t seed) {
      s.seed = seed;
      const auto r = test::render_with(*scene, name, 16, s);
      EXPECT_EQ(r.nonfinite, 0u) << name;
      return test::pixel_stats(r.image).mean;
    });
  };
  const auto bpt = mean_of("bpt", false);
  for (const bool guided_mis : {false, true})
    for (const char* name : {"guided-bpt", "guided-vcm"}) {
      const auto x = mean_of(name, guided_mis);
      std::printf("[ %s mis ] %-10s mean %.5f se %.5f (bpt %.5f se %.5f)\n",
                  guided_mis ? "mixture" : "bsdf", name, x.mean, x.standard_error, bpt.mean,
                  bpt.standard_error);
      // guided-vcm merges (consistent): 1% of the mean at the first radius.
      const double bias = std::string(name) == "guided-vcm" ? 0.01 * bpt.mean : 0.0;
      EXPECT_NEAR(x.mean, bpt.mean, 3 * std::hypot(x.standard_error, bpt.standard_error) + bias)
          << name << (guided_mis ? " mixture" : " bsdf");
    }
}

// guided-bpt and guided-vcm take next event estimation, lens connections and connections with
// probabilities learned per leaf (bidir/technique_probabilities.h); each count enters the MIS
// sums and each taken sample divides by its probability. Forced to the floor in every leaf with
// enough samples (a visible share of 1), the Cornell box's image mean must still agree with
// bpt's over six seeds, and every technique must have been reduced somewhere.
TEST(GuidedVcm, TechniqueProbabilitiesKeepTheEstimateUnbiased) {
  auto scene = make_builtin_scene("cornell", 24, 24);
  IntegratorSettings s;
  s.max_depth = 6;
  s.guiding.nee_floor = 0.25f;
  s.guiding.nee_visible_share = 1;
  const auto bpt = test::over_seeds(6, [&](uint64_t seed) {
    IntegratorSettings plain = s;
    plain.seed = seed;
    return test::pixel_stats(test::render_with(*scene, "bpt", 16, plain).image).mean;
  });
  for (const BidirAlgorithm algorithm : {BidirAlgorithm::GuidedBpt, BidirAlgorithm::GuidedVcm}) {
    bidir::BidirIntegrator integrator(algorithm, s);
    const nlohmann::json stats = render_and_report(*scene, integrator, 16);
    const nlohmann::json& g = stats["guiding"];
    for (const char* key :
         {"nee_reduced_leaves", "lens_connection_reduced_leaves", "connection_reduced_leaves"})
      EXPECT_GT(g[key].get<size_t>(), 0u) << key;
    const char* name = algorithm == BidirAlgorithm::GuidedBpt ? "guided-bpt" : "guided-vcm";
    const auto x = test::over_seeds(6, [&](uint64_t seed) {
      IntegratorSettings seeded = s;
      seeded.seed = seed;
      const auto r = test::render_with(*scene, name, 16, seeded);
      EXPECT_EQ(r.nonfinite, 0u) << name;
      return test::pixel_stats(r.image).mean;
    });
    std::printf("[ technique floor ] %-10s mean %.5f se %.5f (bpt %.5f se %.5f)\n", name, x.mean,
                x.standard_error, bpt.mean, bpt.standard_error);
    const double bias = algorithm == BidirAlgorithm::GuidedVcm ? 0.01 * bpt.mean : 0.0;
    EXPECT_NEAR(x.mean, bpt.mean, 3 * std::hypot(x.standard_error, bpt.standard_error) + bias)
        << name;
  }
}

// guided-bpt and guided-vcm combine their passes by inverse variance, as guided-pt does: the
// image is not the film's plain average, and each pass holds a whole iteration's estimate (the
// camera estimates and the light-tracing splats: a pass without its splats lost light tracing's
// share of the Cornell box, several standard errors).
TEST(GuidedVcm, PassesCombineByInverseVarianceWithTheirSplats) {
  auto scene = make_builtin_scene("cornell", 24, 24);
  for (const char* name : {"guided-bpt", "guided-vcm"}) {
    int differing = 0;
    const auto difference = test::over_seeds(6, [&](uint64_t seed) {
      IntegratorSettings s;
      s.max_depth = 6;
      s.seed = seed;
      s.guiding.inverse_variance = true;
      const Image combined = test::render_with(*scene, name, 32, s).image;
      s.guiding.inverse_variance = false;
      const Image average = test::render_with(*scene, name, 32, s).image;
      differing += test::pixel_stats(combined).mean != test::pixel_stats(average).mean;
      return test::pixel_stats(combined).mean - test::pixel_stats(average).mean;
    });
    std::printf("[ %s ] inverse variance - plain average: %.5f se %.5f\n", name, difference.mean,
                difference.standard_error);
    EXPECT_EQ(differing, 6) << name;
    EXPECT_NEAR(difference.mean, 0.0, 3 * difference.standard_error + 1e-4) << name;
  }
}
