#include "integrators/camera_path.h"

#include <atomic>

#include "film/film.h"
#include "film/tiles.h"
#include "scene/scene.h"

namespace caustica {

void CameraPathIntegrator::prepare(const Scene& scene, Film&) {
  filter_ = PixelFilter(scene.camera().pixel_filter());
}

void CameraPathIntegrator::trace_camera_paths(const Scene& scene, uint32_t iteration,
                                              Film& film) const {
  const Camera& camera = scene.camera();
  std::atomic<uint64_t> nonfinite{0};
  parallel_for_tiles(film.width(), film.height(), [&](const Tile& tile, ScratchArena& arena) {
    uint64_t dropped = 0;
    for (int y = tile.y0; y < tile.y1; ++y)
      for (int x = tile.x0; x < tile.x1; ++x) {
        CameraSample s;
        s.x = x;
        s.y = y;
        s.pixel = uint64_t(y) * uint64_t(film.width()) + uint64_t(x);
        s.iteration = iteration;
        Pcg32 rng = Pcg32::for_sample(s.pixel, iteration, stream_seed_);
        // Filter importance sampling (pixel_filter.h): the weight is 1 for a positive filter
        // and carries the sign of negative lobes.
        const CameraFilterSample fs = filter_.sample_camera(x, y, rng.next_2d());
        const Vec2 lens = rng.next_2d();
        s.ray = camera.generate_ray(fs.raster, lens);
        s.filter_weight = fs.weight;
        s.filter_pdf = fs.pdf;
        arena.reset();
        film.add_sample(x, y, estimate(scene, s, rng, arena, &dropped) * fs.weight);
      }
    if (dropped) nonfinite += dropped;
  });
  if (const uint64_t n = nonfinite.load()) film.count_nonfinite(n);
}

}  // namespace caustica
