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
class Ranks;

struct RenderBudget {
  int spp = 0;         // iterations (one sample per pixel each); 0 = not set
  double seconds = 0;  // wall-clock budget; 0 = not set. Both set: whichever ends first
};

struct RenderResult {
  Image image;                    // on rank 0: the image of all ranks' iterations; elsewhere unused
  uint32_t iterations = 0;        // over all ranks (on every rank)
  uint32_t local_iterations = 0;  // this rank's
  int ranks = 1;
  double seconds = 0;
  uint64_t rays = 0;         // over all ranks
  uint64_t nonfinite = 0;    // over all ranks (on rank 0)
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

  // The processes the render is split over; nullptr: this one alone. Iteration i is rendered by
  // rank i mod K with the same random streams as in one process; films are summed exactly
  // (film.h), so a fixed --spp gives the same image, bit for bit, for any K. With a time budget
  // every rank renders until its own clock says so and the images are combined weighted by
  // iterations. Only rank 0 shows progress (the totals over ranks). A stop requested on any
  // rank is agreed in a progress round, so all ranks stop at one decision.
  Ranks* ranks = nullptr;
  // Every this many seconds of rank 0's render time (0: never), the ranks sum their films and
  // rank 0 gets the image so far, so that a run killed before its end leaves an image.
  double checkpoint_seconds = 0;
  std::function<void(const Image& image, uint32_t iterations, double seconds)> on_checkpoint;
};

// Peak resident memory of this process so far, in bytes (getrusage).
uint64_t peak_memory_bytes();

RenderResult render(const Scene& scene, Integrator& integrator, const RenderBudget& budget,
                    const RenderCallbacks& callbacks = {});

}  // namespace caustica
