// Homogeneous absorbing media (pbrt-v4's "homogeneous" medium without scattering) and the
// surfaces that bound them (pbrt-v4's MediumInterface). Light travelling a distance d inside a
// medium keeps exp(-sigma_a d) of itself per channel (Beer-Lambert). Nothing is sampled in a
// medium, so every vertex is still on a surface and every technique samples the same vertices
// with the same densities: the transmittance is a factor of the measurement contribution alone,
// the MIS weights do not change, and every integrator multiplies it into each segment it forms.
//
// A segment's medium comes from its two ends, so that every technique that forms the segment
// (a camera or light subpath's step, a shadow ray, a connection) gives it the same factor: an
// end on a surface that separates two media (inside != outside) names the medium on its side
// of the segment; any other end (a surface that is no transition, the camera, a light, the sky)
// names none. With no end naming one, the segment is in the scene's default medium (the
// camera's). So a segment between two surfaces that are no transitions, inside a medium other
// than the camera's, is taken to be in the camera's: pbrt-v4 would follow the path's medium.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>

#include "core/rgb.h"
#include "core/vec.h"

namespace caustica {

struct HomogeneousMedium {
  Rgb sigma_a;  // absorption per unit length, per channel (>= 0)

  Rgb transmittance(float distance) const {
    auto channel = [&](float s) { return s > 0 ? std::exp(-s * distance) : 1.f; };
    return Rgb(channel(sigma_a.r), channel(sigma_a.g), channel(sigma_a.b));
  }
};

constexpr int16_t kNoMedium = -1;

// The media on the two sides of a surface: inside is behind the geometric normal, outside in
// front of it (pbrt-v4's MediumInterface). Indices into the scene's media, or kNoMedium.
struct MediumInterface {
  int16_t inside = kNoMedium, outside = kNoMedium;
  bool transition() const { return inside != outside; }
};

// One end of a segment (see above): `medium` is meaningful only when `known`.
struct SegmentEnd {
  int16_t medium = kNoMedium;
  bool known = false;
};

// The end at a surface with interface m and geometric normal ng, for a segment leaving it along w.
inline SegmentEnd segment_end(const MediumInterface& m, Vec3 ng, Vec3 w) {
  if (!m.transition()) return {};
  return {dot(w, ng) > 0 ? m.outside : m.inside, true};
}

// The medium between two ends, the same in both directions: a known end decides; two known ends
// agree in a consistent scene, else the medium (not vacuum, the larger index) is taken.
inline int16_t medium_between(SegmentEnd a, SegmentEnd b, int16_t default_medium) {
  if (a.known && b.known) return std::max(a.medium, b.medium);
  if (a.known) return a.medium;
  if (b.known) return b.medium;
  return default_medium;
}

}  // namespace caustica
