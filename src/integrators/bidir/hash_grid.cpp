#include "integrators/bidir/hash_grid.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_reduce.h>

#include <bit>

namespace caustica::bidir {

void HashGrid::build(const std::vector<LightVertex>& vertices, float radius, uint32_t table_size) {
  radius2_ = radius * radius;
  inv_cell_ = 1.0 / (2.0 * double(radius));
  // Table about the vertex count, a power of two for cheap masking.
  table_size_ = std::bit_ceil(table_size > 0 ? table_size
                                             : uint32_t(std::max<size_t>(vertices.size(), 1024)));
  cell_start_.assign(table_size_ + 1, 0);
  entries_.resize(vertices.size());
  if (vertices.empty()) return;

  // The bounds and each vertex's bucket in parallel (min / max and a per-vertex value: the
  // same for any thread count); the counting sort after it stays serial, in vertex order.
  constexpr size_t kGrain = 16384;
  const tbb::blocked_range<size_t> all(0, vertices.size(), kGrain);
  const Bounds3 box = tbb::parallel_reduce(
      all, Bounds3(),
      [&](const tbb::blocked_range<size_t>& r, Bounds3 b) {
        for (size_t i = r.begin(); i < r.end(); ++i) b.extend(vertices[i].p());
        return b;
      },
      [](Bounds3 a, const Bounds3& b) {
        a.extend(b);
        return a;
      });
  lo_ = box.lo;
  cells_.resize(vertices.size());
  tbb::parallel_for(all, [&](const tbb::blocked_range<size_t>& r) {
    for (size_t i = r.begin(); i < r.end(); ++i) cells_[i] = cell_of(vertices[i].p());
  });

  std::vector<uint32_t>& count = cell_start_;  // counts in [1, size], then prefix sums
  for (const uint32_t cell : cells_) ++count[cell + 1];
  for (uint32_t c = 0; c < table_size_; ++c) count[c + 1] += count[c];
  fill_.assign(cell_start_.begin(), cell_start_.end() - 1);
  for (uint32_t i = 0; i < vertices.size(); ++i) {
    const LightVertex& v = vertices[i];
    entries_[fill_[cells_[i]]++] = {{v.position[0], v.position[1], v.position[2]}, i};
  }
}

}  // namespace caustica::bidir
