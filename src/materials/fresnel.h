// Fresnel reflectance and refraction (private to materials/). Conventions follow pbrt-v4
// (util/scattering.h): cosines are taken with the macro normal +z of the local frame and
// `eta` is the IOR of the -z side over that of the +z side (interior over exterior).
#pragma once

#include <complex>

#include "core/rgb.h"
#include "core/vec.h"

namespace caustica {

// Unpolarised Fresnel reflectance of a dielectric interface (pbrt-v4 FrDielectric).
// cos_i > 0: the incident direction is on the +z (exterior) side and light enters a medium of
// relative IOR eta; cos_i < 0: it arrives from inside, so the relative IOR is 1/eta. Returns 1
// under total internal reflection.
inline float fr_dielectric(float cos_i, float eta) {
  cos_i = clamp(cos_i, -1.f, 1.f);
  if (cos_i < 0) {
    eta = 1 / eta;
    cos_i = -cos_i;
  }
  const float sin2_i = 1 - cos_i * cos_i;
  const float sin2_t = sin2_i / (eta * eta);
  if (sin2_t >= 1) return 1.f;
  const float cos_t = safe_sqrt(1 - sin2_t);
  const float r_parl = (eta * cos_i - cos_t) / (eta * cos_i + cos_t);
  const float r_perp = (cos_i - eta * cos_t) / (cos_i + eta * cos_t);
  return (r_parl * r_parl + r_perp * r_perp) / 2;
}

// Fresnel reflectance of a conductor with complex IOR eta + i k (pbrt-v4 FrComplex).
inline float fr_complex(float cos_i, std::complex<float> eta) {
  using C = std::complex<float>;
  cos_i = clamp(cos_i, 0.f, 1.f);
  const float sin2_i = 1 - cos_i * cos_i;
  const C sin2_t = sin2_i / (eta * eta);
  const C cos_t = std::sqrt(C(1.f) - sin2_t);
  const C r_parl = (eta * cos_i - cos_t) / (eta * cos_i + cos_t);
  const C r_perp = (cos_i - eta * cos_t) / (cos_i + eta * cos_t);
  return (std::norm(r_parl) + std::norm(r_perp)) / 2;
}
inline Rgb fr_complex(float cos_i, Rgb eta, Rgb k) {
  return {fr_complex(cos_i, {eta.r, k.r}), fr_complex(cos_i, {eta.g, k.g}),
          fr_complex(cos_i, {eta.b, k.b})};
}

// Refraction of wi (pointing away from the surface) through the interface with normal n and
// relative IOR eta (pbrt-v4 Refract). If wi is on the other side of n the interface is flipped
// and eta inverted. Writes the refracted direction and the relative IOR actually crossed
// (etap). Returns false under total internal reflection.
inline bool refract(Vec3 wi, Vec3 n, float eta, float* etap, Vec3* wt) {
  float cos_i = dot(n, wi);
  if (cos_i < 0) {
    eta = 1 / eta;
    cos_i = -cos_i;
    n = -n;
  }
  const float sin2_i = std::max(0.f, 1 - cos_i * cos_i);
  const float sin2_t = sin2_i / (eta * eta);
  if (sin2_t >= 1) return false;
  const float cos_t = safe_sqrt(1 - sin2_t);
  *wt = -wi / eta + (cos_i / eta - cos_t) * n;
  if (etap) *etap = eta;
  return true;
}

}  // namespace caustica
