// The directional part of Müller et al. 2017, "Practical Path Guiding for Efficient
// Light-Transport Simulation" (sec. 3.3): a quadtree over the square of cylindrical
// coordinates (cos theta, phi) of world directions. The mapping is area preserving (Archimedes'
// hat-box theorem), so the solid-angle density of a direction is its density on the unit square
// divided by 4 pi: pdf(w) = (energy fraction of its leaf / area of the leaf) / (4 pi).
//
// Each node splits its square into four quadrants (index ix + 2 iy, ix = x >= 1/2); a quadrant
// is a leaf (child 0) or an inner node. A node stores the energy of each quadrant; recording adds
// to leaf quadrants only and propagate() fills the inner sums, so splatting order does not
// change the structure (and, splatted in a fixed order, not the sums either).
//
// Sampling and densities read a second, compact layout that propagate() builds (SamplingNode:
// 32 bytes per node holding what a descent needs, nodes breadth first with the children of a
// node side by side): a descent is one load per level and no division (from the energies it
// would take a division per coordinate and level, and the children's indices would scatter).
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <vector>

#include "core/vec.h"

namespace caustica {

// Unit square <-> unit direction: u = (cos theta + 1) / 2, v = phi / (2 pi).
Vec2 direction_to_square(Vec3 w);
Vec3 square_to_direction(Vec2 p);

class DirectionalQuadtree {
 public:
  struct Node {
    // Per quadrant: recorded flux (inner: sum of its subtree). Float: a node is 32 bytes, and
    // a sampling distribution needs no more precision.
    std::array<float, 4> energy{};
    std::array<uint32_t, 4> child{};  // 0: the quadrant is a leaf
  };

  // One node: four uniform leaf quadrants.
  DirectionalQuadtree() : nodes_(1) {}

  // Sum of the recorded energy (after propagate()).
  double total() const;
  // Adds `value` to the leaf quadrant holding p (a point of the unit square). propagate()
  // afterwards, before sampling.
  void record(Vec2 p, double value);
  // Box-filtered recording (Müller 2019, "Practical Path Guiding in Production", sec. on
  // filtering): `value` is spread over a square of the side of the leaf quadrant holding p,
  // centred at p, in proportion to its overlap with each leaf quadrant. The square is moved
  // inside the unit square in u (cos theta) and wraps around in v (phi), so no energy is lost.
  void record_filtered(Vec2 p, double value);
  // The same filter stochastically: `value` recorded at p moved by (u - 1/2) times that side
  // (reflected back into the square in u, wrapped in v). Its expectation over u in [0, 1)^2 is
  // record_filtered(); it costs two descents instead of a walk over every overlapped quadrant.
  void record_jittered(Vec2 p, double value, Vec2 u);
  // Recomputes inner nodes' energies from the leaves (bottom up) and builds the sampling layout
  // from them (record() after it leaves that stale until the next propagate(); a sampling
  // distribution is no longer recorded into).
  void propagate();

  // Density on the unit square at p, of the distribution of the last propagate(); 0 everywhere
  // if total() == 0 or before any propagate(). Solid angle: pdf / (4 pi).
  float pdf_square(Vec2 p) const;
  float pdf(Vec3 w) const;
  // Hierarchical sample warping (Müller et al. 2017, sec. 3.3 and its appendix): u picks a
  // quadrant per level; requires total() > 0 and propagate(). With pdf, also the density on
  // the square of the leaf it lands in: bit for bit what pdf_square() returns there.
  Vec2 sample_square(Vec2 u, float* pdf = nullptr) const;
  Vec3 sample(Vec2 u) const { return square_to_direction(sample_square(u)); }

  // The structure for the next training iteration (Müller et al. 2017, sec. 3.4): a quadrant is
  // subdivided where its share of the total energy exceeds rho (a leaf's share split evenly
  // among its would-be children), up to max_depth levels; everything else collapses. The
  // energies of the result are `carry` times this tree's, spread over its leaf quadrants by
  // their shares (0: empty). At most *node_budget nodes are created (beyond the root), and
  // *node_budget is decremented by what was.
  DirectionalQuadtree refined(double rho, int max_depth, size_t* node_budget,
                              double carry = 0) const;

  size_t node_count() const { return nodes_.size(); }
  size_t bytes() const {
    return nodes_.capacity() * sizeof(Node) + sampling_.capacity() * sizeof(SamplingNode);
  }
  void shrink_to_fit() {
    nodes_.shrink_to_fit();
    sampling_.shrink_to_fit();
  }
  int depth() const;

  // A node of the sampling layout. Sampling picks the column ix = 0 with probability p_left =
  // (e_0 + e_2) / (sum of e) and then, in column ix, the row iy = 0 with probability
  // p_lower[ix] = e_ix / (e_ix + e_ix+2) (both rounded to float); quadrant q multiplies the
  // density by factor[q] = 4 P(q) (a quarter of the parent's area; P(q) = e_q / sum but for the
  // rounding, and 0 where the node has no energy).
  struct SamplingNode {
    static constexpr uint32_t kIndexMask = (1u << 28) - 1;
    float p_left = 0.5f;
    std::array<float, 2> p_lower{0.5f, 0.5f};
    // Bits 0-27: the index of the first child; bit 28 + q: quadrant q is an inner node. The
    // children of the inner quadrants follow one another in quadrant order.
    uint32_t children = 0;
    std::array<float, 4> factor{};
    bool inner(int q) const { return (children >> (28 + q)) & 1; }
    // The first child plus the inner quadrants before q: the popcount of a 3-bit mask m, read
    // from the 2-bit fields of 0xE994 (0, 1, 1, 2, 1, 2, 2, 3; a baseline x86-64 build has no
    // popcount instruction, and std::popcount becomes a library call).
    uint32_t child(int q) const {
      const uint32_t before = (children >> 28) & ((1u << q) - 1);
      return (children & kIndexMask) + ((0xE994u >> (2 * before)) & 3);
    }
  };
  static_assert(sizeof(SamplingNode) == 32);
  // Per node, sampled or recorded: the node and its sampling layout.
  static constexpr size_t kNodeBytes = sizeof(Node) + sizeof(SamplingNode);

 private:
  // Adds density * (overlap area) of the box [x0, x1) x [y0, y1) to the leaf quadrants under
  // `node`, whose square has corner (ox, oy) and side `size`.
  void record_box(uint32_t node, double ox, double oy, double size, const double box[4],
                  double density);
  // Side of the leaf quadrant holding p.
  double leaf_size(Vec2 p) const;

  std::vector<Node> nodes_;             // nodes_[0] is the root; children come after their parents
  std::vector<SamplingNode> sampling_;  // from propagate(): sampling_[0] is the root
};

}  // namespace caustica
