// Range search over the stored light vertices: a hashed uniform grid with cells of size 2r,
// built by a counting sort in vertex order (deterministic, no per-cell allocation). A query
// visits the 2x2x2 cells that a ball of radius r around the point can touch (Georgiev's
// SmallVCM grid, Teschner et al. 2003 hash).
#pragma once

#include <cmath>
#include <cstdint>
#include <vector>

#include "core/vec.h"
#include "integrators/bidir/light_vertex.h"

namespace caustica::bidir {

class HashGrid {
 public:
  void build(const std::vector<LightVertex>& vertices, const PositionCodec& codec, float radius);

  // fn(vertex_index, light_position) for every vertex within the radius of p.
  template <typename Fn>
  void for_each_near(Vec3 p, const std::vector<LightVertex>& vertices, const PositionCodec& codec,
                     Fn&& fn) const {
    if (cell_start_.empty()) return;
    const Vec3 g = (p - lo_) * inv_cell_;
    const int cx = int(std::floor(g.x)), cy = int(std::floor(g.y)), cz = int(std::floor(g.z));
    // The neighbour on the side of the cell that p is closer to, per axis.
    const int nx = g.x - cx < 0.5f ? -1 : 1, ny = g.y - cy < 0.5f ? -1 : 1,
              nz = g.z - cz < 0.5f ? -1 : 1;
    for (int k = 0; k < 8; ++k) {
      const uint32_t cell =
          hash(cx + ((k & 1) ? nx : 0), cy + ((k & 2) ? ny : 0), cz + ((k & 4) ? nz : 0));
      for (uint32_t i = cell_start_[cell]; i < cell_start_[cell + 1]; ++i) {
        const uint32_t index = indices_[i];
        const Vec3 q = codec.decode(vertices[index].position);
        if (distance_squared(p, q) <= radius2_) fn(index, q);
      }
    }
  }

  size_t memory_bytes() const {
    return (cell_start_.capacity() + indices_.capacity()) * sizeof(uint32_t);
  }

 private:
  uint32_t hash(int x, int y, int z) const {
    return ((uint32_t(x) * 73856093u) ^ (uint32_t(y) * 19349663u) ^ (uint32_t(z) * 83492791u)) &
           (table_size_ - 1);
  }

  Vec3 lo_;
  float inv_cell_ = 1, radius2_ = 0;
  uint32_t table_size_ = 0;
  std::vector<uint32_t> cell_start_;  // table_size_ + 1 offsets into indices_
  std::vector<uint32_t> indices_;     // vertex indices sorted by cell
};

}  // namespace caustica::bidir
