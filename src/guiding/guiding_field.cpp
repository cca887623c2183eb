#include "guiding/guiding_field.h"

#include <cmath>

namespace caustica {

GuidingField::GuidingField(Bounds3 bounds, const GuidingSettings& settings) : settings_(settings) {
  if (bounds.empty()) bounds = Bounds3{{0, 0, 0}, {1, 1, 1}};
  SpatialNode root;
  root.box = bounds;
  nodes_.push_back(root);
  leaves_.emplace_back();
}

uint32_t GuidingField::leaf_at(Vec3 p) const {
  uint32_t node = 0;
  while (nodes_[node].child[0]) {
    const SpatialNode& n = nodes_[node];
    node = n.child[p[n.axis] >= n.middle];
  }
  return nodes_[node].leaf;
}

void GuidingField::record(const RadianceRecord& r) { record(leaf_at(r.p), r.wi, r.value); }

void GuidingField::record(uint32_t leaf, Vec3 wi, float value) {
  Leaf& l = leaves_[leaf];
  ++l.samples;
  if (value > 0 && std::isfinite(value)) l.recording.record(direction_to_square(wi), value);
}

// Müller et al. 2017, sec. 3.4: "we subdivide a leaf node if it contains more than
// c sqrt(2^k) path vertices"; the children inherit the directional distributions.
void GuidingField::split(uint32_t node) {
  const Bounds3 box = nodes_[node].box;
  const Vec3 d = box.diagonal();
  const int axis = d.x >= d.y && d.x >= d.z ? 0 : (d.y >= d.z ? 1 : 2);
  const float middle = 0.5f * (box.lo[axis] + box.hi[axis]);
  const uint32_t leaf = nodes_[node].leaf;
  leaves_[leaf].samples /= 2;
  const uint32_t copy = uint32_t(leaves_.size());
  leaves_.push_back(leaves_[leaf]);
  SpatialNode lower, upper;
  lower.box = upper.box = box;
  lower.box.hi[axis] = middle;
  upper.box.lo[axis] = middle;
  lower.leaf = leaf;
  upper.leaf = copy;
  const uint32_t first = uint32_t(nodes_.size());
  nodes_.push_back(lower);
  nodes_.push_back(upper);
  SpatialNode& n = nodes_[node];
  n.child[0] = first;
  n.child[1] = first + 1;
  n.axis = axis;
  n.middle = middle;
}

void GuidingField::end_iteration(int k) {
  for (Leaf& l : leaves_) {
    l.recording.propagate();
    l.sampling = std::move(l.recording);
    l.recording = DirectionalQuadtree();
  }
  auto used = [&] {
    size_t n = 0;
    for (const Leaf& l : leaves_) n += l.sampling.node_count() + l.recording.node_count();
    return n;
  };
  const double threshold = settings_.spatial_threshold * std::sqrt(std::ldexp(1.0, k));
  size_t nodes = used();
  // nodes_ grows inside the loop: new children are visited too, so a leaf splits repeatedly.
  for (uint32_t i = 0; i < nodes_.size(); ++i) {
    if (nodes_[i].child[0]) continue;
    const Leaf& l = leaves_[nodes_[i].leaf];
    const size_t cost = l.sampling.node_count() + l.recording.node_count();
    if (double(l.samples) <= threshold || nodes + cost > settings_.max_quadtree_nodes) continue;
    nodes += cost;
    split(i);
  }
  size_t budget = settings_.max_quadtree_nodes > nodes ? settings_.max_quadtree_nodes - nodes : 0;
  for (Leaf& l : leaves_) {
    l.recording = l.sampling.refined(settings_.rho, settings_.max_quadtree_depth, &budget);
    l.samples = 0;
  }
}

size_t GuidingField::quadtree_node_count() const {
  size_t n = 0;
  for (const Leaf& l : leaves_) n += l.sampling.node_count() + l.recording.node_count();
  return n;
}

size_t GuidingField::memory_bytes() const {
  return quadtree_node_count() * DirectionalQuadtree::kNodeBytes +
         nodes_.capacity() * sizeof(SpatialNode) + leaves_.capacity() * sizeof(Leaf);
}

uint64_t GuidingField::recorded_samples() const {
  uint64_t n = 0;
  for (const Leaf& l : leaves_) n += l.samples;
  return n;
}

}  // namespace caustica
