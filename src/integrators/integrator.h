// The integrator interface. The render loop drives iterations; an iteration estimates every
// pixel once (camera-path integrators: one sample per pixel; bidirectional ones: one batch of
// light paths plus one camera path per pixel). Iteration results are added to the Film.
#pragma once

#include <cstdint>
#include <memory>
#include <nlohmann/json_fwd.hpp>
#include <optional>
#include <span>
#include <string>

#include "core/fixed_sum.h"
#include "guiding/guiding_settings.h"
#include "image/image.h"

namespace caustica {

class Scene;
class Film;

enum class MisHeuristic { Balance, Power };

// Knobs of the bidirectional family (lt, bpt, ppm, bpm, vcm); the others ignore them.
struct BidirSettings {
  uint64_t light_paths = 0;    // light subpaths per iteration; 0 = one per pixel
  float radius = 0;            // initial merge radius; 0 = derived from the scene size
  float radius_alpha = 0.75f;  // r_i = r_1 i^((alpha - 1) / 2)
  std::string techniques_dir;  // if set, write one image per technique
  int connections = 1;         // bpt, vcm: light subpaths each camera vertex connects to
  // vcm, guided-vcm: scales the merges' sample count N pi r^2 in the MIS weights only (1 = the
  // balance heuristic of Georgiev et al. 2012). Any value keeps the weights summing to one;
  // below 1 it trusts merging less, everywhere, which is the direction correlation-aware MIS
  // (Grittmann et al. 2021) moves per vertex: merges share their light subpaths, so they are
  // worth fewer than N independent samples. (bpm: every technique merges, the factor cancels.)
  float merge_mis_scale = 1;
  // vcm: correlation-aware MIS for the merges (Grittmann, Georgiev and Slusallek 2021;
  // bidir/mis.h, CorrelationTrack): each merge's count is lowered by how much of its path the
  // merges around it share. --merge-mis correlation-aware.
  bool correlation_aware = false;
  // adaptive-vcm: price techniques with costs measured on this machine while rendering
  // (non-deterministic) instead of the fixed cost model.
  bool measured_costs = false;
  // adaptive-vcm: every iteration is a probe (studies of the variance prediction, tests).
  bool probe_every_iteration = false;
  // adaptive-vcm: probes record one pixel per probe_stride x probe_stride block (0: from the
  // image's size, AdaptivePlan::kProbePixels).
  int probe_stride = 0;
  // adaptive-vcm, for experiments and tests: after each choice every pixel takes this mode
  // (bidir::PixelMode: 0 the core, 1 the core and merging, 2 path tracing, 3 photon mapping)
  // instead of its own; -1: each pixel's own choice.
  int force_pixel_mode = -1;
};

// Settings shared by all integrators, and each family's own struct.
struct IntegratorSettings {
  int max_depth = 10;  // scattering vertices, as pbrt-v4's maxdepth (1 = direct light only)
  uint64_t seed = 0;
  // The MIS heuristic the user chose (--mis); empty: each integrator's default (pt: power, the
  // bidirectional family: balance).
  std::optional<MisHeuristic> mis;
  MisHeuristic mis_or(MisHeuristic fallback) const { return mis.value_or(fallback); }
  BidirSettings bidir;
  GuidingSettings guiding;  // guided-pt (--guiding-*)
};

class Integrator {
 public:
  virtual ~Integrator() = default;
  virtual const char* name() const = 0;
  // The render loop's budget, before prepare(): spp > 0 samples per pixel, seconds > 0 a time
  // limit (0: not limited that way). An integrator that splits its budget between learning and
  // rendering (guided ones) reads it; without it (tests driving iterations) it is unknown.
  void set_budget(int spp, double seconds) {
    budget_spp_ = spp;
    budget_seconds_ = seconds;
  }
  // Called once before the first iteration.
  virtual void prepare(const Scene& scene, Film& film) {
    (void)scene;
    (void)film;
  }
  // Renders iteration `iteration` (0-based) into film; film.end_iteration() is the caller's.
  virtual void render_iteration(const Scene& scene, uint32_t iteration, Film& film) = 0;
  // Called once after the last iteration (e.g. to write per-technique images).
  virtual void finish(const Scene& scene, Film& film) {
    (void)scene;
    (void)film;
  }
  // The image of the iterations completed in film: by default their plain average
  // (film.image()). An integrator that weights its iterations unequally (guided-pt: inverse
  // variance) returns its own combination; the render loop and the comparisons use this.
  virtual Image image(const Film& film) const;
  // Integrator-specific statistics for the JSON output.
  virtual void report(nlohmann::json& stats) const { (void)stats; }

  // Learning that every MPI rank shares (adaptive-vcm's probes, the training passes of the
  // guided integrators): an iteration for which this is true teaches the integrator how to
  // render later ones. The render loop has every rank render it, in global iteration order, so
  // that each rank learns the same; only the rank that owns the iteration (iteration mod K)
  // keeps its image in the film. In one process nothing changes. Asked for the iterations from
  // the next one on, which the integrator must know by then (the guided ones decide at the end
  // of a pass what the next does).
  virtual bool shared_iteration(uint32_t iteration) const {
    (void)iteration;
    return false;
  }
  // Called by the render loop right before a shared iteration with the film of every iteration
  // before it, summed over all ranks (at a fixed --spp; under --time, this rank's own film), so
  // that what the integrator reads from the film does not depend on the number of ranks. An
  // integrator driven without the render loop reads its own film instead.
  virtual void observe_film(const Film& before) { (void)before; }
  // Whether observe_film() is wanted: else the ranks meet before a shared iteration only to
  // agree whether to stop, without summing their films.
  virtual bool observes_film() const { return false; }
  // Exact sums an integrator learns from beside the film (adaptive-vcm: the pixel moments of
  // the iterations since its last probe; empty: none, the default). Before a shared iteration
  // at a fixed --spp the render loop sums them over the ranks, right after the films, and hands
  // the sum to observe_learning_sums(); otherwise the integrator reads its own. The span's
  // length must be the same on every rank.
  virtual std::span<FixedSum> learning_sums() { return {}; }
  virtual void observe_learning_sums(std::span<const FixedSum> total) { (void)total; }

  // A render split over MPI ranks calls this once on every rank after the last iteration, and
  // adds the returned exact sums over the ranks into rank 0's before image() there, as it adds
  // the films: what image() reads beside the film (guided-pt: its current pass). The span's
  // length must be the same on every rank; `root`: this is rank 0 (a part that every rank
  // holds whole, such as a pass of shared iterations, is cleared elsewhere). Default: none.
  virtual std::span<FixedSum> sums_over_ranks(bool root) {
    (void)root;
    return {};
  }

 protected:
  int budget_spp() const { return budget_spp_; }
  double budget_seconds() const { return budget_seconds_; }

 private:
  int budget_spp_ = 0;
  double budget_seconds_ = 0;
};

}  // namespace caustica
