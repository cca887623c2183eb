#include "integrators/integrator.h"

#include "film/film.h"

namespace caustica {

Image Integrator::image(const Film& film) const { return film.image(); }

}  // namespace caustica
