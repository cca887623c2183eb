// Compiled against the integrators layer's include view by the Layers test: the render layer
// sits above integrators, so this include must not be found.
#include "render/renderer.h"
