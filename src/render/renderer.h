// The progressive render loop: iterations until a sample or time budget is met.
#pragma once

#include <atomic>
#include <cstdint>
#include <functional>
#include <string>

#include "image/image.h"
#include "integrators/integrator.h"

namespace caustica {

class Scene;
class Film;

struct RenderBudget {
  int spp = 0;         // iterations (one sample per pixel each); 0 = not set
  double seconds = 0;  // wall-clock budget; 0 = not set. Both set: whichever ends first
};

struct RenderResult {
  Image image;
  uint32_t iterations = 0;
  double seconds = 0;
  uint64_t rays = 0;
  uint64_t nonfinite = 0;
  bool interrupted = false;  // ended by `stop` before the budget was spent
};

struct RenderCallbacks {
  bool quiet = false;  // no progress bar
  std::string progress_label = "render";
  // Called after every iteration with the film and the render time so far; return false to
  // stop early. Time spent inside the callback (e.g. error snapshots) is not render time:
  // it is excluded from the time budget and from the reported seconds.
  std::function<bool(const Film&, uint32_t iterations, double seconds)> on_iteration;
  // When it becomes true (e.g. set by the caller's SIGINT handler) the render ends after the
  // current iteration and the result says `interrupted`. It is read only between iterations, so
  // an iteration is never cut short, and at least one always completes: an interrupted render
  // still has an image to write. The renderer owns no signal state; the caller does.
  const std::atomic<bool>* stop = nullptr;
};

// Peak resident memory of this process so far, in bytes (getrusage).
uint64_t peak_memory_bytes();

RenderResult render(const Scene& scene, Integrator& integrator, const RenderBudget& budget,
                    const RenderCallbacks& callbacks = {});

}  // namespace caustica
