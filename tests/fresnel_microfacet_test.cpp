// The building blocks of the materials: Fresnel reflectance (dielectric, and complex for
// conductors, against pbrt-v4's formula in complex arithmetic), refraction, the Trowbridge-Reitz
// microfacet distribution and its visible normals, and the named spectra (metals' eta and k,
// glasses' eta) that feed them.
#include <gtest/gtest.h>

#include <cmath>
#include <complex>
#include <string>

#include "chi2.h"
#include "materials/fresnel.h"
#include "materials/materials.h"
#include "materials/microfacet.h"
#include "materials_helpers.h"

namespace caustica {
namespace {

using test::kTilted;

// ---------------------------------------------------------------------------------------------
// Building blocks

TEST(Fresnel, DielectricKnownValues) {
  EXPECT_NEAR(fr_dielectric(1.f, 1.5f), 0.04f, 1e-6f);
  EXPECT_NEAR(fr_dielectric(-1.f, 1.5f), 0.04f, 1e-6f);  // same from inside at normal incidence
  EXPECT_FLOAT_EQ(fr_dielectric(0.f, 1.5f), 1.f);        // grazing
  // From inside beyond the critical angle (asin(1/1.5) = 41.8 deg): total internal reflection.
  EXPECT_EQ(fr_dielectric(-std::cos(radians(45.f)), 1.5f), 1.f);
  EXPECT_LT(fr_dielectric(-std::cos(radians(40.f)), 1.5f), 1.f);
  // eta < 1 is the same interface seen from the other side.
  for (float c : {0.2f, 0.5f, 0.9f})
    EXPECT_NEAR(fr_dielectric(c, 1 / 1.5f), fr_dielectric(-c, 1.5f), 1e-6f);
  // Brewster angle: parallel polarisation vanishes, R = r_perp^2 / 2.
  const float cb = std::cos(std::atan(1.5f)),
              ct = std::cos(std::asin(std::sin(std::atan(1.5f)) / 1.5f));
  EXPECT_NEAR(fr_dielectric(cb, 1.5f), sqr((cb - 1.5f * ct) / (cb + 1.5f * ct)) / 2, 1e-6f);
}

TEST(Fresnel, ComplexReducesToDielectricWithoutAbsorption) {
  for (float c : {0.05f, 0.3f, 0.7f, 1.f})
    EXPECT_NEAR(fr_complex(c, {1.5f, 0.f}), fr_dielectric(c, 1.5f), 1e-5f);
  // Normal incidence: |(n - 1 + ik) / (n + 1 + ik)|^2.
  EXPECT_NEAR(fr_complex(1.f, {0.2f, 3.f}), (sqr(0.2f - 1) + 9) / (sqr(1.2f) + 9), 1e-5f);
  EXPECT_NEAR(fr_complex(0.f, {0.2f, 3.f}), 1.f, 1e-5f);
}

// fr_complex in real arithmetic against pbrt-v4's complex formula evaluated in double: metals
// (k large), dielectrics (k = 0, eta above and below 1: total internal reflection), and in
// between, at every angle.
TEST(Fresnel, ConductorMatchesComplexArithmetic) {
  auto reference = [](double cos_i, double eta, double k) {
    using C = std::complex<double>;
    const C n(eta, k);
    const double sin2_i = 1 - cos_i * cos_i;
    const C cos_t = std::sqrt(C(1.0) - sin2_i / (n * n));
    const C r_parl = (n * cos_i - cos_t) / (n * cos_i + cos_t);
    const C r_perp = (cos_i - n * cos_t) / (cos_i + n * cos_t);
    return (std::norm(r_parl) + std::norm(r_perp)) / 2;
  };
  double worst = 0;
  for (float eta : {0.05f, 0.2f, 0.67f, 1.f, 1.5f, 2.5f})
    for (float k : {0.f, 0.1f, 1.f, 3.f, 8.f})
      for (int i = 1; i <= 200; ++i) {
        const float c = float(i) / 200;
        if (eta == 1.f && k == 0.f) continue;  // no interface
        const double want = reference(c, eta, k);
        const float got = fr_complex(c, {eta, k});
        worst = std::max(worst, std::abs(double(got) - want));
        ASSERT_NEAR(got, want, 2e-5) << "eta " << eta << " k " << k << " cos " << c;
      }
  std::printf("[ fresnel ] max |real - complex| = %.2e\n", worst);
}

TEST(Fresnel, RefractObeysSnell) {
  const Vec3 wo = normalize(Vec3(0.5f, 0.2f, 0.8f));
  Vec3 wt;
  float etap = 0;
  ASSERT_TRUE(refract(wo, Vec3(0, 0, 1), 1.5f, &etap, &wt));
  EXPECT_FLOAT_EQ(etap, 1.5f);
  EXPECT_NEAR(length(wt), 1.f, 1e-5f);
  EXPECT_LT(wt.z, 0);
  EXPECT_NEAR(sin_theta(wo), 1.5f * sin_theta(wt), 1e-5f);
  // From inside the path reverses: the relative IOR crossed is 1/eta.
  Vec3 back;
  ASSERT_TRUE(refract(wt, Vec3(0, 0, 1), 1.5f, &etap, &back));
  EXPECT_FLOAT_EQ(etap, 1 / 1.5f);
  EXPECT_NEAR(back.x, wo.x, 1e-5f);
  EXPECT_NEAR(back.z, wo.z, 1e-5f);
  // Beyond the critical angle inside: total internal reflection.
  EXPECT_FALSE(refract(normalize(Vec3(0.9f, 0, -0.3f)), Vec3(0, 0, 1), 1.5f, &etap, &wt));
}

TEST(TrowbridgeReitz, NormalisedAndVisibleNormalsNormalised) {
  for (auto [ax, ay] : {std::pair{0.1f, 0.1f}, {0.3f, 0.3f}, {0.6f, 0.2f}}) {
    const TrowbridgeReitz d(ax, ay);
    // Projected microfacet area: integral of D(wm) cos(theta_m) = 1.
    // Quadrature in the tilted frame puts the peak at the grid's equator.
    const double projected = test::integrate_sphere(
        [&](Vec3 w) {
          const Vec3 wm = kTilted.to_local(w);
          return wm.z > 0 ? double(d.D(wm) * wm.z) : 0.0;
        },
        512, 1024);
    EXPECT_NEAR(projected, 1.0, 5e-3) << ax << " " << ay;
    // Visible normals from any direction integrate to 1 (Heitz 2014, eq. 2 with Smith G1).
    for (float theta : {0.f, 45.f, 80.f}) {
      const float t = radians(theta);
      const Vec3 w(std::sin(t) * std::cos(0.7f), std::sin(t) * std::sin(0.7f), std::cos(t));
      const double visible = test::integrate_sphere(
          [&](Vec3 v) {
            const Vec3 wm = kTilted.to_local(v);
            return wm.z > 0 && dot(w, wm) > 0 ? double(d.D(w, wm)) : 0.0;
          },
          512, 1024);
      EXPECT_NEAR(visible, 1.0, 1e-2) << ax << " " << ay << " theta " << theta;
    }
  }
  EXPECT_TRUE(TrowbridgeReitz(9e-4f, 9e-4f).effectively_smooth());
  EXPECT_FALSE(TrowbridgeReitz(9e-4f, 2e-3f).effectively_smooth());  // max of the two alphas
  EXPECT_FLOAT_EQ(TrowbridgeReitz::roughness_to_alpha(0.25f), 0.5f);
}

// ---------------------------------------------------------------------------------------------
// Named spectra

TEST(NamedSpectra, MetalsAndGlassesAreKnown) {
  for (const char* metal : {"Au", "Ag", "Cu", "Al", "CuZn"}) {
    const auto eta = named_spectrum_rgb(std::string("metal-") + metal + "-eta");
    const auto k = named_spectrum_rgb(std::string("metal-") + metal + "-k");
    ASSERT_TRUE(eta && k) << metal;
    for (int c = 0; c < 3; ++c) {
      EXPECT_GT((*eta)[c], 0.f);
      EXPECT_GT((*k)[c], 1.f);
    }
  }
  // Gold and copper are red: higher normal reflectance in red than in blue.
  for (const char* metal : {"Au", "Cu"}) {
    const Rgb eta = *named_spectrum_rgb(std::string("metal-") + metal + "-eta");
    const Rgb k = *named_spectrum_rgb(std::string("metal-") + metal + "-k");
    const Rgb r = fr_complex(1.f, eta, k);
    EXPECT_GT(r.r, r.b + 0.2f) << metal;
  }
  // Silver and aluminium are bright and nearly neutral.
  for (const char* metal : {"Ag", "Al"}) {
    const Rgb r = fr_complex(1.f, *named_spectrum_rgb(std::string("metal-") + metal + "-eta"),
                             *named_spectrum_rgb(std::string("metal-") + metal + "-k"));
    EXPECT_GT(r.b, 0.85f) << metal;
    EXPECT_LT(r.max_component() - r.b, 0.1f) << metal;
  }
  const auto bk7 = named_spectrum_rgb("glass-BK7");
  ASSERT_TRUE(bk7);
  EXPECT_NEAR(bk7->g, 1.5185f, 2e-3f);
  EXPECT_EQ(bk7->r, bk7->b);
  for (const char* glass :
       {"glass-BAF10", "glass-FK51A", "glass-LASF9", "glass-F5", "glass-F10", "glass-F11"})
    EXPECT_TRUE(named_spectrum_rgb(glass)) << glass;
  EXPECT_FALSE(named_spectrum_rgb("metal-Unobtainium-eta"));
}

}  // namespace
}  // namespace caustica
