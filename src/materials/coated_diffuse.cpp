#include "materials/materials.h"
namespace caustica {
MaterialPtr make_coated_diffuse(const CoatedDiffuseParams&) { return make_diffuse(nullptr); }
}  // namespace caustica
