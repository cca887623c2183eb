// The layered materials, pbrt-v4's stochastic layered BSDF (a random walk between a dielectric
// coat and its base): coated diffuse and coated conductor. Their flags follow the coat, their
// energy stays at most one and their sample weights agree with f(), smooth layers reproduce the
// analytic series of bounces, an index-matched coat gives the bare metal back, and their
// stochastic evaluation is deterministic. The shared setup: materials_helpers.h.
#include <gtest/gtest.h>

#include <cmath>

#include "chi2.h"
#include "core/warp.h"
#include "materials/fresnel.h"
#include "materials_helpers.h"

namespace caustica {
namespace {

using test::coated;
using test::constant;
using test::kModes;
using test::kRadiance;
using test::kTilted;
using test::sample_weights;
using test::Surface;
using test::WeightStats;

// ---------------------------------------------------------------------------------------------
// Coated diffuse (stochastic layered BSDF)

TEST(CoatedDiffuse, FlagsFollowTheCoat) {
  EXPECT_EQ(Surface(coated(0.5f, 0.f)).bsdf.flags(),
            uint32_t(kBxdfReflection | kBxdfSpecular | kBxdfDiffuse));
  EXPECT_EQ(Surface(coated(0.5f, 0.2f)).bsdf.flags(), uint32_t(kBxdfReflection | kBxdfDiffuse));
  EXPECT_FALSE(Surface(coated(0.5f, 0.f)).bsdf.is_delta());
}

TEST(CoatedDiffuse, BlackBaseReflectsOnlyTheCoatsFresnel) {
  Surface s(coated(0.f, 0.f));
  for (float theta : {0.f, 45.f, 75.f, 135.f}) {
    const Vec3 wo = s.dir(theta);
    // Reflection is chosen with probability F and then has weight 1; every walk into the
    // black base dies. The mean weight is a binomial proportion around F.
    const int n = 20000;
    const WeightStats w = sample_weights(s.bsdf, wo, kRadiance, n);
    const double F = fr_dielectric(std::abs(dot(wo, kTilted.n)), 1.5f);
    EXPECT_NEAR(w.mean, F, 4 * std::sqrt(F * (1 - F) / n)) << theta;
    EXPECT_NEAR(w.max, 1.0, 1e-5) << theta;
    EXPECT_TRUE(s.bsdf.f(wo, s.dir(30, 2.f), kRadiance).is_black());
  }
}

TEST(CoatedDiffuse, EnergyAtMostOneAndSamplesConsistentWithF) {
  // Default walk length (10) and a long one: f() with next-event estimation and sample() cut
  // the walk at different points, so they agree closely only when truncation is negligible.
  for (int max_depth : {10, 100})
    for (float roughness : {0.f, 0.3f})
      for (float theta : {10.f, 50.f, 80.f, 140.f}) {
        SCOPED_TRACE(testing::Message() << "maxdepth " << max_depth << " roughness " << roughness
                                        << " theta " << theta);
        Surface s(coated(1.f, roughness, max_depth));
        const Vec3 wo = s.dir(theta);
        // Sample weights: an unbiased estimate of the directional albedo, delta lobe included.
        Pcg32 rng(21, 22);
        const int n = 40000;
        double total = 0, non_specular = 0;
        for (int i = 0; i < n; ++i) {
          const float uc = rng.next_float();
          const auto smp = s.bsdf.sample(wo, uc, rng.next_2d(), kRadiance);
          if (!smp) continue;
          EXPECT_TRUE(smp->pdf_is_proportional);
          EXPECT_FALSE(smp->is_transmission());
          const double w = smp->f.g * s.bsdf.abs_cos(smp->wi) / smp->pdf;
          total += w;
          if (!smp->is_specular()) non_specular += w;
        }
        total /= n;
        non_specular /= n;
        // A white base under a lossless coat: only the thin absorbing layer, the walk length and
        // (for a rough coat) single-scattering microfacets lose energy.
        EXPECT_LE(total, 1.0 + 1e-2);
        EXPECT_GT(total, 0.6);
        // f() is a stochastic estimate of the same BSDF, so its integral matches the non-delta
        // part of the sampled weights: loosely, because both are noisy and truncate the walk
        // differently, and because for a rough coat pbrt-v4's f() (reproduced here) uses an MIS
        // weight whose densities do not match, which makes it 5-9% brighter (with the matching
        // density the two agree within 3% at maxdepth 100).
        const double integral = test::integrate_sphere(
            [&](Vec3 wi) { return double(s.bsdf.f(wo, wi, kRadiance).g * s.bsdf.abs_cos(wi)); },
            128, 256);
        if (roughness == 0 && max_depth == 100) {
          EXPECT_NEAR(integral, non_specular, 0.03 * non_specular + 0.01);
        } else if (roughness == 0) {
          EXPECT_NEAR(integral, non_specular, 0.1 * non_specular);
        } else {
          EXPECT_GT(integral, non_specular);
          EXPECT_LT(integral, 1.12 * non_specular + 0.01);
        }
        EXPECT_LE(integral, 1.0 + 1e-2);
      }
}

TEST(CoatedDiffuse, StochasticEvaluationIsDeterministic) {
  const MaterialPtr m = coated(0.6f, 0.1f);
  Surface a(m), b(m);
  Pcg32 rng(8, 9);
  for (int i = 0; i < 200; ++i) {
    const Vec3 wo = kTilted.to_world(sample_uniform_sphere(rng.next_2d()));
    const Vec3 wi = kTilted.to_world(sample_uniform_sphere(rng.next_2d()));
    for (auto mode : kModes) {
      const Rgb fa = a.bsdf.f(wo, wi, mode), fb = b.bsdf.f(wo, wi, mode);
      EXPECT_EQ(fa, fb);
      EXPECT_EQ(a.bsdf.f(wo, wi, mode), fa);  // same call twice
      EXPECT_EQ(a.bsdf.pdf(wo, wi, mode), b.bsdf.pdf(wo, wi, mode));
      EXPECT_TRUE(fa.is_finite());
      // Two-sided, and never a zero pdf where f may be non-zero (mixed with the uniform pdf).
      if (dot(wo, kTilted.n) * dot(wi, kTilted.n) > 0) {
        EXPECT_GE(a.bsdf.pdf(wo, wi, mode), 0.1f * kInv4Pi);
      }
    }
    const float uc = rng.next_float();
    const Vec2 u = rng.next_2d();
    const auto sa = a.bsdf.sample(wo, uc, u, kRadiance), sb = b.bsdf.sample(wo, uc, u, kRadiance);
    ASSERT_EQ(bool(sa), bool(sb));
    if (sa) {
      EXPECT_EQ(sa->wi, sb->wi);
      EXPECT_EQ(sa->f, sb->f);
    }
  }
}

TEST(CoatedDiffuse, PdfRoughlyNormalised) {
  // pdf() is only an approximation of the sampling density (pbrt-v4's estimator mixed 9:1 with
  // the uniform density): for a rough coat it adds the coat's full reflection density to the
  // estimate of the base's, so it integrates to about 2. Only check it stays plausible for MIS.
  for (float roughness : {0.f, 0.3f}) {
    Surface s(coated(0.5f, roughness));
    const Vec3 wo = s.dir(40);
    const double integral = test::integrate_sphere(
        [&](Vec3 wi) { return double(s.bsdf.pdf(wo, wi, kRadiance)); }, 128, 256);
    EXPECT_GT(integral, 0.5) << roughness;
    EXPECT_LT(integral, 2.5) << roughness;
  }
}

// ---------------------------------------------------------------------------------------------
// Coated conductor (the same layered BSDF over a conductor)

MaterialPtr coated_conductor(float reflectance, float coat_roughness, float metal_roughness,
                             float thickness = 0.01f, int max_depth = 10) {
  CoatedConductorParams p;
  p.max_depth = max_depth;
  p.reflectance = constant(reflectance);
  p.interface_u_roughness = p.interface_v_roughness = constant(coat_roughness);
  p.conductor_u_roughness = p.conductor_v_roughness = constant(metal_roughness);
  p.remap_roughness = false;
  p.thickness = thickness;
  return make_coated_conductor(p);
}

TEST(CoatedConductor, SmoothLayersReflectTheAnalyticSeries) {
  // A smooth coat (eta 1.5) over a smooth conductor: every sample leaves along the mirror
  // direction, and at normal incidence their mean weight is the series of bounces between the
  // coat and the metal, F + (1 - F)^2 R T^2 / (1 - F R T^2), with T = exp(-thickness) the slab's
  // transmittance per crossing and R the metal's reflectance *inside the coat*: pbrt-v4 divides
  // eta and k by the coat's IOR. The bare conductor would reflect 0.5.
  for (float thickness : {0.01f, 0.5f}) {
    Surface s(coated_conductor(0.5f, 0.f, 0.f, thickness));
    EXPECT_TRUE(s.bsdf.is_delta());
    const Vec3 wo = s.dir(0);
    const double F = fr_dielectric(1.f, 1.5f);
    const double k = 2 * std::sqrt(0.5) / std::sqrt(0.5);  // reflectance 0.5 -> eta 1, k 2
    const double R = fr_complex(1.f, {float(1 / 1.5), float(k / 1.5)});
    const double T2 = std::exp(-2.0 * thickness);
    const double expected = F + sqr(1 - F) * R * T2 / (1 - F * R * T2);
    for (auto mode : kModes) {
      Pcg32 rng(5, 6);
      const int n = 20000;
      double sum = 0;
      for (int i = 0; i < n; ++i) {
        const float uc = rng.next_float();
        const auto smp = s.bsdf.sample(wo, uc, rng.next_2d(), mode);
        if (!smp) continue;
        EXPECT_TRUE(smp->is_specular());
        EXPECT_NEAR(dot(smp->wi, kTilted.n), 1.f, 1e-5f);
        sum += smp->f.g * s.bsdf.abs_cos(smp->wi) / smp->pdf;
      }
      // The weights are F-or-not choices of weight ~1 and the walk's products: binomial-like.
      EXPECT_NEAR(sum / n, expected, 4 * std::sqrt(expected * (1 - expected) / n) + 1e-3)
          << thickness;
    }
    EXPECT_TRUE(s.bsdf.f(wo, s.dir(30, 2.f), kRadiance).is_black());
  }
  EXPECT_NEAR(fr_complex(1.f, {1.f, 2.f}), 0.5f, 1e-5f);  // the bare metal
}

TEST(CoatedConductor, EnergyAtMostOneAndSamplesConsistentWithF) {
  for (float coat : {0.f, 0.3f})
    for (float theta : {10.f, 50.f, 80.f, 140.f}) {
      SCOPED_TRACE(testing::Message() << "coat roughness " << coat << " theta " << theta);
      Surface s(coated_conductor(0.95f, coat, 0.3f));
      EXPECT_FALSE(s.bsdf.is_delta());
      const Vec3 wo = s.dir(theta);
      Pcg32 rng(23, 24);
      const int n = 40000;
      double total = 0, non_specular = 0;
      for (int i = 0; i < n; ++i) {
        const float uc = rng.next_float();
        const auto smp = s.bsdf.sample(wo, uc, rng.next_2d(), kRadiance);
        if (!smp) continue;
        EXPECT_TRUE(smp->pdf_is_proportional);
        EXPECT_FALSE(smp->is_transmission());
        const double w = smp->f.g * s.bsdf.abs_cos(smp->wi) / smp->pdf;
        total += w;
        if (!smp->is_specular()) non_specular += w;
      }
      total /= n;
      non_specular /= n;
      // A rough metal under glass traps what it scatters beyond the critical angle, which
      // returns to the metal again and again: 0.61-0.71 here where the bare metal reflects
      // 0.79-0.83 (an index-matched coat gives the bare metal back: the next test).
      EXPECT_LE(total, 1.0 + 1e-2);
      EXPECT_GT(total, 0.4);
      // f() estimates the same BSDF's non-delta part (with pbrt-v4's mismatched MIS weight for a
      // rough coat, which makes it a few percent brighter; see CoatedDiffuse).
      const double integral = test::integrate_sphere(
          [&](Vec3 wi) { return double(s.bsdf.f(wo, wi, kRadiance).g * s.bsdf.abs_cos(wi)); }, 128,
          256);
      if (coat == 0) {
        EXPECT_NEAR(integral, non_specular, 0.1 * non_specular + 0.01);
      } else {
        EXPECT_GT(integral, 0.95 * non_specular);
        EXPECT_LT(integral, 1.15 * non_specular + 0.01);
      }
      EXPECT_LE(integral, 1.0 + 2e-2);
    }
}

TEST(CoatedConductor, IndexMatchedThinCoatIsTheBareMetal) {
  // With a coat of the surrounding medium's index (and no thickness to absorb) the layered
  // walk must reproduce the conductor alone, rough or smooth: this checks the walk's handling
  // of the metal base, the conductor's lobes restricted to reflection, and the eta / k scaling.
  for (float metal : {0.f, 0.1f, 0.3f})
    for (float theta : {10.f, 50.f, 80.f}) {
      SCOPED_TRACE(testing::Message() << "metal roughness " << metal << " theta " << theta);
      CoatedConductorParams p;
      p.reflectance = constant(0.95f);
      p.interface_eta = 1.0001f;
      p.thickness = 1e-5f;
      p.max_depth = 100;
      p.remap_roughness = false;
      ConductorParams c;
      c.reflectance = constant(0.95f);
      c.remap_roughness = false;
      if (metal > 0) {
        p.conductor_u_roughness = p.conductor_v_roughness = constant(metal);
        c.u_roughness = c.v_roughness = constant(metal);
      }
      Surface coated(make_coated_conductor(p)), bare(make_conductor(c));
      const Vec3 wo = coated.dir(theta);
      const int n = 100000;
      const WeightStats a = sample_weights(coated.bsdf, wo, kRadiance, n);
      const WeightStats b = sample_weights(bare.bsdf, wo, kRadiance, n);
      EXPECT_NEAR(a.mean, b.mean, 0.01);
    }
}

TEST(CoatedConductor, StochasticEvaluationIsDeterministicAndTwoSided) {
  const MaterialPtr m = coated_conductor(0.8f, 0.1f, 0.2f);
  Surface a(m), b(m);
  Pcg32 rng(8, 10);
  for (int i = 0; i < 200; ++i) {
    const Vec3 wo = kTilted.to_world(sample_uniform_sphere(rng.next_2d()));
    const Vec3 wi = kTilted.to_world(sample_uniform_sphere(rng.next_2d()));
    for (auto mode : kModes) {
      const Rgb fa = a.bsdf.f(wo, wi, mode);
      EXPECT_EQ(fa, b.bsdf.f(wo, wi, mode));
      EXPECT_EQ(a.bsdf.pdf(wo, wi, mode), b.bsdf.pdf(wo, wi, mode));
      EXPECT_TRUE(fa.is_finite());
      if (dot(wo, kTilted.n) * dot(wi, kTilted.n) > 0) {
        EXPECT_GE(a.bsdf.pdf(wo, wi, mode), 0.1f * kInv4Pi);
      } else {
        EXPECT_TRUE(fa.is_black());  // a metal base transmits nothing
      }
    }
  }
}

}  // namespace
}  // namespace caustica
