// The processes a render is split over: one (SingleProcess) or K MPI ranks (built with
// CAUSTICA_MPI and started by mpirun). The render loop (renderer.h) and the command line speak
// only to this interface, so the one-process path is the same code with K = 1.
//
// Every method marked collective must be called by all ranks in the same order. Only the
// thread that created the Ranks calls them (MPI_THREAD_FUNNELED); TBB workers never do.
#pragma once

#include <cstdint>
#include <memory>
#include <span>
#include <string>

#include "core/fixed_sum.h"

namespace caustica {

class Film;

// What one rank reports in a progress round; the round's result is the sum over ranks.
struct RoundState {
  uint64_t iterations = 0;   // iterations this rank completed
  uint64_t rays = 0;         // rays this rank traced
  uint64_t finished = 0;     // 1: this rank has no more work
  uint64_t stop = 0;         // 1: a stop (a signal) was requested on this rank
  uint64_t interrupted = 0;  // 1: this rank ended its work early because of a stop
  uint64_t root_micros =
      0;  // rank 0's render time in microseconds (others give 0): its clock rules
};

class Ranks {
 public:
  virtual ~Ranks() = default;
  virtual int rank() const = 0;
  virtual int size() const = 0;
  bool is_root() const { return rank() == 0; }

  // Collective. Starts a progress round with this rank's state. Non-blocking under MPI
  // (MPI_Iallreduce), so a rank never waits for slower ones between iterations.
  virtual void start_round(const RoundState& mine) = 0;
  // True, with the sums over ranks in *totals, once every rank has joined the round started
  // last. With `wait` it returns only then (sleeping, not spinning, so that an idle rank leaves
  // its cores to the rank's neighbours on the same node).
  virtual bool poll_round(RoundState* totals, bool wait) = 0;

  // Collective. Sums every rank's film (sums, iterations, discarded samples) into *root_total,
  // which must be a film of the same size, on rank 0; elsewhere *root_total is untouched.
  virtual void sum_films(const Film& mine, Film* root_total) = 0;

  // Collective, on a channel of its own (it may interleave with progress rounds). Sums every
  // rank's film into *total on every rank (total: a film of the same size, not `mine`) and
  // returns whether any rank passed stop = true, so that all ranks stop at one decision.
  virtual bool all_sum_films(const Film& mine, Film* total, bool stop) = 0;

  // Collective, on all_sum_films' channel: whether any rank passed stop = true (the meeting
  // before a shared iteration of an integrator that does not read the film).
  virtual bool any_stops(bool stop) = 0;

  // Collective. Replaces `sums` on rank 0 by its sum over the ranks (the same length on every
  // rank; elsewhere it is left as it was): an integrator's own exact sums beside the film.
  virtual void sum_to_root(std::span<FixedSum> sums) = 0;

  // Collective, on all_sum_films' channel. Replaces `sums` on every rank by its sum over the
  // ranks (the same length on every rank): an integrator's learning sums beside the film.
  virtual void all_sum(std::span<FixedSum> sums) = 0;

  // Collective. Every rank passes its status (0: ready) and, when it failed, its message. All
  // return the largest status; rank 0 gets in *message the lowest failing rank's message
  // (empty if rank 0 failed itself: it has printed its own).
  virtual int agree(int status, const std::string& mine, std::string* message) = 0;

  // Collective. Returns when every rank has called it, sleeping meanwhile (an idle rank leaves
  // its node's cores to the ranks that work).
  virtual void wait_all() = 0;

  // Ends every rank at once (MPI_Abort): for a failure after agree(), when the other ranks
  // may be inside a collective that this rank will never join.
  [[noreturn]] virtual void abort(int exit_code) = 0;
};

class SingleProcess final : public Ranks {
 public:
  int rank() const override { return 0; }
  int size() const override { return 1; }
  void start_round(const RoundState& mine) override { round_ = mine; }
  bool poll_round(RoundState* totals, bool) override {
    *totals = round_;
    return true;
  }
  void sum_films(const Film& mine, Film* root_total) override;
  bool all_sum_films(const Film& mine, Film* total, bool stop) override {
    sum_films(mine, total);
    return stop;
  }
  bool any_stops(bool stop) override { return stop; }
  void sum_to_root(std::span<FixedSum>) override {}
  void all_sum(std::span<FixedSum>) override {}
  int agree(int status, const std::string&, std::string* message) override {
    message->clear();
    return status;
  }
  void wait_all() override {}
  [[noreturn]] void abort(int exit_code) override;

 private:
  RoundState round_;
};

// MPI ranks when this build has MPI and the process was started by an MPI launcher (mpirun,
// srun: it sets OMPI_COMM_WORLD_SIZE, PMI_SIZE or PMIX_RANK); otherwise SingleProcess, and MPI
// is never initialised. Call first thing in main(), before any thread exists.
std::unique_ptr<Ranks> start_ranks(int* argc, char*** argv);

// Whether this build can run across MPI ranks.
bool built_with_mpi();

}  // namespace caustica
