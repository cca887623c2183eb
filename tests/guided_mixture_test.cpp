// The mixtures of BSDF sampling and a learned distribution, guided-pt's (guided_mixture.h) and
// guided-bpt/guided-vcm's (bidir/vertex_guides.h, both transport modes): for any BSDF they
// guide, layered (stochastic) ones included, the mean sample weight over the mixture is the
// BSDF's directional albedo, the same number its own sample weights estimate.
#include "integrators/guided_mixture.h"

#include <gtest/gtest.h>

#include <cmath>

#include "chi2.h"
#include "core/arena.h"
#include "core/rng.h"
#include "core/warp.h"
#include "geometry/interaction.h"
#include "integrators/bidir/vertex_guides.h"
#include "materials/materials.h"

namespace caustica {
namespace {

const Frame kFrame(Vec3(0, 1, 0), Vec3(0, 0, 1), Vec3(1, 0, 0));

struct Surface {
  ScratchArena arena;
  Bsdf bsdf;
  explicit Surface(const MaterialPtr& m) {
    SurfaceInteraction si;
    si.p = Vec3(0.25f, 0.5f, 0.75f);
    si.uv = Vec2(0.3f, 0.6f);
    si.shading = kFrame;
    si.ng = kFrame.n;
    si.wo = kFrame.n;
    bsdf = m->bsdf(si, arena);
  }
};

// A learned distribution that is not the BSDF's: most of its energy in a cone around a grazing
// direction of the upper hemisphere, some spread over the whole sphere.
DirectionalQuadtree cone_guide() {
  DirectionalQuadtree t;
  Pcg32 rng(7, 8);
  const Vec3 axis = kFrame.to_world(normalize(Vec3(0.8f, 0.1f, 0.3f)));
  const Frame cone = Frame::from_normal(axis);
  for (int i = 0; i < 20000; ++i) {
    const Vec2 u = rng.next_2d();
    const Vec3 w = i % 4 == 0 ? sample_uniform_sphere(u)
                              : cone.to_world(sample_uniform_cone(u, std::cos(0.3f)));
    t.record(direction_to_square(w), 1.0);
  }
  t.propagate();
  size_t budget = 100000;
  DirectionalQuadtree g = t.refined(0.01, 12, &budget, 1.0);
  g.propagate();
  return g;
}

struct Mean {
  double mean = 0, standard_error = 0;
};

template <typename F>
Mean mean_of(int n, F&& sample) {
  double sum = 0, sum2 = 0;
  for (int i = 0; i < n; ++i) {
    const double x = sample(i);
    sum += x;
    sum2 += x * x;
  }
  const double m = sum / n;
  return {m, std::sqrt(std::max(0.0, sum2 / n - m * m) / n)};
}

// f_brighter: the BSDF is a layered one with a rough coat, whose f() pbrt-v4 computes with an MIS
// weight of mismatched densities, a few percent brighter than its sample() (see the CoatedDiffuse
// tests). The guide technique evaluates f(), the BSDF technique samples, so the mixture's mean
// lies between the two albedos instead of on the sampled one.
void expect_unbiased(const MaterialPtr& material, const char* name, bool f_brighter = false) {
  Surface s(material);
  ASSERT_TRUE(guidable_bsdf(s.bsdf)) << name;
  const DirectionalQuadtree guide = cone_guide();
  for (float theta : {15.f, 60.f}) {
    const float t = radians(theta);
    const Vec3 wo = kFrame.to_world(Vec3(std::sin(t) * 0.6f, std::sin(t) * 0.8f, std::cos(t)));
    const int n = 80000;
    // The albedo each mode's sample weights estimate (the adjoint's differs).
    Mean albedos[2];
    for (TransportMode mode : {TransportMode::Radiance, TransportMode::Importance}) {
      Pcg32 rng_b(1, 2);
      albedos[int(mode)] = mean_of(n, [&](int) {
        const float uc = rng_b.next_float();
        const auto smp = s.bsdf.sample(wo, uc, rng_b.next_2d(), mode);
        return smp ? double(smp->f.g * s.bsdf.abs_cos(smp->wi) / smp->pdf) : 0.0;
      });
    }
    for (float a : {0.25f, 0.7f})
      for (bool bidirectional : {false, true}) {
        Pcg32 rng_m(3, 4);
        Mixture m;  // guided-pt's
        m.guide = &guide;
        m.bsdf_fraction = a;
        m.guidable = true;
        // guided-bpt / guided-vcm's, on the side of wo, for the subpaths of both modes.
        bidir::VertexGuides g;
        g.n = kFrame.n;
        for (int mode = 0; mode < 2; ++mode) {
          g.guides[mode][0] = &guide;
          g.bsdf[mode][0] = a;
        }
        g.resolved = 0b0101;
        const TransportMode mode =
            bidirectional && a > 0.5f ? TransportMode::Importance : TransportMode::Radiance;
        const Mean mixed = mean_of(n, [&](int) {
          const float ut = rng_m.next_float(), uc = rng_m.next_float();
          const Vec2 u = rng_m.next_2d();
          if (bidirectional) {
            const auto smp = bidir::sample_guided(s.bsdf, g, wo, mode, ut, uc, u);
            return smp ? double(smp->weight.g) : 0.0;
          }
          const auto smp = sample_mixture(s.bsdf, wo, m, ut, uc, u);
          return smp ? double(smp->weight.g) : 0.0;
        });
        SCOPED_TRACE(bidirectional ? "bidir::sample_guided" : "sample_mixture");
        const Mean& albedo = albedos[int(mode)];
        const double tolerance =
            4 * std::sqrt(sqr(albedo.standard_error) + sqr(mixed.standard_error)) + 1e-4;
        if (!f_brighter) {
          EXPECT_NEAR(mixed.mean, albedo.mean, tolerance)
              << name << " theta " << theta << " a " << a << " (albedo " << albedo.mean << ")";
          continue;
        }
        const double f_albedo = test::integrate_sphere(
            [&](Vec3 wi) { return double(s.bsdf.f(wo, wi, mode).g * s.bsdf.abs_cos(wi)); }, 256,
            512);
        EXPECT_GT(f_albedo, albedo.mean + tolerance) << name;
        EXPECT_GT(mixed.mean, albedo.mean - tolerance) << name << " theta " << theta << " a " << a;
        EXPECT_LT(mixed.mean, f_albedo + tolerance) << name << " theta " << theta << " a " << a;
      }
  }
}

TEST(GuidedMixture, DiffuseMeanWeightIsTheAlbedo) {
  expect_unbiased(make_diffuse(make_constant_texture(Rgb(0.7f))), "diffuse");
}

TEST(GuidedMixture, LayeredBsdfsAreGuidedWithoutBias) {
  for (float roughness : {0.f, 0.3f}) {
    CoatedDiffuseParams p;
    p.reflectance = make_constant_texture(Rgb(0.8f));
    p.u_roughness = p.v_roughness = make_constant_texture(Rgb(roughness));
    p.remap_roughness = false;
    expect_unbiased(make_coated_diffuse(p),
                    roughness > 0 ? "rough coated diffuse" : "smooth coated diffuse",
                    /*f_brighter=*/roughness > 0);
  }
  CoatedConductorParams c;
  c.reflectance = make_constant_texture(Rgb(0.9f));
  c.interface_u_roughness = c.interface_v_roughness = make_constant_texture(Rgb(0.1f));
  c.conductor_u_roughness = c.conductor_v_roughness = make_constant_texture(Rgb(0.3f));
  c.remap_roughness = false;
  expect_unbiased(make_coated_conductor(c), "coated conductor");
}

// Without the MIS weights (weighting a layered BSDF's sample by f / (a p~ + (1 - a) p_guide)
// with its approximate pdf()) the mean is off: the test above would catch it.
TEST(GuidedMixture, ApproximateDensityAloneWouldBeBiased) {
  CoatedDiffuseParams p;
  p.reflectance = make_constant_texture(Rgb(0.8f));
  p.u_roughness = p.v_roughness = make_constant_texture(Rgb(0.3f));
  p.remap_roughness = false;
  Surface s(make_coated_diffuse(p));
  const DirectionalQuadtree guide = cone_guide();
  Mixture m;
  m.guide = &guide;
  m.bsdf_fraction = 0.5f;
  const Vec3 wo = kFrame.to_world(normalize(Vec3(0.3f, 0.2f, 1.f)));
  const int n = 200000;
  Pcg32 rng_b(1, 2), rng_m(3, 4);
  const Mean albedo = mean_of(n, [&](int) {
    const float uc = rng_b.next_float();
    const auto smp = s.bsdf.sample(wo, uc, rng_b.next_2d(), TransportMode::Radiance);
    return smp ? double(smp->f.g * s.bsdf.abs_cos(smp->wi) / smp->pdf) : 0.0;
  });
  const Mean naive = mean_of(n, [&](int) {
    const float ut = rng_m.next_float(), uc = rng_m.next_float();
    const Vec2 u = rng_m.next_2d();
    Vec3 wi;
    if (ut >= m.bsdf_fraction) {
      wi = guide.sample(u);
    } else {
      const auto smp = s.bsdf.sample(wo, uc, u, TransportMode::Radiance);
      if (!smp) return 0.0;
      wi = smp->wi;
    }
    const DirectionPdfs d = m.evaluate(s.bsdf, wo, wi);
    return double(s.bsdf.f(wo, wi, TransportMode::Radiance).g * s.bsdf.abs_cos(wi) / m.pdf(d));
  });
  EXPECT_GT(std::abs(naive.mean - albedo.mean),
            6 * std::sqrt(sqr(albedo.standard_error) + sqr(naive.standard_error)))
      << "naive " << naive.mean << " albedo " << albedo.mean;
}

}  // namespace
}  // namespace caustica
