// The learned incident-radiance field of Müller et al. 2017, "Practical Path Guiding for
// Efficient Light-Transport Simulation" (the SD-tree, sec. 3): a binary tree over the scene's
// bounding box whose leaves each hold a directional quadtree (directional_quadtree.h) of the
// radiance arriving in their region, and the learned BSDF-vs-guide selection probability of
// Müller 2019 (selection_optimizer.h). Every leaf keeps two quadtrees: `sampling`, learned in the
// previous training pass and read while rendering, and `recording`, which the current pass's
// samples are splatted into.
//
// Training pass k ends with end_pass(k) (sec. 3.4):
//  1. recording becomes sampling;
//  2. a leaf that recorded more than c sqrt(2^k) path vertices (statistical weight) is split in
//     two at the middle of its box's longest axis (the children copy its distributions, its
//     selection optimizer and half its weight), repeatedly;
//  3. each leaf's recording structure is rebuilt from its sampling distribution, refining
//     quadrants whose energy share exceeds rho, and starts from GuidingSettings::carry of that
//     distribution's energy (Müller: zero).
//
// Memory cap: the whole structure (memory_bytes(): spatial nodes, leaves and every quadtree)
// stays under GuidingSettings::max_bytes. Splits and refinements that would exceed it are not
// done (leaves are visited in index order, so what is kept is deterministic).
//
// Determinism: splat() takes the records in an order that does not depend on threads (the caller's:
// pixel, then position along the path; pixel_records.h gathers them so without a merged copy),
// groups them by leaf keeping that order (a stable counting sort), and processes the leaves in
// parallel, each leaf's records in order: the field does not depend on thread scheduling.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <span>
#include <vector>

#include "core/vec.h"
#include "guiding/directional_quadtree.h"
#include "guiding/guiding_settings.h"
#include "guiding/selection_optimizer.h"

namespace caustica {

// One sample of the incident radiance at a point, to splat.
struct GuidingRecord {
  uint64_t key = 0;   // the caller's order (e.g. pixel, then vertex along the path)
  uint32_t leaf = 0;  // the spatial leaf it goes to (after the spatial filter's jitter)
  Vec2 square;        // its direction, on the unit square (direction_to_square)
  // Luminance of the incident radiance estimate over the density its direction was sampled
  // with (Müller et al. 2017, sec. 3.2: summed over a quadrant, an estimate of its flux).
  float radiance = 0;
  // Luminance of f |cos| L_i over the same density: the selection optimizer's target.
  float product = 0;
  // Densities (solid angle) of the BSDF and of the learned distribution at the direction;
  // guide_pdf <= 0: the vertex had no learned distribution (the optimizer skips it).
  float bsdf_pdf = 0, guide_pdf = 0;
  // The selection optimizer's batch weight: 1 for a path vertex, 0 for a next event sample.
  float statistical_weight = 1;
};

class GuidingField {
 public:
  GuidingField() : GuidingField(Bounds3{{0, 0, 0}, {1, 1, 1}}, {}) {}
  // sided: the field is kept once per side class (side_class(): six classes of the normal on the
  // side a vertex is seen from), so that the two faces of a thin wall, or a floor and the wall
  // it meets, learn and sample separate distributions. One guide for both faces of a
  // zero-thickness wall sent a third of guided-pt's guided directions, and half of guided
  // bidirectional ones, below the surface (f = 0) on door-ajar. Implemented as eight copies of
  // the box side by side along x, one per class, split apart before anything is learned; the
  // spatial tree, its split rule and the memory cap are shared.
  GuidingField(Bounds3 bounds, const GuidingSettings& settings, bool sided = false);

  // The side class of a normal n facing the side a vertex is seen from: 2 * (the axis of its
  // largest component) + (that component < 0). The other side of the surface is class ^ 1.
  static int side_class(Vec3 n);
  static constexpr int kSideClasses = 6;

  // The leaf whose box holds p (points outside the box go to the nearest leaf), in the copy of
  // side class `side` (0 unless the field is sided).
  uint32_t leaf_at(Vec3 p, int side = 0) const;
  // The leaf of p moved by (u - 1/2) times the size of the box of `leaf` (p's leaf): a sample of
  // the box filter of the spatial splat (Müller 2019). u in [0, 1)^3. It stays in p's class.
  uint32_t jittered_leaf(Vec3 p, uint32_t leaf, Vec3 u, int side = 0) const;
  // The distribution learned for the leaf; its total() is 0 until some radiance was recorded.
  const DirectionalQuadtree& sampling(uint32_t leaf) const { return leaves_[leaf].sampling; }
  // The leaf's box (in the copy of its side class where the field is sided).
  const Bounds3& leaf_box(uint32_t leaf) const { return leaves_[leaf].box; }
  // The probability of sampling the BSDF at the leaf (fixed, or learned: guiding_settings.h).
  float bsdf_fraction(uint32_t leaf) const;
  // Techniques that a vertex takes with a learned probability (add_technique_counts()): next
  // event estimation (guided-pt, guided-bpt, guided-vcm), and in the bidirectional core the
  // lens connection of a light vertex and the connection of a light vertex to a camera vertex.
  enum Technique : int { kNextEvent = 0, kLensConnection = 1, kConnection = 2, kTechniques = 3 };
  // What a vertex in the leaf samples with, in one small record read per vertex: the learned
  // distribution (nullptr until the leaf has learned radiance), the BSDF selection probability
  // and the techniques' probabilities. Refreshed by splat() and end_pass().
  struct Guide {
    const DirectionalQuadtree* distribution = nullptr;
    float bsdf_fraction = 1;
    float probability[kTechniques] = {1, 1, 1};  // see add_technique_counts()
  };
  const Guide& guide(uint32_t leaf) const { return guides_[leaf]; }

  // Adds path vertex counts per leaf (counts[leaf], as many as leaf_count()) for the split
  // rule. Every guided vertex counts, whether or not it found radiance (Müller et al. 2017:
  // "path vertices"). Callers count per thread and add the integers in any order.
  void add_vertex_counts(const std::vector<uint32_t>& counts);
  // Adds samples of technique t per leaf: counts[2 leaf] taken at the leaf's vertices (for
  // next event estimation: light samples; for connections: shadow rays), counts[2 leaf + 1] of
  // them unoccluded with a non-zero contribution (callers count per thread, as above).
  // end_pass() sets the probability of t at a leaf that saw something to 1 and at one that took
  // at least kNeeEvidence samples and saw nothing (at most GuidingSettings::nee_visible_share of
  // them, for connections at most connection_visible_share) to GuidingSettings::nee_floor; a leaf
  // with fewer samples keeps its probability (children inherit their parent's). A leaf at the floor
  // still takes samples: a later pass that sees something there sets it back to 1.
  static constexpr uint32_t kNeeEvidence = 64;
  void add_technique_counts(Technique t, const std::vector<uint32_t>& counts);
  void add_nee_counts(const std::vector<uint32_t>& counts) {
    add_technique_counts(kNextEvent, counts);
  }
  // The leaves whose probability of technique t is below 1 (a statistic).
  size_t reduced_leaves(Technique t = kNextEvent) const;
  // The share of technique t's attempts in the last training pass that counted it (samples
  // taken over their probability) made in leaves whose probability is now below 1.
  double reduced_attempt_share(Technique t) const { return reduced_attempt_share_[t]; }
  size_t reduced_nee_leaves() const { return reduced_leaves(kNextEvent); }
  // Records one sample directly (sequential; tests), counting it as a vertex when its
  // statistical weight is positive.
  void record(const GuidingRecord& r);
  // Splats the records of `runs`, run after run (see Determinism above).
  void splat(std::span<const std::span<const GuidingRecord>> runs);
  void splat(std::span<const GuidingRecord> records) { splat({&records, 1}); }
  // The bytes of splat()'s buffer (kept between calls; not part of memory_bytes()).
  size_t splat_buffer_bytes() const { return grouped_.bytes(); }
  // Ends training pass k (0-based, the k-th with 2^k samples per pixel); see above.
  void end_pass(int k);

  const GuidingSettings& settings() const { return settings_; }
  size_t leaf_count() const { return leaves_.size(); }
  size_t spatial_node_count() const { return nodes_.size(); }
  size_t quadtree_node_count() const;
  size_t memory_bytes() const;
  uint64_t counted_vertices() const;  // in the current pass
  // The mean over leaves of the BSDF selection probability (a statistic).
  double mean_bsdf_fraction() const;

 private:
  // 8 bytes, so that the descent stays in cache: the two children of an inner node are
  // adjacent, and a leaf stores its index into leaves_.
  struct SpatialNode {
    static constexpr uint32_t kLeaf = 3, kIndexMask = (1u << 30) - 1;
    float middle = 0;               // inner: the split position along the axis
    uint32_t packed = kLeaf << 30;  // bits 30-31: axis (kLeaf: a leaf); 0-29: first child / leaf
    uint32_t axis() const { return packed >> 30; }
    uint32_t index() const { return packed & kIndexMask; }
  };
  struct Leaf {
    Bounds3 box;
    DirectionalQuadtree sampling, recording;
    SelectionOptimizer selection;
    double carry_share = 1;  // of its distribution's energy, halved at each split (carry)
    float probability[kTechniques] = {1, 1, 1};
  };
  void record_into(Leaf& leaf, const GuidingRecord& r);
  // Splits a leaf node in two at the middle of `axis` (-1: its box's longest axis).
  void split(uint32_t node, std::vector<uint64_t>& counts, int axis = -1);
  // The leaf holding p, descending from node `start` (p must lie in its box).
  uint32_t leaf_of_point(Vec3 p, uint32_t start) const;
  // The start grid: a uniform grid over the root box (dyadic cells, about cubic, at most
  // kStartCells and an eighth of the memory cap) holding per cell the deepest node whose box
  // contains the whole cell, the outer cells reaching to infinity. A descent starts at its
  // point's cell: the same leaf as from the root, a dozen fewer dependent loads. Points within
  // kStartTolerance of a cell's inner border (where float rounding could put them in the wrong
  // cell) start at the root. Rebuilt whenever the tree changes.
  static constexpr size_t kStartCells = size_t(1) << 13;
  static constexpr float kStartTolerance = 1e-3f;  // in cells
  void build_start_grid();
  uint32_t start_node(Vec3 p) const;
  // p clamped into the scene's box along x and moved into the copy of its side class.
  Vec3 class_point(Vec3 p, int side) const;
  void split_leaves(int k);
  size_t leaf_bytes(const Leaf& l) const;

  GuidingSettings settings_;
  Bounds3 bounds_;        // the scene's box (copy 0)
  float copy_width_ = 0;  // sided: the x extent of one copy
  bool sided_ = false;
  std::vector<SpatialNode> nodes_;  // nodes_[0] is the root
  std::vector<uint32_t> start_;     // the start grid, x fastest
  std::array<int, 3> start_dims_{1, 1, 1};
  Vec3 start_origin_, start_scale_;  // cell coordinates of p: (p - origin) * scale
  std::vector<Leaf> leaves_;
  std::vector<uint64_t> counts_;  // path vertices per leaf in the current pass
  // Per technique and leaf: samples taken, of them seeing something.
  std::array<std::vector<uint64_t>, kTechniques> technique_counts_;
  double reduced_attempt_share_[kTechniques] = {0, 0, 0};
  std::vector<Guide> guides_;  // per leaf
  // Uninitialised storage for splat()'s records grouped by leaf, grown and kept, so that the
  // parallel scatter, not a serial constructor, first touches its pages. A copy starts empty.
  class RecordScratch {
   public:
    RecordScratch() = default;
    RecordScratch(const RecordScratch&) {}
    RecordScratch& operator=(const RecordScratch&) { return *this; }
    GuidingRecord* reserve(size_t n);
    size_t bytes() const { return capacity_ * sizeof(GuidingRecord); }

   private:
    struct Free {
      void operator()(GuidingRecord* p) const { ::operator delete(p); }
    };
    std::unique_ptr<GuidingRecord, Free> data_;
    size_t capacity_ = 0;
  };
  RecordScratch grouped_;
  void refresh_guides();
};

}  // namespace caustica
