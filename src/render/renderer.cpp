#include "render/renderer.h"

#include <sys/resource.h>

#include <chrono>
#include <cmath>
#include <optional>
#include <stdexcept>
#include <vector>

#include "film/film.h"
#include "render/iteration_dealer.h"
#include "render/progress.h"
#include "render/ranks.h"
#include "scene/scene.h"

namespace caustica {

uint64_t peak_memory_bytes() {
  struct rusage usage {};
  getrusage(RUSAGE_SELF, &usage);
  return uint64_t(usage.ru_maxrss) * 1024;  // Linux reports kilobytes
}

RenderResult render(const Scene& scene, Integrator& integrator, const RenderBudget& budget,
                    const RenderCallbacks& callbacks) {
  if (budget.spp <= 0 && budget.seconds <= 0)
    throw std::invalid_argument("render budget needs spp or seconds");
  SingleProcess single;
  Ranks& ranks = callbacks.ranks ? *callbacks.ranks : single;
  const uint64_t rank_count = uint64_t(ranks.size()), me = uint64_t(ranks.rank());
  Film film(scene.camera().width(), scene.camera().height());
  ProgressBar progress(callbacks.progress_label, callbacks.quiet || !ranks.is_root());
  const auto start = std::chrono::steady_clock::now();
  const uint64_t rays_before = scene.rays_traced();
  double paused = 0;  // seconds spent in callbacks, not counted as render time
  auto elapsed = [&] {
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count() - paused;
  };

  integrator.set_budget(budget.spp, budget.seconds);
  integrator.prepare(scene, film);
  uint32_t done = 0;         // iterations this rank completed
  bool finished = false;     // this rank has no more work
  bool interrupted = false;  // ... because of a stop
  bool stop_all = false;     // a stop was agreed in a round: the same on every rank
  bool round_pending = false;
  // Shared learning across ranks at a fixed --spp: before each shared iteration the ranks sum
  // their films (a blocking collective), so a rank may only stop there, together with the
  // others (`stopping` tells them); under --time every rank learns from its own film.
  const bool shared_sums = rank_count > 1 && budget.seconds <= 0;
  IterationDealer dealer(integrator, me, rank_count, budget.spp);
  bool ending = false;    // on_iteration asked to end (with shared sums: at the next ones)
  bool stopping = false;  // on the way to the next shared iteration's sums, to stop there
  // Before a shared iteration: the film of every iteration before it, over all ranks. False
  // when the ranks agreed there to stop.
  auto observe_before = [&] {
    if (!shared_sums) {
      integrator.observe_film(film);
      return true;
    }
    if (!integrator.observes_film()) return !ranks.any_stops(stopping);
    Film before(film.width(), film.height());
    if (ranks.all_sum_films(film, &before, stopping)) return false;
    integrator.observe_film(before);
    if (const std::span<FixedSum> mine = integrator.learning_sums(); !mine.empty()) {
      std::vector<FixedSum> total(mine.begin(), mine.end());
      ranks.all_sum(total);
      integrator.observe_learning_sums(total);
    }
    return true;
  };
  std::optional<Film> scratch;  // the film of other ranks' shared iterations, never read
  RoundState totals;
  double next_checkpoint = callbacks.checkpoint_seconds;
  auto my_state = [&] {
    RoundState s;
    s.iterations = done;
    s.rays = scene.rays_traced() - rays_before;
    s.finished = finished;
    s.stop = callbacks.stop && callbacks.stop->load();
    s.interrupted = interrupted;
    s.root_micros = ranks.is_root() ? uint64_t(std::max(0.0, elapsed()) * 1e6) : 0;
    return s;
  };
  for (;;) {
    // Progress rounds: one at a time, started when the last one ended. In one process a round
    // ends at once, so the stop flag is read before every iteration as it always was.
    if (!round_pending) {
      ranks.start_round(my_state());
      round_pending = true;
    }
    // A finished rank waits for the round; a working one only looks and renders on.
    if (ranks.poll_round(&totals, finished)) {
      round_pending = false;
      stop_all = stop_all || totals.stop > 0;
      if (totals.finished == rank_count) break;
      const double root_seconds = double(totals.root_micros) * 1e-6;
      const double frac_spp = budget.spp > 0 ? double(totals.iterations) / budget.spp : 0;
      const double frac_time = budget.seconds > 0 ? root_seconds / budget.seconds : 0;
      progress.update(std::max(frac_spp, frac_time),
                      root_seconds > 0 ? double(totals.rays) / root_seconds * 1e-6 : 0, "Mrays/s");
      // Every rank sees the same round totals, so every rank takes this branch at the same
      // round and the collective inside it matches.
      if (next_checkpoint > 0 && root_seconds >= next_checkpoint && totals.iterations > 0) {
        const auto before = std::chrono::steady_clock::now();
        Film sum(film.width(), film.height());
        ranks.sum_films(film, &sum);
        if (ranks.is_root() && callbacks.on_checkpoint)
          callbacks.on_checkpoint(sum.image(), sum.iterations(), root_seconds);
        next_checkpoint = callbacks.checkpoint_seconds *
                          (std::floor(root_seconds / callbacks.checkpoint_seconds) + 1);
        paused += std::chrono::duration<double>(std::chrono::steady_clock::now() - before).count();
      }
    }
    if (finished) continue;

    const uint64_t iteration = dealer.current();  // iteration_dealer.h
    if (budget.spp > 0 && iteration >= uint64_t(budget.spp)) {
      finished = true;
    } else if (budget.seconds > 0 && done > 0 && elapsed() >= budget.seconds) {
      finished = true;
    } else if (done > 0 && stop_all && !shared_sums) {
      // After the budget checks, so a stop that arrives during the last iteration is not
      // reported as an interruption of a render that was complete anyway.
      finished = interrupted = true;
    } else if ((stop_all || ending) && shared_sums && !stopping) {
      // Other ranks may be on their way to the next shared iteration's sums: this rank meets
      // them there and says it stops (below), or ends now if no shared iteration is left.
      stopping = true;
      if (dealer.skip_to_next_shared()) continue;
      finished = interrupted = true;
    }
    if (finished) continue;
    if (dealer.shared(iteration) && !observe_before()) {
      finished = interrupted = true;
      continue;
    }
    dealer.advance();
    if (!dealer.owns(iteration)) {  // someone else's shared iteration: learn, keep no image
      if (!scratch) scratch.emplace(film.width(), film.height());
      integrator.render_iteration(scene, uint32_t(iteration), *scratch);
      continue;
    }
    integrator.render_iteration(scene, uint32_t(iteration), film);
    film.end_iteration();
    ++done;
    if (callbacks.on_iteration) {
      const auto before = std::chrono::steady_clock::now();
      const bool go_on = callbacks.on_iteration(film, done, elapsed());
      paused += std::chrono::duration<double>(std::chrono::steady_clock::now() - before).count();
      if (!go_on && shared_sums) ending = true;  // other ranks may be on their way to sums
      if (!go_on && !shared_sums) finished = true;
    }
  }
  integrator.finish(scene, film);
  const double total = elapsed();
  if (totals.interrupted == 0)
    progress.update(1.0, total > 0 ? double(totals.rays) / total * 1e-6 : 0, "Mrays/s");
  progress.finish();

  RenderResult r;
  r.seconds = total;
  r.ranks = ranks.size();
  r.local_iterations = done;
  r.iterations = uint32_t(totals.iterations);
  r.rays = totals.rays;
  r.interrupted = totals.interrupted > 0;
  if (rank_count == 1) {
    r.image = integrator.image(film);
    r.nonfinite = film.nonfinite_count();
  } else {
    // What the integrator's image reads beside the film (a collective on every rank whenever
    // the integrator has such sums: the same integrator everywhere).
    const std::span<FixedSum> own = integrator.sums_over_ranks(ranks.is_root());
    if (!own.empty()) ranks.sum_to_root(own);
    Film sum(film.width(), film.height());
    ranks.sum_films(film, &sum);
    r.image = ranks.is_root() ? integrator.image(sum) : sum.image();
    r.nonfinite = sum.nonfinite_count();
  }
  return r;
}

}  // namespace caustica
