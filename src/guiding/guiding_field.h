// The learned incident-radiance field of Müller et al. 2017, "Practical Path Guiding for
// Efficient Light-Transport Simulation" (the SD-tree, sec. 3): a binary tree over the scene's
// bounding box whose leaves each hold a directional quadtree (directional_quadtree.h) of the
// radiance arriving in their region. Every leaf keeps two: `sampling`, learned in the previous
// training iteration and read while rendering, and `recording`, which the current iteration's
// samples are splatted into.
//
// Training iteration k ends with end_iteration(k) (sec. 3.4):
//  1. recording becomes sampling;
//  2. a leaf that recorded more than c sqrt(2^k) samples is split in two at the middle of its
//     box's longest axis (the children copy its distributions and half its count), repeatedly;
//  3. each leaf's recording structure is rebuilt from its sampling distribution, refining
//     quadrants whose energy share exceeds rho (zero energies).
//
// Memory cap: the directional quadtrees of all leaves together hold at most
// GuidingSettings::max_quadtree_nodes nodes (each DirectionalQuadtree::kNodeBytes bytes); where
// a split or a refinement would exceed it, it is not done (leaves are visited in index order,
// so what is kept is deterministic). memory_bytes() reports the whole structure.
//
// Determinism: record() is sequential; callers splat their samples in a fixed order.
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

#include "core/vec.h"
#include "guiding/directional_quadtree.h"

namespace caustica {

struct GuidingSettings {
  double spatial_threshold = 12000;  // c of the split rule c sqrt(2^k) (Müller et al. 2017)
  double rho = 0.01;                 // quadrant refinement threshold (energy share)
  int max_quadtree_depth = 20;
  size_t max_quadtree_nodes = size_t(1) << 21;  // the memory cap: about 100 MiB
};

// One radiance sample to splat: where, which direction (world, pointing away from p), and how
// much: the incident radiance estimate divided by the density the direction was sampled with
// (its luminance), so that sums over a quadrant estimate the flux through it.
struct RadianceRecord {
  Vec3 p;
  Vec3 wi;
  float value = 0;
};

class GuidingField {
 public:
  GuidingField() : GuidingField(Bounds3{{0, 0, 0}, {1, 1, 1}}, {}) {}
  GuidingField(Bounds3 bounds, const GuidingSettings& settings);

  // The leaf whose box holds p (points outside the box go to the nearest leaf).
  uint32_t leaf_at(Vec3 p) const;
  // The distribution learned for the leaf; its total() is 0 until some radiance was recorded.
  const DirectionalQuadtree& sampling(uint32_t leaf) const { return leaves_[leaf].sampling; }

  void record(const RadianceRecord& r);
  void record(uint32_t leaf, Vec3 wi, float value);
  // Ends training iteration k (0-based, the k-th with 2^k samples per pixel); see above.
  void end_iteration(int k);

  size_t leaf_count() const { return leaves_.size(); }
  size_t spatial_node_count() const { return nodes_.size(); }
  size_t quadtree_node_count() const;
  size_t memory_bytes() const;
  uint64_t recorded_samples() const;  // in the current iteration

 private:
  struct SpatialNode {
    Bounds3 box;
    uint32_t child[2] = {0, 0};  // both 0: a leaf
    uint32_t leaf = 0;           // index into leaves_ when a leaf
    int axis = 0;                // inner: the split axis, at `middle`
    float middle = 0;
  };
  struct Leaf {
    DirectionalQuadtree sampling, recording;
    uint64_t samples = 0;  // recorded in the current iteration
  };
  void split(uint32_t node);

  GuidingSettings settings_;
  std::vector<SpatialNode> nodes_;  // nodes_[0] is the root
  std::vector<Leaf> leaves_;
};

}  // namespace caustica
