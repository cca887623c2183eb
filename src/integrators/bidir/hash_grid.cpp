#include "integrators/bidir/hash_grid.h"

#include <bit>

namespace caustica::bidir {

void HashGrid::build(const std::vector<LightVertex>& vertices, float radius, uint32_t table_size) {
  radius2_ = radius * radius;
  inv_cell_ = 1.0 / (2.0 * double(radius));
  // Table about the vertex count, a power of two for cheap masking.
  table_size_ = std::bit_ceil(table_size > 0 ? table_size
                                             : uint32_t(std::max<size_t>(vertices.size(), 1024)));
  cell_start_.assign(table_size_ + 1, 0);
  indices_.resize(vertices.size());
  if (vertices.empty()) return;

  Bounds3 box;
  for (const LightVertex& v : vertices) box.extend(v.p());
  lo_ = box.lo;

  std::vector<uint32_t>& count = cell_start_;  // counts in [1, size], then prefix sums
  for (const LightVertex& v : vertices) ++count[cell_of(v.p()) + 1];
  for (uint32_t c = 0; c < table_size_; ++c) count[c + 1] += count[c];
  std::vector<uint32_t> fill(cell_start_.begin(), cell_start_.end() - 1);
  for (uint32_t i = 0; i < vertices.size(); ++i) indices_[fill[cell_of(vertices[i].p())]++] = i;
}

}  // namespace caustica::bidir
