// pbrt-v4 keeps singular transformations (`Scale 0 0 0` hides what follows), so a transform
// from a file may have no inverse; these build and inspect such transforms.
#pragma once

#include <optional>

#include "core/transform.h"

namespace caustica::pbrt {

// The transform of matrix m; if m is singular, its inverse is all NaN.
Transform make_transform(const Mat4& m);

// True if the matrix and its inverse are finite.
bool is_invertible(const Transform& t);

// Uniform scale of a similarity transform (rotation, translation, uniform scale, mirror),
// or nothing if the transform shears, scales non-uniformly or is projective.
std::optional<float> similarity_scale(const Transform& t);

}  // namespace caustica::pbrt
