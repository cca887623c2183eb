#include "render/ranks.h"

#include <cstdlib>
#include <stdexcept>

#include "film/film.h"

namespace caustica {

void SingleProcess::sum_films(const Film& mine, Film* root_total) {
  if (root_total == &mine) return;
  root_total->set_counts(0, 0);
  for (FixedSum& s : root_total->sums()) s = 0;
  root_total->add(mine);
}

void SingleProcess::abort(int exit_code) { std::_Exit(exit_code); }

#ifndef CAUSTICA_MPI
std::unique_ptr<Ranks> start_ranks(int*, char***) { return std::make_unique<SingleProcess>(); }
bool built_with_mpi() { return false; }
#endif

}  // namespace caustica
