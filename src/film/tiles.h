// Parallel loop over the image in fixed 16x16 tiles. The tiling does not depend on the thread
// count, and each pixel belongs to exactly one tile, so per-pixel work is deterministic.
#pragma once

#include <tbb/parallel_for.h>

#include "core/arena.h"

namespace caustica {

struct Tile {
  int x0, y0, x1, y1;
};

// fn(const Tile&, ScratchArena&) is called once per tile, from any thread.
template <typename Fn>
void parallel_for_tiles(int width, int height, Fn&& fn) {
  constexpr int kTile = 16;
  const int tiles_x = (width + kTile - 1) / kTile, tiles_y = (height + kTile - 1) / kTile;
  tbb::parallel_for(0, tiles_x * tiles_y, [&](int t) {
    thread_local ScratchArena arena;
    const int tx = t % tiles_x, ty = t / tiles_x;
    const Tile tile{tx * kTile, ty * kTile, std::min(width, (tx + 1) * kTile),
                    std::min(height, (ty + 1) * kTile)};
    arena.reset();
    fn(tile, arena);
  });
}

}  // namespace caustica
