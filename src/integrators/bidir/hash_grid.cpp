#include "integrators/bidir/hash_grid.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_reduce.h>

#include <bit>

namespace caustica::bidir {

namespace {

// Resizes a buffer that is kept from one build to the next to n elements. When it must grow,
// the old storage is released first (its contents are rewritten anyway) and a sixteenth is
// added for the next builds, instead of std::vector's doubling: the next iteration's vertex
// count is close to this one's.
template <typename T>
void resize_for_rebuild(std::vector<T>& buffer, size_t n) {
  if (n > buffer.capacity()) {
    std::vector<T>().swap(buffer);
    buffer.reserve(n + n / 16);
  }
  buffer.resize(n);
}

}  // namespace

void HashGrid::build(const std::vector<LightVertex>& vertices, float radius, uint32_t table_size) {
  radius2_ = radius * radius;
  inv_cell_ = 1.0 / (2.0 * double(radius));
  // A table of about a quarter of the vertex count, a power of two for cheap masking: smaller
  // than one bucket per vertex, it stays in cache more often, and the vertices' cells, on
  // surfaces, are fewer than the vertices (cornell-glass vcm 512x512, 1 thread: 3% faster per
  // iteration than a table of the vertex count; docs/performance.md).
  table_size_ = std::bit_ceil(
      table_size > 0 ? table_size : uint32_t(std::max<size_t>(vertices.size() / 4, 1024)));
  cell_start_.assign(table_size_ + 1, 0);
  resize_for_rebuild(entries_, vertices.size());
  if (vertices.empty()) return;

  // The lower bound and each vertex's bucket in parallel (a minimum and a per-vertex value: the
  // same for any thread count); the counting sort after it stays serial, in vertex order.
  constexpr size_t kGrain = 16384;
  const tbb::blocked_range<size_t> all(0, vertices.size(), kGrain);
  // Only the lower corner is needed. Plain comparisons, not Bounds3's std::fmin (a libm call
  // per coordinate that was a third of the build; positions are finite, so the result is the
  // same).
  auto lower = [](Vec3 a, Vec3 b) {
    return Vec3(b.x < a.x ? b.x : a.x, b.y < a.y ? b.y : a.y, b.z < a.z ? b.z : a.z);
  };
  lo_ = tbb::parallel_reduce(
      all, Vec3(kInfinity, kInfinity, kInfinity),
      [&](const tbb::blocked_range<size_t>& r, Vec3 lo) {
        for (size_t i = r.begin(); i < r.end(); ++i) lo = lower(lo, vertices[i].p());
        return lo;
      },
      lower);
  resize_for_rebuild(cells_, vertices.size());
  tbb::parallel_for(all, [&](const tbb::blocked_range<size_t>& r) {
    for (size_t i = r.begin(); i < r.end(); ++i) cells_[i] = cell_of(vertices[i].p());
  });

  // Counting sort. cell_start_[c] counts bucket c, then (inclusive prefix sums) holds its end;
  // filling each bucket from its end, vertices in reverse order, leaves it at the bucket's start
  // with the bucket in vertex order, and needs no second array of cursors.
  std::vector<uint32_t>& cursor = cell_start_;
  for (const uint32_t cell : cells_) ++cursor[cell];
  for (uint32_t c = 1; c < table_size_; ++c) cursor[c] += cursor[c - 1];
  cursor[table_size_] = uint32_t(vertices.size());
  for (uint32_t i = uint32_t(vertices.size()); i-- > 0;) {
    const LightVertex& v = vertices[i];
    entries_[--cursor[cells_[i]]] = {{v.position[0], v.position[1], v.position[2]}, i};
  }
}

}  // namespace caustica::bidir
