// Fresnel reflectance and refraction (private to materials/). Conventions follow pbrt-v4
// (util/scattering.h): cosines are taken with the macro normal +z of the local frame and
// `eta` is the IOR of the -z side over that of the +z side (interior over exterior).
#pragma once

#include <algorithm>
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

// Fresnel reflectance of a conductor with complex IOR eta + i k: the value of pbrt-v4's FrComplex
// (unpolarised, |r_parallel|^2 and |r_perpendicular|^2 averaged) in real arithmetic, as pbrt-v3's
// FrConductor writes it. std::complex<float> spent half of a rough conductor's f() in the
// library's Annex G division and csqrtf (287 ns per f + pdf, BM_RoughConductorEval); the test
// Fresnel.ConductorMatchesComplexArithmetic compares the two.
inline float fr_complex(float cos_i, std::complex<float> eta_k) {
  cos_i = clamp(cos_i, 0.f, 1.f);
  if (cos_i == 0) return 1;  // grazing
  const float eta = eta_k.real(), k = eta_k.imag();
  const float cos2 = cos_i * cos_i, sin2 = 1 - cos2;
  const float t0 = eta * eta - k * k - sin2;
  const float a2b2 = std::sqrt(std::max(0.f, t0 * t0 + 4 * eta * eta * k * k));
  const float a = std::sqrt(std::max(0.f, 0.5f * (a2b2 + t0)));
  const float t1 = a2b2 + cos2, t2 = 2 * a * cos_i;
  const float r_perp = (t1 - t2) / (t1 + t2);
  const float t3 = cos2 * a2b2 + sin2 * sin2, t4 = t2 * sin2;
  const float r_parl = r_perp * (t3 - t4) / (t3 + t4);
  return 0.5f * (r_parl + r_perp);
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
