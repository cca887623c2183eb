#include "guiding/directional_quadtree.h"

#include <algorithm>
#include <bit>
#include <cmath>
#include <stdexcept>

#include "core/math.h"

namespace caustica {

namespace {

double sum(const std::array<float, 4>& e) { return (double(e[0]) + e[1]) + (double(e[2]) + e[3]); }

}  // namespace

namespace {

// atan2 by a minimax polynomial for atan on [0, 1] (maximum error 1.7e-6 radians): the mapping
// runs for every guided direction, and std::atan2 was a noticeable share of the render.
float fast_atan2(float y, float x) {
  const float ax = std::abs(x), ay = std::abs(y);
  const float hi = std::max(ax, ay), a = hi > 0 ? std::min(ax, ay) / hi : 0.f, s = a * a;
  float r = -0.01172120f;
  r = r * s + 0.05265332f;
  r = r * s - 0.11643287f;
  r = r * s + 0.19354346f;
  r = r * s - 0.33262347f;
  r = (r * s + 0.99997726f) * a;
  if (ay > ax) r = 0.5f * kPi - r;
  if (x < 0) r = kPi - r;
  return y < 0 ? -r : r;
}

}  // namespace

Vec2 direction_to_square(Vec3 w) {
  const float cos_theta = std::clamp(w.z, -1.f, 1.f);
  float phi = fast_atan2(w.y, w.x);
  if (phi < 0) phi += 2 * kPi;
  const float v = phi * (0.5f / kPi);
  return {std::clamp((cos_theta + 1) * 0.5f, 0.f, kOneMinusEpsilon),
          std::clamp(v, 0.f, kOneMinusEpsilon)};
}

Vec3 square_to_direction(Vec2 p) {
  const float cos_theta = 2 * p.x - 1, sin_theta = safe_sqrt(1 - cos_theta * cos_theta);
  const float phi = 2 * kPi * p.y;
  return {sin_theta * std::cos(phi), sin_theta * std::sin(phi), cos_theta};
}

double DirectionalQuadtree::total() const { return sum(nodes_[0].energy); }

void DirectionalQuadtree::record(Vec2 p, double value) {
  double x = p.x, y = p.y;
  uint32_t node = 0;
  for (;;) {
    const int ix = x >= 0.5, iy = y >= 0.5, q = ix + 2 * iy;
    x = 2 * x - ix;
    y = 2 * y - iy;
    const uint32_t child = nodes_[node].child[q];
    if (!child) {
      nodes_[node].energy[q] += float(value);
      return;
    }
    node = child;
  }
}

double DirectionalQuadtree::leaf_size(Vec2 p) const {
  double x = p.x, y = p.y, size = 1;
  uint32_t node = 0;
  for (;;) {
    const int ix = x >= 0.5, iy = y >= 0.5;
    x = 2 * x - ix;
    y = 2 * y - iy;
    size *= 0.5;
    const uint32_t child = nodes_[node].child[ix + 2 * iy];
    if (!child) return size;
    node = child;
  }
}

void DirectionalQuadtree::record_filtered(Vec2 p, double value) {
  const double size = leaf_size(p), density = value / (size * size);
  const double x0 = std::clamp(double(p.x) - size / 2, 0.0, 1.0 - size);
  const double y0 = double(p.y) - size / 2, y1 = y0 + size;
  auto splat = [&](double lo, double hi) {
    const double box[4] = {x0, x0 + size, lo, hi};
    if (hi > lo) record_box(0, 0, 0, 1, box, density);
  };
  if (y0 < 0) {  // phi wraps around
    splat(0, y1);
    splat(1 + y0, 1);
  } else if (y1 > 1) {
    splat(y0, 1);
    splat(0, y1 - 1);
  } else {
    splat(y0, y1);
  }
}

void DirectionalQuadtree::record_jittered(Vec2 p, double value, Vec2 u) {
  const double size = leaf_size(p);
  double x = p.x + (u.x - 0.5) * size, y = p.y + (u.y - 0.5) * size;
  if (x < 0) x = -x;
  if (x >= 1) x = 2 - x;
  y -= std::floor(y);
  record(Vec2(float(std::clamp(x, 0.0, double(kOneMinusEpsilon))),
              float(std::clamp(y, 0.0, double(kOneMinusEpsilon)))),
         value);
}

void DirectionalQuadtree::record_box(uint32_t node, double ox, double oy, double size,
                                     const double box[4], double density) {
  const double half = size / 2;
  for (int q = 0; q < 4; ++q) {
    const double qx = ox + (q & 1) * half, qy = oy + (q >> 1) * half;
    const double w = std::min(box[1], qx + half) - std::max(box[0], qx);
    const double h = std::min(box[3], qy + half) - std::max(box[2], qy);
    if (!(w > 0 && h > 0)) continue;
    if (const uint32_t child = nodes_[node].child[q])
      record_box(child, qx, qy, half, box, density);
    else
      nodes_[node].energy[q] += float(density * w * h);
  }
}

void DirectionalQuadtree::propagate() {
  for (size_t i = nodes_.size(); i-- > 0;)
    for (int q = 0; q < 4; ++q)
      if (const uint32_t c = nodes_[i].child[q]) nodes_[i].energy[q] = float(sum(nodes_[c].energy));
  if (nodes_.size() > SamplingNode::kIndexMask)
    throw std::length_error("a directional quadtree of more than 2^28 nodes");
  // Breadth first: the sampling layout's node i is nodes_[order[i]]; a node's inner quadrants
  // take the next free indices, in quadrant order.
  sampling_.assign(nodes_.size(), SamplingNode());
  std::vector<uint32_t> order(nodes_.size());
  uint32_t next = 1;
  for (size_t i = 0; i < nodes_.size(); ++i) {
    const Node& n = nodes_[order[i]];
    SamplingNode& s = sampling_[i];
    const std::array<float, 4>& e = n.energy;
    const double total = sum(e), left = double(e[0]) + e[2];
    if (total > 0) {
      s.p_left = float(left / total);
      for (int ix = 0; ix < 2; ++ix) {
        const double column = double(e[ix]) + e[ix + 2];
        s.p_lower[ix] = column > 0 ? float(e[ix] / column) : 0.5f;
        // From the rounded probabilities, not from e: the density is the sampling's, and a
        // quadrant whose probability rounded to 0 has density 0.
        const double p_column = ix ? 1 - double(s.p_left) : double(s.p_left);
        s.factor[ix] = float(4 * p_column * s.p_lower[ix]);
        s.factor[ix + 2] = float(4 * p_column * (1 - double(s.p_lower[ix])));
      }
    }
    s.children = next;
    for (int q = 0; q < 4; ++q)
      if (n.child[q]) {
        s.children |= 1u << (28 + q);
        order[next++] = n.child[q];
      }
  }
}

// Each level multiplies the density by its quadrant's factor: 4 (a quadrant has a quarter of
// its parent's area) times the quadrant's share of the parent's energy. The halvings of p are
// exact in float (the quadrants' corners are dyadic).
float DirectionalQuadtree::pdf_square(Vec2 p) const {
  if (sampling_.empty()) return 0;
  float x = p.x, y = p.y, pdf = 1;
  uint32_t node = 0;
  for (;;) {
    const SamplingNode& n = sampling_[node];
    const int ix = x >= 0.5f, iy = y >= 0.5f, q = ix + 2 * iy;
    pdf *= n.factor[q];
    if (!n.inner(q)) return pdf;
    x = 2 * x - float(ix);
    y = 2 * y - float(iy);
    node = n.child(q);
  }
}

float DirectionalQuadtree::pdf(Vec3 w) const {
  return pdf_square(direction_to_square(w)) * kInv4Pi;
}

// Per level: the column (ix) with probability p_left, then the row (iy) within the column.
// Instead of rescaling u at every level (two divisions), u stays where it is and each level
// narrows the interval [lo, hi) of its coordinates that the chosen quadrant owns (the split at
// lo + p (hi - lo)); u's place in the final interval is its place in the leaf. lo <= u < hi
// holds throughout, so a column or row of probability 0 is never chosen (p = 1 is tested
// explicitly: lo + (hi - lo) may round below hi).
Vec2 DirectionalQuadtree::sample_square(Vec2 u, float* pdf) const {
  const double ux = u.x, uy = u.y;
  double x_lo = 0, x_hi = 1, y_lo = 0, y_hi = 1;
  double ox = 0, oy = 0, size = 1;
  float density = 1;  // as pdf_square() computes it
  uint32_t node = 0;
  for (;;) {
    const SamplingNode& n = sampling_[node];
    const double x_split = x_lo + double(n.p_left) * (x_hi - x_lo);
    const int ix = n.p_left < 1 && ux >= x_split;
    (ix ? x_lo : x_hi) = x_split;
    const float p_lower = n.p_lower[ix];
    const double y_split = y_lo + double(p_lower) * (y_hi - y_lo);
    const int iy = p_lower < 1 && uy >= y_split;
    (iy ? y_lo : y_hi) = y_split;
    const int q = ix + 2 * iy;
    size *= 0.5;
    ox += ix * size;
    oy += iy * size;
    density *= n.factor[q];
    if (!n.inner(q)) break;
    node = n.child(q);
  }
  // The leaf's corners are dyadic (exact in float): keep the rounded point inside the leaf, so
  // that pdf_square() finds the leaf it was sampled from.
  auto inside = [size](double origin, double u, double lo, double hi) {
    const double t = hi > lo ? (u - lo) / (hi - lo) : 0.5;
    // The float below `last` (> 0): its bits minus one, as std::nextafter without the call.
    const float first = float(origin),
                below = std::bit_cast<float>(std::bit_cast<uint32_t>(float(origin + size)) - 1);
    return std::clamp(float(origin + size * t), first, below);
  };
  if (pdf) *pdf = density;
  return {inside(ox, ux, x_lo, x_hi), inside(oy, uy, y_lo, y_hi)};
}

DirectionalQuadtree DirectionalQuadtree::refined(double rho, int max_depth, size_t* node_budget,
                                                 double carry) const {
  DirectionalQuadtree out;
  const double whole = total();
  if (!(whole > 0)) return out;
  struct Pending {
    uint32_t node;     // in `out`
    int64_t old_node;  // the same square in *this, or -1 where *this has a leaf above it
    int depth;
    double share;  // the square's share of the energy
  };
  std::vector<Pending> stack{{0, 0, 1, 1.0}};
  while (!stack.empty()) {
    const Pending at = stack.back();
    stack.pop_back();
    for (int q = 0; q < 4; ++q) {
      double share = at.share / 4;  // a leaf's energy, spread evenly over its quadrants
      int64_t old_child = -1;
      if (at.old_node >= 0) {
        const Node& old = nodes_[size_t(at.old_node)];
        share = old.energy[q] / whole;
        if (old.child[q]) old_child = old.child[q];
      }
      if (share > rho && at.depth<max_depth&& * node_budget> 0) {
        --*node_budget;
        const uint32_t child = uint32_t(out.nodes_.size());
        out.nodes_.emplace_back();
        out.nodes_[at.node].child[q] = child;
        stack.push_back({child, old_child, at.depth + 1, share});
      } else {
        out.nodes_[at.node].energy[q] = float(carry * share * whole);  // a leaf quadrant
      }
    }
  }
  return out;
}

int DirectionalQuadtree::depth() const {
  std::vector<int> level(nodes_.size(), 1);
  int deepest = 1;
  for (size_t i = 0; i < nodes_.size(); ++i) {
    deepest = std::max(deepest, level[i]);
    for (uint32_t c : nodes_[i].child)
      if (c) level[c] = level[i] + 1;
  }
  return deepest;
}

}  // namespace caustica
