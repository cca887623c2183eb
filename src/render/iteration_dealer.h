// Which global iterations one rank renders, in order (renderer.h): its own, iteration mod K ==
// rank, so that every random stream and the merge radius schedule are those of one process; and
// every shared iteration (Integrator::shared_iteration: learning every rank must see, such as
// adaptive-vcm's probes), whoever owns it. At a fixed --spp with several ranks the ranks meet
// before each shared iteration (Ranks::all_sum_films), so a rank that wants to stop skips to the
// next shared iteration and stops there, together with the others.
#pragma once

#include <cstdint>

#include "integrators/integrator.h"

namespace caustica {

class IterationDealer {
 public:
  IterationDealer(const Integrator& integrator, uint64_t rank, uint64_t ranks, int spp_budget)
      : integrator_(integrator), rank_(rank), ranks_(ranks), spp_(spp_budget) {}

  // The next iteration this rank renders (advance() moves past it).
  uint64_t current() {
    while (!owns(cursor_) && !shared(cursor_)) ++cursor_;
    return cursor_;
  }
  void advance() { ++cursor_; }
  bool owns(uint64_t iteration) const { return iteration % ranks_ == rank_; }
  bool shared(uint64_t iteration) const {
    return integrator_.shared_iteration(uint32_t(iteration));
  }
  // Moves to the next shared iteration within the --spp budget (this one, if it is shared);
  // false, without moving, when there is none.
  bool skip_to_next_shared() {
    if (spp_ <= 0) return false;
    uint64_t i = cursor_;
    while (i < uint64_t(spp_) && !shared(i)) ++i;
    if (i >= uint64_t(spp_)) return false;
    cursor_ = i;
    return true;
  }

 private:
  const Integrator& integrator_;
  uint64_t rank_, ranks_;
  int spp_;
  uint64_t cursor_ = 0;
};

}  // namespace caustica
