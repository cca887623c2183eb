// adaptive-vcm's probes in the image. A probe is a full VCM iteration (every technique, every
// pixel merging) that the plan learns from; its estimate is as valid as any other iteration's,
// but where the choice renders far less noise per iteration (bidirectional connections alone),
// the probes' noise, merging's fireflies included, can dominate the plain average although
// they are a tenth of the iterations (a room lit around a corner: 60% of the relMSE in ten
// pixels). ProbeFilm keeps the probes' exact sums beside the film, so that the image can weight
// the probes' iterations by w <= 1 against the others (AdaptivePlan::probe_weight):
//   I = (w P + (F - P)) / (w n_p + (n - n_p)),
// F the film's sums over its n iterations, P the probes' over their n_p. With w = 1 it is the
// film's plain average, bit for bit.
//
// The sums are film differences: the film's totals before a probe subtracted, after it added,
// so they are exact (fixed point, core/fixed_sum.h) and need no hook in the estimators. Under
// MPI every rank renders every probe (a shared iteration, into its film or a scratch one), so
// every rank holds the probes' sums whole: rank 0's are the total (sums_over_ranks clears the
// others'). Memory: 48 bytes per pixel.
#pragma once

#include <algorithm>
#include <cstdint>
#include <span>
#include <vector>

#include "core/fixed_sum.h"
#include "image/image.h"

namespace caustica {
class Film;
}

namespace caustica::bidir {

class ProbeFilm {
 public:
  void reset(size_t pixels) { sums_.assign(3 * pixels, 0); }
  bool empty() const { return sums_.empty(); }
  // Around one probe iteration rendered into `film` (before it adds anything, after its last
  // estimate).
  void begin_probe(const Film& film);
  void end_probe(const Film& film);
  // The image of `film` with its `probes` probe iterations weighted by `weight` (in (0, 1]; 1,
  // or a film of probes alone: film.image()).
  Image image(const Film& film, uint32_t probes, double weight) const;
  std::span<FixedSum> sums() { return sums_; }
  void clear() { std::fill(sums_.begin(), sums_.end(), FixedSum(0)); }

 private:
  std::vector<FixedSum> sums_;  // 3 per pixel: the probes' estimates summed
};

}  // namespace caustica::bidir
