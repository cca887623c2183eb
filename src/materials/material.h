// Materials turn a surface point into a BSDF: they evaluate their textures at the hit and
// place a BxDF in the caller's scratch arena. Every material is built from a typed
// parameter set by a factory (see materials/factory.h) so loaders never see the classes.
#pragma once

#include <memory>

#include "core/arena.h"
#include "geometry/interaction.h"
#include "materials/bsdf.h"

namespace caustica {

class Material {
 public:
  virtual ~Material() = default;
  // The BSDF at si. May return an invalid Bsdf for "interface" materials that do not scatter.
  virtual Bsdf bsdf(const SurfaceInteraction& si, ScratchArena& arena) const = 0;
  virtual const char* name() const = 0;
};

using MaterialPtr = std::shared_ptr<const Material>;

}  // namespace caustica
