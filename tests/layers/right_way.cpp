// The positive control of the Layers test: the film layer sits below integrators.
#include "film/film.h"
#include "integrators/integrator.h"
