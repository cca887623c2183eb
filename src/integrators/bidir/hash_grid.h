// Range search over the stored light vertices: a hashed uniform grid with cells of size 2r,
// built by a counting sort in vertex order (deterministic, no per-cell allocation). A query
// visits the 2x2x2 cells that a ball of radius r around the point can touch (Georgiev's
// SmallVCM grid, Teschner et al. 2003 hash, here of blocks of 2x2x2 cells: see hash()). Two of
// those cells can hash to one bucket; each bucket is visited once, so no vertex is ever counted
// twice.
//
// Speed (profiled on cornell-glass, vcm 512x512): a query scans whole buckets of which only a
// few vertices lie within r, so the scan is the cost. The positions are therefore kept a second
// time, sorted by bucket, each beside its vertex index in 16 bytes: the scan reads contiguous
// memory instead of one 40-byte vertex per index, and the vertex is looked up only when it is
// within r. A query's three dependent cache misses (bucket table, entries, vertex record) are
// made to overlap across its buckets. The order in which fn sees the vertices is fixed (bucket
// order, then vertex order within a bucket), so the sums a query makes are too.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <vector>

#include "core/vec.h"
#include "integrators/bidir/light_vertex.h"

namespace caustica::bidir {

class HashGrid {
 public:
  // table_size: buckets (rounded up to a power of two); 0 = about a quarter of the vertex count.
  void build(const std::vector<LightVertex>& vertices, float radius, uint32_t table_size = 0);

  // fn(vertex_index, light_position) for every vertex within the radius of p. For records the
  // caller keeps beside the vertices, prefetch(index, 0) when a vertex is found and
  // prefetch(index, 1) when its batch is about to be handed to fn (a second, dependent load).
  template <typename Fn, typename Prefetch = void (*)(uint32_t, int)>
  void for_each_near(
      Vec3 p, const std::vector<LightVertex>& vertices, Fn&& fn,
      Prefetch&& prefetch = [](uint32_t, int) {}) const {
    if (cell_start_.empty()) return;
    uint32_t begin[8], end[8];
    const int count = buckets_near(p, begin, end);
    // The vertices within r, in bucket order then vertex order, handed to fn in batches: each
    // accepted vertex's record is prefetched when it is found (the caller reads it), so those
    // cache misses overlap instead of following each other, across buckets too.
    constexpr uint32_t kBatch = 32;
    uint32_t found[kBatch];
    uint32_t n = 0;
    auto flush = [&] {
      for (uint32_t j = 0; j < n; ++j) prefetch(entries_[found[j]].index, 1);
      for (uint32_t j = 0; j < n; ++j) {
        const Entry& e = entries_[found[j]];
        fn(e.index, Vec3(e.p[0], e.p[1], e.p[2]));
      }
      n = 0;
    };
    for (int k = 0; k < count; ++k) {
      for (uint32_t i = begin[k]; i < end[k]; ++i) {
        const Entry& e = entries_[i];
        if (distance_squared(p, Vec3(e.p[0], e.p[1], e.p[2])) > radius2_) continue;
        __builtin_prefetch(&vertices[e.index]);
        prefetch(e.index, 0);
        found[n++] = i;
        if (n == kBatch) flush();
      }
    }
    flush();
  }

  size_t memory_bytes() const {
    return (cell_start_.capacity() + cells_.capacity()) * sizeof(uint32_t) +
           entries_.capacity() * sizeof(Entry);
  }

 private:
  // Cell coordinate along axis a relative to the vertices' bounds, in double so that a point far
  // from the bounds' corner (a huge scene, a tiny radius) still lands in the right cell, and
  // clamped so that it never overflows the integer conversion (clamped cells only collide).
  double grid_coordinate(Vec3 p, int a) const {
    constexpr double kLimit = double(1 << 30);
    return std::clamp((double(p[a]) - double(lo_[a])) * inv_cell_, -kLimit, kLimit);
  }
  // The distinct buckets of the 2x2x2 cells a ball of radius r around p can touch, as entry
  // ranges [begin, end): their count. The table lookups are independent loads (their cache
  // misses overlap), and each bucket's first entries are prefetched before any is scanned.
  int buckets_near(Vec3 p, uint32_t* begin, uint32_t* end) const {
    int c[3], n[3];
    for (int a = 0; a < 3; ++a) {
      const double g = grid_coordinate(p, a);
      c[a] = int(std::floor(g));
      n[a] = g - c[a] < 0.5 ? -1 : 1;  // the neighbour on the side p is closer to
    }
    uint32_t buckets[8];
    int count = 0;
    for (int k = 0; k < 8; ++k) {
      const uint32_t b = hash(c[0] + ((k & 1) ? n[0] : 0), c[1] + ((k & 2) ? n[1] : 0),
                              c[2] + ((k & 4) ? n[2] : 0));
      if (std::find(buckets, buckets + count, b) == buckets + count) buckets[count++] = b;
    }
    for (int k = 0; k < count; ++k) {
      begin[k] = cell_start_[buckets[k]];
      end[k] = cell_start_[buckets[k] + 1];
      __builtin_prefetch(entries_.data() + begin[k]);
    }
    return count;
  }
  uint32_t cell_of(Vec3 p) const {
    return hash(int(std::floor(grid_coordinate(p, 0))), int(std::floor(grid_coordinate(p, 1))),
                int(std::floor(grid_coordinate(p, 2))));
  }
  // Cells are hashed in blocks of 2x2x2 (Teschner et al.'s hash of the block), the eight cells of
  // a block in consecutive buckets: a query's 2x2x2 cells lie in 3.4 blocks on average instead
  // of 8 scattered buckets, so fewer of its table lookups and entry scans miss the cache, and
  // neighbouring queries share them.
  uint32_t hash(int x, int y, int z) const {
    const uint32_t block = (uint32_t(x >> 1) * 73856093u) ^ (uint32_t(y >> 1) * 19349663u) ^
                           (uint32_t(z >> 1) * 83492791u);
    const uint32_t cell = uint32_t(x & 1) | uint32_t(y & 1) << 1 | uint32_t(z & 1) << 2;
    return (block * 8u + cell) & (table_size_ - 1);
  }

  Vec3 lo_;
  double inv_cell_ = 1;
  float radius2_ = 0;
  uint32_t table_size_ = 0;
  struct Entry {
    float p[3];      // the vertex's position, exactly
    uint32_t index;  // into the vertices the grid was built over
  };
  std::vector<uint32_t> cell_start_;  // table_size_ + 1 offsets into entries_
  std::vector<Entry> entries_;        // sorted by bucket, in vertex order within one
  // Build scratch, kept so that a build allocates nothing once the sizes have been reached.
  std::vector<uint32_t> cells_;  // per vertex: its bucket
};

}  // namespace caustica::bidir
