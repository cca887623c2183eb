// The learned radiance field of path guiding (guiding/, after Müller et al. 2017 and Müller
// 2019): its directional distribution is a density over the sphere whose samples follow it,
// trained on a known radiance field it learns that field, its spatial tree finds the leaf of any
// point and separates the sides of a surface, its memory stays under the cap, its filtered
// splats conserve energy and its training does not depend on the order of the records; the
// learned next event and selection probabilities follow the better technique. The passes it is
// trained in: training_schedule_test.cpp; the integrators that use it:
// guided_integrators_test.cpp.
#include "guiding/guiding_field.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <span>
#include <utility>
#include <vector>

#include "chi2.h"
#include "core/math.h"

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
