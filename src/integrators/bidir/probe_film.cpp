#include "integrators/bidir/probe_film.h"

#include <algorithm>

#include "film/film.h"

namespace caustica::bidir {

void ProbeFilm::begin_probe(const Film& film) {
  const std::span<const FixedSum> total = film.sums();
  for (size_t i = 0; i < sums_.size(); ++i) sums_[i] -= total[i];
}

void ProbeFilm::end_probe(const Film& film) {
  const std::span<const FixedSum> total = film.sums();
  for (size_t i = 0; i < sums_.size(); ++i) sums_[i] += total[i];
}

Image ProbeFilm::image(const Film& film, uint32_t probes, double weight) const {
  const uint32_t n = film.iterations();
  if (!(weight < 1) || probes == 0 || probes >= n || sums_.size() != 3 * film.pixel_count())
    return film.image();
  weight = std::max(weight, 0.0);
  const double inv = 1.0 / (weight * probes + double(n - probes));
  const std::span<const FixedSum> total = film.sums();
  Image out(film.width(), film.height());
  for (size_t p = 0; p < film.pixel_count(); ++p) {
    float c[3];
    for (int k = 0; k < 3; ++k) {
      const FixedSum probe = sums_[3 * p + k];
      c[k] = float((weight * from_fixed(probe) + from_fixed(total[3 * p + k] - probe)) * inv);
    }
    out[p] = Rgb(c[0], c[1], c[2]);
  }
  return out;
}

}  // namespace caustica::bidir
