#include "guiding/guiding_field.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <array>
#include <bit>
#include <cmath>
#include <cstddef>
#include <cstring>
#include <memory>
#include <utility>

namespace caustica {

namespace {

// SplitMix64's finalizer: a well-mixed 64-bit hash of a record's key.
uint64_t mix_bits(uint64_t x) {
  x ^= x >> 30;
  x *= 0xbf58476d1ce4e5b9ull;
  x ^= x >> 27;
  x *= 0x94d049bb133111ebull;
  return x ^ (x >> 31);
}

}  // namespace

GuidingField::GuidingField(Bounds3 bounds, const GuidingSettings& settings, bool sided)
    : settings_(settings),
      bounds_(bounds.empty() ? Bounds3{{0, 0, 0}, {1, 1, 1}} : bounds),
      sided_(sided) {
  nodes_.emplace_back();  // a leaf: leaves_[0]
  leaves_.emplace_back();
  leaves_[0].box = bounds_;
  counts_.assign(1, 0);
  if (sided_) {
    // Eight copies side by side along x (a flat box gets a width, so that they stay apart), then
    // three rounds of splits along x: the midpoints are the copies' borders, one leaf each.
    const Vec3 d = bounds_.diagonal();
    copy_width_ = std::max(d.x, 1e-3f * std::max({d.x, d.y, d.z, 1e-3f}));
    leaves_[0].box.hi.x = bounds_.lo.x + 8 * copy_width_;
    for (int round = 0; round < 3; ++round) {
      const size_t n = nodes_.size();
      for (uint32_t i = 0; i < n; ++i)
        if (nodes_[i].axis() == SpatialNode::kLeaf) split(i, counts_, 0);
    }
    std::fill(counts_.begin(), counts_.end(), 0);
  }
  // Dyadic cells over the root box, about cubic: double the grid along the axis of the longest
  // cell extent (as split() halves a box's longest axis) while the cell budget allows.
  const Vec3 d = sided_ ? Vec3(8 * copy_width_, bounds_.diagonal().y, bounds_.diagonal().z)
                        : bounds_.diagonal();
  start_origin_ = bounds_.lo;
  const size_t cells = std::min(kStartCells, settings_.max_bytes / 8 / sizeof(uint32_t));
  while (size_t(start_dims_[0]) * start_dims_[1] * start_dims_[2] * 2 <= cells) {
    int a = 0;
    for (int k = 1; k < 3; ++k)
      if (d[k] / float(start_dims_[k]) > d[a] / float(start_dims_[a])) a = k;
    if (!(d[a] > 0)) break;  // a box of one point
    start_dims_[a] *= 2;
  }
  for (int k = 0; k < 3; ++k) start_scale_[k] = d[k] > 0 ? float(start_dims_[k]) / d[k] : 0.f;
  build_start_grid();
  refresh_guides();
}

void GuidingField::build_start_grid() {
  start_.resize(size_t(start_dims_[0]) * start_dims_[1] * start_dims_[2]);
  int cell[3];
  auto bound = [&](int axis, int i) {  // the lower plane of cell i along axis (inf outside)
    if (i <= 0) return -kInfinity;
    if (i >= start_dims_[axis]) return kInfinity;
    return start_origin_[axis] + float(i) / start_scale_[axis];
  };
  size_t at = 0;
  for (cell[2] = 0; cell[2] < start_dims_[2]; ++cell[2])
    for (cell[1] = 0; cell[1] < start_dims_[1]; ++cell[1])
      for (cell[0] = 0; cell[0] < start_dims_[0]; ++cell[0]) {
        uint32_t node = 0;
        while (nodes_[node].axis() != SpatialNode::kLeaf) {
          const int a = int(nodes_[node].axis());
          // Planes within a ten-thousandth of a cell of its border (the cells' and the planes'
          // float rounding) count as on it; start_node() sends points that close to a border to
          // the root instead.
          const float tolerance = kStartTolerance / 10 / start_scale_[a];
          const float m = nodes_[node].middle;
          if (m <= bound(a, cell[a]) + tolerance) {
            node = nodes_[node].index() + 1;  // the whole cell is above the plane
          } else if (m >= bound(a, cell[a] + 1) - tolerance) {
            node = nodes_[node].index();
          } else {
            break;  // the plane crosses the cell: points decide from here
          }
        }
        start_[at++] = node;
      }
}

uint32_t GuidingField::start_node(Vec3 p) const {
  size_t index = 0;
  for (int a = 2; a >= 0; --a) {
    const float t = (p[a] - start_origin_[a]) * start_scale_[a];
    const int last = start_dims_[a] - 1;
    if (!(t < float(last))) {  // the last cell, which reaches to infinity (NaN: the root)
      if (!(t >= float(last) + kStartTolerance)) return 0;
      index = index * size_t(start_dims_[a]) + size_t(last);
      continue;
    }
    const int i = t > 0 ? int(t) : 0;  // the first cell reaches to minus infinity
    const float f = t - float(i);
    // Within a thousandth of a cell of an inner border: the cell's decisions may not hold.
    if (f > 1 - kStartTolerance || (i > 0 && f < kStartTolerance)) return 0;
    index = index * size_t(start_dims_[a]) + size_t(i);
  }
  return start_[index];
}

int GuidingField::side_class(Vec3 n) {
  const float ax = std::abs(n.x), ay = std::abs(n.y), az = std::abs(n.z);
  const int axis = ax >= ay && ax >= az ? 0 : (ay >= az ? 1 : 2);
  return 2 * axis + (n[axis] < 0 ? 1 : 0);
}

Vec3 GuidingField::class_point(Vec3 p, int side) const {
  if (!sided_) return p;
  // Kept a sliver inside the copy, so that float rounding of the split planes at the copies'
  // borders never moves a point into the neighbouring class.
  const float t = std::clamp((p.x - bounds_.lo.x) / copy_width_, 5e-4f, 1 - 5e-4f);
  return {bounds_.lo.x + (float(side) + t) * copy_width_, p.y, p.z};
}

void GuidingField::add_vertex_counts(const std::vector<uint32_t>& counts) {
  for (size_t i = 0; i < counts.size() && i < counts_.size(); ++i) counts_[i] += counts[i];
}

void GuidingField::add_technique_counts(Technique t, const std::vector<uint32_t>& counts) {
  std::vector<uint64_t>& mine = technique_counts_[t];
  if (mine.size() != 2 * leaves_.size()) mine.assign(2 * leaves_.size(), 0);
  for (size_t i = 0; i < counts.size() && i < mine.size(); ++i) mine[i] += counts[i];
}

size_t GuidingField::reduced_leaves(Technique t) const {
  size_t n = 0;
  for (const Leaf& l : leaves_) n += l.probability[t] < 1;
  return n;
}

uint32_t GuidingField::leaf_at(Vec3 p, int side) const {
  const Vec3 q = class_point(p, side);
  return leaf_of_point(q, start_node(q));
}

uint32_t GuidingField::leaf_of_point(Vec3 p, uint32_t start) const {
  const float coordinate[4] = {p.x, p.y, p.z, 0};  // indexed without branches
  // Both children are loaded while the side is decided (they are adjacent, one cache line), and
  // the choice is a select, not a branch: a level costs one load's latency, not a load followed
  // by the comparison that decides the next load's address.
  // A node read as one 64-bit word (little endian): `middle` in the low half, `packed` above.
  static_assert(sizeof(SpatialNode) == sizeof(uint64_t) && offsetof(SpatialNode, middle) == 0 &&
                offsetof(SpatialNode, packed) == 4);
  uint64_t n;
  std::memcpy(&n, &nodes_[start], sizeof(n));
  auto axis = [](uint64_t bits) { return uint32_t(bits >> 62); };
  while (axis(n) != SpatialNode::kLeaf) {
    float middle;
    const uint32_t packed = uint32_t(n >> 32);
    std::memcpy(&middle, &n, sizeof(middle));
    uint64_t lower, upper;
    const SpatialNode* children = &nodes_[packed & SpatialNode::kIndexMask];
    std::memcpy(&lower, children, sizeof(lower));
    std::memcpy(&upper, children + 1, sizeof(upper));
    const uint64_t take_upper = uint64_t(0) - uint64_t(coordinate[axis(n)] >= middle);
    n = (lower & ~take_upper) | (upper & take_upper);
  }
  return uint32_t(n >> 32) & SpatialNode::kIndexMask;
}

void GuidingField::refresh_guides() {
  if (guides_.size() != leaves_.size()) {
    guides_.resize(leaves_.size());
    guides_.shrink_to_fit();
  }
  for (uint32_t i = 0; i < leaves_.size(); ++i) {
    const Leaf& l = leaves_[i];
    guides_[i] = {l.sampling.total() > 0 ? &l.sampling : nullptr,
                  bsdf_fraction(i),
                  {l.probability[0], l.probability[1], l.probability[2]}};
  }
}

uint32_t GuidingField::jittered_leaf(Vec3 p, uint32_t leaf, Vec3 u, int side) const {
  const Vec3 size = leaves_[leaf].box.diagonal();
  return leaf_at(p + (u - Vec3(0.5f, 0.5f, 0.5f)) * size, side);
}

float GuidingField::bsdf_fraction(uint32_t leaf) const {
  return settings_.bsdf_fraction >= 0 ? settings_.bsdf_fraction
                                      : leaves_[leaf].selection.bsdf_fraction();
}

void GuidingField::record(const GuidingRecord& r) {
  if (r.statistical_weight > 0) ++counts_[r.leaf];
  record_into(leaves_[r.leaf], r);
  guides_[r.leaf].bsdf_fraction = bsdf_fraction(r.leaf);
}

void GuidingField::record_into(Leaf& leaf, const GuidingRecord& r) {
  if (r.radiance > 0 && std::isfinite(r.radiance)) {
    if (settings_.filter) {
      // The directional box filter, stochastically, with a jitter hashed from the record's key.
      const uint64_t h = mix_bits(r.key);
      const Vec2 u(float(h >> 40) * 0x1p-24f, float((h >> 16) & 0xffffff) * 0x1p-24f);
      leaf.recording.record_jittered(r.square, r.radiance, u);
    } else {
      leaf.recording.record(r.square, r.radiance);
    }
  }
  if (settings_.bsdf_fraction < 0 && r.guide_pdf > 0 && r.product > 0)
    leaf.selection.add(r.product, r.bsdf_pdf, r.guide_pdf, r.statistical_weight);
}

GuidingRecord* GuidingField::RecordScratch::reserve(size_t n) {
  if (n > capacity_) {
    data_.reset(static_cast<GuidingRecord*>(::operator new(n * sizeof(GuidingRecord))));
    capacity_ = n;
  }
  return data_.get();
}

void GuidingField::splat(std::span<const std::span<const GuidingRecord>> runs) {
  // kChunks chunks of about equal record counts, fixed by the runs alone (not by threads).
  std::vector<size_t> first(runs.size() + 1, 0);
  for (size_t i = 0; i < runs.size(); ++i) first[i + 1] = first[i] + runs[i].size();
  const size_t n = first.back(), leaves = leaves_.size();
  constexpr size_t kChunks = 16;
  auto for_chunk = [&](size_t c, auto&& fn) {
    const size_t begin = n * c / kChunks, end = n * (c + 1) / kChunks;
    if (begin == end) return;
    // The run holding record `begin`: the last whose first record is at or before it.
    size_t run = size_t(std::upper_bound(first.begin(), first.end(), begin) - first.begin()) - 1;
    for (size_t i = begin; i < end; ++run) {
      const size_t stop = std::min(end, first[run + 1]);
      for (const GuidingRecord& r : runs[run].subspan(i - first[run], stop - i)) fn(r);
      i = stop;
    }
  };
  // A stable counting sort by leaf: per chunk and leaf a count, then leaf-major offsets (leaf
  // l's records of chunk c after those of the chunks before c), then the scatter.
  std::vector<size_t> offsets(kChunks * leaves, 0);
  std::array<uint64_t, kChunks> largest_key{};
  tbb::parallel_for(size_t(0), kChunks, [&](size_t c) {
    size_t* count = &offsets[c * leaves];
    uint64_t largest = 0;
    for_chunk(c, [&](const GuidingRecord& r) {
      ++count[r.leaf];
      largest = std::max(largest, r.key);
    });
    largest_key[c] = largest;
  });
  std::vector<uint32_t> used;  // leaves with records
  std::vector<size_t> leaf_start(leaves + 1, 0);
  size_t sum = 0;
  for (size_t l = 0; l < leaves; ++l) {
    leaf_start[l] = sum;
    for (size_t c = 0; c < kChunks; ++c) sum += std::exchange(offsets[c * leaves + l], sum);
    if (sum > leaf_start[l]) used.push_back(uint32_t(l));
  }
  leaf_start[leaves] = sum;
  // The directional filter's jitter hashes the key with the leaf (when both fit in 64 bits).
  const int key_bits = std::bit_width(*std::max_element(largest_key.begin(), largest_key.end()));
  const bool tag_leaf = key_bits + std::bit_width(uint64_t(leaves)) <= 64;
  GuidingRecord* grouped = grouped_.reserve(n);
  tbb::parallel_for(size_t(0), kChunks, [&](size_t c) {
    size_t* at = &offsets[c * leaves];
    for_chunk(c, [&](const GuidingRecord& r) {
      GuidingRecord* g = std::construct_at(grouped + at[r.leaf]++, r);
      if (tag_leaf) g->key |= uint64_t(r.leaf) << key_bits;
    });
  });
  tbb::parallel_for(size_t(0), used.size(), [&](size_t u) {
    const uint32_t l = used[u];
    for (size_t i = leaf_start[l]; i < leaf_start[l + 1]; ++i) record_into(leaves_[l], grouped[i]);
  });
  refresh_guides();
}

// Müller et al. 2017, sec. 3.4: "we subdivide a leaf node if it contains more than
// c sqrt(2^k) path vertices"; the children inherit the directional distributions.
void GuidingField::split(uint32_t node, std::vector<uint64_t>& counts, int split_axis) {
  const uint32_t leaf = nodes_[node].index();
  const Bounds3 box = leaves_[leaf].box;
  const Vec3 d = box.diagonal();
  const uint32_t axis = split_axis >= 0 ? uint32_t(split_axis)
                                        : (d.x >= d.y && d.x >= d.z ? 0 : (d.y >= d.z ? 1 : 2));
  const float middle = 0.5f * (box.lo[int(axis)] + box.hi[int(axis)]);
  counts[leaf] /= 2;
  leaves_[leaf].carry_share *= 0.5;
  const uint32_t copy = uint32_t(leaves_.size());
  leaves_.push_back(leaves_[leaf]);
  counts.push_back(counts[leaf]);
  leaves_[leaf].box.hi[int(axis)] = middle;
  leaves_[copy].box.lo[int(axis)] = middle;
  SpatialNode lower, upper;
  lower.packed = (SpatialNode::kLeaf << 30) | leaf;
  upper.packed = (SpatialNode::kLeaf << 30) | copy;
  const uint32_t first = uint32_t(nodes_.size());
  nodes_.push_back(lower);
  nodes_.push_back(upper);
  nodes_[node].packed = (axis << 30) | first;
  nodes_[node].middle = middle;
}

size_t GuidingField::leaf_bytes(const Leaf& l) const {
  return sizeof(Leaf) + 2 * sizeof(SpatialNode) + sizeof(uint64_t) + sizeof(Guide) +
         l.sampling.bytes() + l.recording.bytes();
}

void GuidingField::split_leaves(int k) {
  const double threshold = settings_.spatial_threshold * std::sqrt(std::ldexp(1.0, k));
  size_t bytes = memory_bytes();
  std::vector<uint64_t>& counts = counts_;
  // nodes_ grows inside the loop: new children are visited too, so a leaf splits repeatedly.
  for (uint32_t i = 0; i < nodes_.size(); ++i) {
    if (nodes_[i].axis() != SpatialNode::kLeaf) continue;
    const uint32_t leaf = nodes_[i].index();
    const size_t cost = leaf_bytes(leaves_[leaf]);
    if (double(counts[leaf]) <= threshold || bytes + cost > settings_.max_bytes) continue;
    bytes += cost;
    split(i, counts);
  }
  nodes_.shrink_to_fit();
  leaves_.shrink_to_fit();
}

void GuidingField::end_pass(int k) {
  const float floor = std::clamp(settings_.nee_floor, 0.f, 1.f);
  for (int t = 0; t < kTechniques; ++t) {
    std::vector<uint64_t>& counts = technique_counts_[t];
    if (counts.size() != 2 * leaves_.size()) continue;
    const double share =
        t == kConnection ? std::max(settings_.nee_visible_share, settings_.connection_visible_share)
                         : settings_.nee_visible_share;
    // The share of the technique's attempts (samples taken over the probability they were
    // taken with) that fall in leaves reduced from now on.
    double attempts = 0, reduced = 0;
    for (size_t i = 0; i < leaves_.size(); ++i) {
      const uint64_t taken = counts[2 * i], visible = counts[2 * i + 1];
      const double tried = double(taken) / double(leaves_[i].probability[t]);
      const bool dark = double(visible) <= share * double(taken);
      if (!dark) {
        leaves_[i].probability[t] = 1;
      } else if (taken >= kNeeEvidence && floor > 0) {
        leaves_[i].probability[t] = floor;
      }
      attempts += tried;
      if (leaves_[i].probability[t] < 1) reduced += tried;
    }
    reduced_attempt_share_[t] = attempts > 0 ? reduced / attempts : 0;
    counts.clear();
  }
  for (Leaf& l : leaves_) {
    l.recording.propagate();
    l.sampling = std::move(l.recording);
    l.sampling.shrink_to_fit();
    l.recording = DirectionalQuadtree();
  }
  split_leaves(k);
  build_start_grid();
  refresh_guides();  // leaves_ moved: the pointers change
  const size_t bytes = memory_bytes();
  size_t budget = settings_.max_bytes > bytes
                      ? (settings_.max_bytes - bytes) / DirectionalQuadtree::kNodeBytes
                      : 0;
  for (Leaf& l : leaves_) {
    l.recording = l.sampling.refined(settings_.rho, settings_.max_quadtree_depth, &budget,
                                     settings_.carry * l.carry_share);
    l.carry_share = 1;
    l.recording.shrink_to_fit();
  }
  counts_.assign(leaves_.size(), 0);
  counts_.shrink_to_fit();
}

size_t GuidingField::quadtree_node_count() const {
  size_t n = 0;
  for (const Leaf& l : leaves_) n += l.sampling.node_count() + l.recording.node_count();
  return n;
}

size_t GuidingField::memory_bytes() const {
  size_t bytes = nodes_.capacity() * sizeof(SpatialNode) + leaves_.capacity() * sizeof(Leaf) +
                 (counts_.capacity() + technique_counts_[0].capacity() +
                  technique_counts_[1].capacity() + technique_counts_[2].capacity()) *
                     sizeof(uint64_t) +
                 guides_.capacity() * sizeof(Guide) + start_.capacity() * sizeof(uint32_t);
  for (const Leaf& l : leaves_) bytes += l.sampling.bytes() + l.recording.bytes();
  return bytes;
}

uint64_t GuidingField::counted_vertices() const {
  uint64_t n = 0;
  for (uint64_t c : counts_) n += c;
  return n;
}

double GuidingField::mean_bsdf_fraction() const {
  double sum = 0;
  for (uint32_t i = 0; i < leaves_.size(); ++i) sum += bsdf_fraction(i);
  return sum / double(leaves_.size());
}

}  // namespace caustica
