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
  // Recomputes inner nodes' energies from the leaves (bottom up), and each node's density
  // factors (4 e_q / total per quadrant), which pdf_square() and sample_square() multiply along
  // the descent instead of dividing at every level (record() after it leaves them stale until
  // the next propagate(); a sampling distribution is no longer recorded into).
  void propagate();

  // Density on the unit square at p; 0 everywhere if total() == 0. Solid angle: pdf / (4 pi).
  float pdf_square(Vec2 p) const;
  float pdf(Vec3 w) const;
  // Hierarchical sample warping (Müller et al. 2017, sec. 3.3 and its appendix): u picks a
  // quadrant per level and is rescaled; requires total() > 0. With pdf, also the density on
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
    return nodes_.capacity() * sizeof(Node) + factors_.capacity() * sizeof(factors_[0]);
  }
  void shrink_to_fit() {
    nodes_.shrink_to_fit();
    factors_.shrink_to_fit();
  }
  int depth() const;
  // Per node, sampled or recorded: the node and its density factors.
  static constexpr size_t kNodeBytes = sizeof(Node) + sizeof(std::array<float, 4>);

 private:
  // Adds density * (overlap area) of the box [x0, x1) x [y0, y1) to the leaf quadrants under
  // `node`, whose square has corner (ox, oy) and side `size`.
  void record_box(uint32_t node, double ox, double oy, double size, const double box[4],
                  double density);
  // Side of the leaf quadrant holding p.
  double leaf_size(Vec2 p) const;

  // Quadrant q of node n multiplies the density by factor(n, q) = 4 e_q / (sum of e) (0 where
  // the node has no energy): from
  // factors_ when propagate() filled it, else computed (the same float expression either way,
  // so that sample_square() and pdf_square() agree bit for bit).
  float factor(uint32_t node, int q) const {
    if (factors_.size() == nodes_.size()) return factors_[node][q];
    const std::array<float, 4>& e = nodes_[node].energy;
    const float total = (e[0] + e[1]) + (e[2] + e[3]);
    return total > 0 ? 4 * e[q] / total : 0.f;  // no energy below: density 0
  }

  std::vector<Node> nodes_;  // nodes_[0] is the root; children come after their parents
  std::vector<std::array<float, 4>> factors_;
};

}  // namespace caustica
