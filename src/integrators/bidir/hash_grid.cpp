#include "integrators/bidir/hash_grid.h"

#include <bit>

namespace caustica::bidir {

void HashGrid::build(const std::vector<LightVertex>& vertices, const PositionCodec& codec,
                     float radius) {
  radius2_ = radius * radius;
  const float cell = 2 * radius;
  inv_cell_ = 1.f / cell;
  // Table about the vertex count, a power of two for cheap masking.
  table_size_ = std::bit_ceil(uint32_t(std::max<size_t>(vertices.size(), 1024)));
  cell_start_.assign(table_size_ + 1, 0);
  indices_.resize(vertices.size());
  if (vertices.empty()) return;

  Bounds3 box;
  for (const LightVertex& v : vertices) box.extend(codec.decode(v.position));
  lo_ = box.lo;

  std::vector<uint32_t>& count = cell_start_;  // counts in [1, size], then prefix sums
  auto cell_of = [&](const LightVertex& v) {
    const Vec3 g = (codec.decode(v.position) - lo_) * inv_cell_;
    return hash(int(std::floor(g.x)), int(std::floor(g.y)), int(std::floor(g.z)));
  };
  for (const LightVertex& v : vertices) ++count[cell_of(v) + 1];
  for (uint32_t c = 0; c < table_size_; ++c) count[c + 1] += count[c];
  std::vector<uint32_t> fill(cell_start_.begin(), cell_start_.end() - 1);
  for (uint32_t i = 0; i < vertices.size(); ++i) indices_[fill[cell_of(vertices[i])]++] = i;
}

}  // namespace caustica::bidir
