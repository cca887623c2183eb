// The camera-path seam (in the spirit of pbrt-v4's RayIntegrator and Mitsuba 3's
// SamplingIntegrator): one place owns the tile loop, the pixel-keyed random streams, camera
// sampling through the pixel filter and the film writes. A camera-path integrator (pt, the
// bidirectional family's camera subpaths, and guided or adaptive ones to come) writes only
// estimate(); the vertex helpers in path_vertex.h give it emitter MIS, light sampling and
// Russian roulette without copying them.
//
// Random numbers: pixel p of iteration i draws from Pcg32::for_sample(p, i, stream_seed); the
// first two 2D samples are the pixel-filter offset and the lens point, in that order, then the
// stream is the estimator's. Nothing depends on which thread runs which tile, so an image is
// bit-identical for any thread count.
#pragma once

#include <cstdint>

#include "core/arena.h"
#include "core/rgb.h"
#include "core/rng.h"
#include "film/pixel_filter.h"
#include "geometry/interaction.h"
#include "integrators/integrator.h"

namespace caustica {

// One camera sample of one pixel.
struct CameraSample {
  int x = 0, y = 0;
  uint64_t pixel = 0;       // y * width + x
  uint32_t iteration = 0;   // 0-based
  Ray ray;                  // the primary ray, leaving the lens point ray.o
  float filter_weight = 1;  // the pixel filter's sample weight (1 for positive filters)
  float filter_pdf = 1;     // raster density of the filter offset (bidirectional MIS)
};

class CameraPathIntegrator : public Integrator {
 public:
  // Remembers the camera's pixel filter; an override must call it.
  void prepare(const Scene& scene, Film& film) override;
  // One camera sample per pixel (trace_camera_paths); integrators with per-iteration work of
  // their own (light subpaths) override it and call trace_camera_paths themselves.
  void render_iteration(const Scene& scene, uint32_t iteration, Film& film) override {
    trace_camera_paths(scene, iteration, film);
  }

 protected:
  // stream_seed keys the pixels' random streams (with the pixel and the iteration).
  explicit CameraPathIntegrator(uint64_t stream_seed) : stream_seed_(stream_seed) {}

  // Every pixel once: sample the camera, call estimate(), add estimate * filter weight to the
  // film. Values the estimator itself dropped as non-finite are counted in the film.
  void trace_camera_paths(const Scene& scene, uint32_t iteration, Film& film) const;

  // The pixel's estimate along sample.ray, before the filter weight. rng continues the pixel's
  // stream; arena is reset for every pixel. Add to *nonfinite what the estimator dropped.
  virtual Rgb estimate(const Scene& scene, const CameraSample& sample, Pcg32& rng,
                       ScratchArena& arena, uint64_t* nonfinite) const = 0;

 private:
  uint64_t stream_seed_;
  PixelFilter filter_;
};

}  // namespace caustica
