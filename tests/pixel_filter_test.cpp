// Pixel filters (render/pixel_filter.h): each integrates to its integral, samples offsets with
// density |f| / integral |f|, keeps the box of radius 1/2 bit-identical to the uniform jitter,
// and renders an edge as the step convolved with the filter, through camera samples (pt),
// splats (lt) and their MIS combination (bpt) alike. Also: the pbrt loader reads PixelFilter.
#include "film/pixel_filter.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <functional>
#include <vector>

#include "core/rng.h"
#include "geometry/texture.h"
#include "integrators/path_tracer.h"
#include "io/builtin_scenes.h"
#include "io/scene_builder.h"
#include "lights/lights.h"
#include "materials/materials.h"
#include "pbrt_test_util.h"
#include "test_scenes.h"

namespace caustica {
namespace {

std::vector<PixelFilterParams> all_filters() {
  std::vector<PixelFilterParams> out;
  for (PixelFilterKind k :
       {PixelFilterKind::Box, PixelFilterKind::Gaussian, PixelFilterKind::Triangle,
        PixelFilterKind::Mitchell, PixelFilterKind::Lanczos}) {
    out.push_back(PixelFilterParams::defaults(k));
    PixelFilterParams odd = PixelFilterParams::defaults(k);  // unequal, non-default radii
    odd.radius = {odd.radius.x * 0.7f, odd.radius.y * 1.3f};
    out.push_back(odd);
  }
  return out;
}

std::string describe(const PixelFilterParams& p) {
  return std::string(pixel_filter_name(p.kind)) + " r=(" + std::to_string(p.radius.x) + ", " +
         std::to_string(p.radius.y) + ")";
}

// Midpoint quadrature of g over [-r.x, r.x] x [-r.y, r.y] on an n x n grid, in double.
double integrate_support(Vec2 r, int n, const std::function<double(Vec2)>& g) {
  double sum = 0;
  const double hx = 2.0 * r.x / n, hy = 2.0 * r.y / n;
  for (int j = 0; j < n; ++j)
    for (int i = 0; i < n; ++i)
      sum += g({float(-r.x + (i + 0.5) * hx), float(-r.y + (j + 0.5) * hy)});
  return sum * hx * hy;
}

TEST(PixelFilter, IntegralMatchesQuadratureOfEvaluate) {
  for (const PixelFilterParams& p : all_filters()) {
    const PixelFilter filter(p);
    const double quad = integrate_support(filter.radius(), 2048,
                                          [&](Vec2 o) { return double(filter.evaluate(o)); });
    EXPECT_NEAR(filter.integral(), quad, 2e-4 * quad) << describe(p);
  }
  // Closed forms at pbrt-v4's defaults: box 1, triangle r^4 = 16, mitchell r^2 / 4 = 1,
  // gaussian (erf(3 / sqrt 2) - 3 g(1.5))^2.
  const double g15 = std::exp(-4.5) / std::sqrt(2 * M_PI * 0.25);
  const double gauss = std::pow(std::erf(3 / std::sqrt(2.0)) - 3 * g15, 2);
  EXPECT_FLOAT_EQ(PixelFilter(PixelFilterParams::defaults(PixelFilterKind::Box)).integral(), 1.f);
  EXPECT_FLOAT_EQ(PixelFilter(PixelFilterParams::defaults(PixelFilterKind::Triangle)).integral(),
                  16.f);
  EXPECT_FLOAT_EQ(PixelFilter(PixelFilterParams::defaults(PixelFilterKind::Mitchell)).integral(),
                  1.f);
  EXPECT_NEAR(PixelFilter(PixelFilterParams::defaults(PixelFilterKind::Gaussian)).integral(), gauss,
              1e-6);
}

TEST(PixelFilter, EvaluateFollowsPbrtV4Definitions) {
  const PixelFilter gauss(PixelFilterParams::defaults(PixelFilterKind::Gaussian));
  const double g0 = 1 / std::sqrt(2 * M_PI * 0.25), g15 = std::exp(-4.5) * g0;
  EXPECT_NEAR(gauss.evaluate({0, 0}), (g0 - g15) * (g0 - g15), 1e-6);
  EXPECT_EQ(gauss.evaluate({1.5f, 0}), 0.f);  // pbrt-v4 subtracts g(r): zero at the radius
  const PixelFilter mitchell(PixelFilterParams::defaults(PixelFilterKind::Mitchell));
  EXPECT_NEAR(mitchell.evaluate({0, 0}), std::pow((6 - 2 / 3.0) / 6, 2), 1e-6);
  EXPECT_LT(mitchell.evaluate({1.5f, 0}), 0.f);  // the negative lobe
  const PixelFilter sinc(PixelFilterParams::defaults(PixelFilterKind::Lanczos));
  EXPECT_NEAR(sinc.evaluate({0, 0}), 1.0, 1e-6);
  EXPECT_NEAR(sinc.evaluate({1, 0}), 0.0, 1e-6);  // sinc(1) = 0
  EXPECT_LT(sinc.evaluate({1.5f, 0}), 0.f);
  const PixelFilter tri(PixelFilterParams::defaults(PixelFilterKind::Triangle));
  EXPECT_FLOAT_EQ(tri.evaluate({0.5f, -1}), 1.5f * 1.f);
}

// Bin masses of a separable density g(x, y) = g_x(x) g_y(y) >= 0 on a bins x bins grid over the
// support, normalised to 1: products of the axes' bin masses, each by a 4096-point midpoint rule
// per bin (fine enough that the table's jumps cost < 1e-4 of a bin's mass).
std::vector<double> bin_masses(Vec2 r, int bins, const std::function<double(Vec2)>& g) {
  auto axis = [&](bool x_axis) {
    const float radius = x_axis ? r.x : r.y;
    std::vector<double> m(bins, 0.0);
    double total = 0;
    constexpr int kSub = 4096;
    for (int b = 0; b < bins; ++b) {
      for (int i = 0; i < kSub; ++i) {
        const float t = -radius + 2 * radius * (b + (i + 0.5f) / kSub) / bins;
        m[b] += g(x_axis ? Vec2{t, 0} : Vec2{0, t});
      }
      total += m[b];
    }
    for (double& v : m) v /= total;
    return m;
  };
  const std::vector<double> mx = axis(true), my = axis(false);
  std::vector<double> out(bins * bins);
  for (int by = 0; by < bins; ++by)
    for (int bx = 0; bx < bins; ++bx) out[by * bins + bx] = mx[bx] * my[by];
  return out;
}

// Pearson's statistic of observed counts against expected masses, bins expecting fewer than 5
// pooled, as the Wilson-Hilferty z (standard normal under the null hypothesis).
double chi2_z(const std::vector<double>& observed, const std::vector<double>& mass, double n,
              std::string* detail) {
  double chi2 = 0, pooled_e = 0, pooled_o = 0;
  int dof = -1;
  for (size_t b = 0; b < mass.size(); ++b) {
    const double e = mass[b] * n;
    if (e < 5) {
      pooled_e += e;
      pooled_o += observed[b];
      continue;
    }
    chi2 += sqr(observed[b] - e) / e;
    ++dof;
  }
  if (pooled_e >= 5) {
    chi2 += sqr(pooled_o - pooled_e) / pooled_e;
    ++dof;
  }
  const double k = dof;
  *detail = "chi2 " + std::to_string(chi2) + " dof " + std::to_string(dof);
  return (std::cbrt(chi2 / k) - (1 - 2 / (9 * k))) / std::sqrt(2 / (9 * k));
}

// sample() draws offsets with the density it reports (chi-square against at().pdf on a 24 x 24
// grid, 600k samples, Wilson-Hilferty z < 4: p < 3e-5), and that density is |f| / integral |f|:
// exactly for box and triangle (the same chi-square against |evaluate|), within a total
// variation distance of 0.04 for the tabulated kinds: pbrt-v4's table of 16 cells per pixel
// differs from f by |f'| h / 2 at worst, about |f'| h / 4 on average (measured 0.025 to 0.032,
// as the sum over the axes, which bounds the 2D distance).
TEST(PixelFilter, SampledOffsetsFollowAbsoluteFilter) {
  constexpr int kBins = 24, kSamples = 600000;
  for (const PixelFilterParams& p : all_filters()) {
    const PixelFilter filter(p);
    const Vec2 r = filter.radius();
    std::vector<double> observed(kBins * kBins, 0.0);
    Pcg32 rng(5, 17);
    double weight_sum = 0;
    int pdf_mismatch = 0;
    for (int i = 0; i < kSamples; ++i) {
      const FilterSample s = filter.sample(rng.next_2d());
      ASSERT_TRUE(s.offset.x >= -r.x && s.offset.x < r.x && s.offset.y >= -r.y && s.offset.y < r.y)
          << describe(p);
      const int bx = std::min(kBins - 1, int((s.offset.x + r.x) / (2 * r.x) * kBins));
      const int by = std::min(kBins - 1, int((s.offset.y + r.y) / (2 * r.y) * kBins));
      observed[by * kBins + bx] += 1;
      weight_sum += s.weight;
      const FilterSample again = filter.at(s.offset);
      if (std::abs(again.pdf - s.pdf) > 1e-4f * s.pdf || again.weight != s.weight) ++pdf_mismatch;
    }
    // Offsets exactly on a table cell boundary may round into the neighbour: allow a handful.
    EXPECT_LE(pdf_mismatch, 5) << describe(p) << ": at() disagrees with sample()";
    // E[weight] = integral f / integral f = 1; |weight| <= integral |f| / integral f (1.27 for
    // the sinc), so 600k samples give a standard error below 2e-3.
    EXPECT_NEAR(weight_sum / kSamples, 1.0, 8e-3) << describe(p);

    std::string detail;
    const double z_pdf =
        chi2_z(observed, bin_masses(r, kBins, [&](Vec2 o) { return double(filter.at(o).pdf); }),
               kSamples, &detail);
    EXPECT_LT(z_pdf, 4.0) << describe(p) << " against at().pdf: " << detail;

    // Total variation between the pdf and |f| / integral |f|, per axis (10^5-point rule each).
    auto axis_tv = [&](bool x_axis) {
      const float radius = x_axis ? r.x : r.y;
      auto point = [&](float t) { return x_axis ? Vec2{t, 0} : Vec2{0, t}; };
      const int n = 100000;
      double norm_pdf = 0, norm_f = 0, tv = 0;
      std::vector<double> pdf(n), f(n);
      for (int i = 0; i < n; ++i) {
        const float t = -radius + 2 * radius * (i + 0.5f) / n;
        norm_pdf += pdf[i] = filter.at(point(t)).pdf;
        norm_f += f[i] = std::abs(filter.evaluate(point(t)));
      }
      for (int i = 0; i < n; ++i) tv += std::abs(pdf[i] / norm_pdf - f[i] / norm_f);
      return tv / 2;
    };
    const double tv = axis_tv(true) + axis_tv(false);
    const bool exact = p.kind == PixelFilterKind::Box || p.kind == PixelFilterKind::Triangle;
    EXPECT_LT(tv, exact ? 1e-5 : 0.04) << describe(p);
    double z_f = 0;
    if (exact) {
      z_f = chi2_z(observed,
                   bin_masses(r, kBins, [&](Vec2 o) { return std::abs(filter.evaluate(o)); }),
                   kSamples, &detail);
      EXPECT_LT(z_f, 4.0) << describe(p) << " against |f|: " << detail;
    }
    std::printf("[ chi2 ] %-32s z %5.2f against the pdf%s, TV(pdf, |f|) %.1e, mean weight %.4f\n",
                describe(p).c_str(), z_pdf,
                exact ? (", " + std::to_string(z_f).substr(0, 5) + " against |f|").c_str() : "", tv,
                weight_sum / kSamples);
  }
}

// pdf integrates to 1; pdf * weight (what a splat adds per unit value) is f / integral f: exactly
// for box and triangle, up to the table's piecewise-constant step for the others.
TEST(PixelFilter, PdfTimesWeightIsTheNormalisedFilter) {
  for (const PixelFilterParams& p : all_filters()) {
    const PixelFilter filter(p);
    // The pdf is separable: its mass is the product of the axes' masses, each by a 10^6-point
    // midpoint rule (the table's jumps cost it at most ~1e-5).
    auto axis_mass = [&](bool x_axis) {
      const float r = x_axis ? filter.radius().x : filter.radius().y;
      const int n = 1000000;
      double sum = 0;
      for (int i = 0; i < n; ++i) {
        const float t = -r + 2 * r * (i + 0.5f) / n;
        sum += filter.at(x_axis ? Vec2{t, 0} : Vec2{0, t}).pdf;
      }
      return sum * 2 * r / n;
    };
    const double mass = axis_mass(true) * axis_mass(false) / filter.at({0, 0}).pdf;
    EXPECT_NEAR(mass, 1.0, 1e-4) << describe(p);
    const double peak = filter.evaluate({0, 0}) / filter.integral();
    double worst = 0;
    Pcg32 rng(3, 4);
    for (int i = 0; i < 20000; ++i) {
      const Vec2 u = rng.next_2d();
      const Vec2 o{(2 * u.x - 1) * filter.radius().x, (2 * u.y - 1) * filter.radius().y};
      const FilterSample s = filter.at(o);
      worst = std::max(worst,
                       double(std::abs(s.pdf * s.weight - filter.evaluate(o) / filter.integral())));
    }
    const bool exact = p.kind == PixelFilterKind::Box || p.kind == PixelFilterKind::Triangle;
    // The table steps by about 1/16 pixel, so |f_table - f| <= max |f'| / 32 per axis: measured
    // up to 0.061 of the peak (mitchell squeezed to r = 1.4); 1e-6 of it for the exact kinds.
    std::printf("[ table ] %-32s max |pdf w - f / integral f| = %.2e of the peak\n",
                describe(p).c_str(), worst / peak);
    EXPECT_LT(worst, (exact ? 1e-6 : 0.08) * peak) << describe(p);
  }
}

// A light-tracing connection is skipped where no candidate pixel takes splats
// (BidirIntegrator::splat_can_land): every pixel whose support holds the raster point must be a
// candidate, also at pixel edges, at the film's border and outside it.
TEST(PixelFilter, CandidatePixelsHoldEveryPixelWhoseSupportHoldsTheRasterPoint) {
  const int w = 9, h = 7;
  for (const PixelFilterParams& p : all_filters()) {
    const PixelFilter filter(p);
    Pcg32 rng(11, 12);
    int missed = 0, splats = 0;
    for (int i = 0; i < 4000; ++i) {
      Vec2 raster{-1.5f + 12.f * rng.next_float(), -1.5f + 10.f * rng.next_float()};
      if (i % 4 == 0) raster.x = std::round(raster.x);  // on pixel edges
      if (i % 4 == 1) raster = {raster.x, std::nextafter(std::round(raster.y), 0.f)};
      const PixelFilter::PixelRange range = filter.candidate_pixels(raster, w, h);
      for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x) {
          const Vec2 offset{raster.x - (float(x) + 0.5f), raster.y - (float(y) + 0.5f)};
          if (!(filter.at(offset).pdf > 0)) continue;
          ++splats;
          missed += x < range.x0 || x > range.x1 || y < range.y0 || y > range.y1;
        }
    }
    EXPECT_EQ(missed, 0) << describe(p);
    EXPECT_GT(splats, 1000) << describe(p);
  }
}

TEST(PixelFilter, BoxOfHalfAPixelIsTheUniformJitterBitForBit) {
  const PixelFilter box;  // the default: box, radius 1/2
  Pcg32 rng(1, 2);
  for (int i = 0; i < 100000; ++i) {
    const int x = int(rng.next_bounded(4096)), y = int(rng.next_bounded(4096));
    const Vec2 u = rng.next_2d();
    const CameraFilterSample s = box.sample_camera(x, y, u);
    ASSERT_EQ(s.raster.x, x + u.x);
    ASSERT_EQ(s.raster.y, y + u.y);
    ASSERT_EQ(s.pdf, 1.f);
    ASSERT_EQ(s.weight, 1.f);
  }
  // A splat lands in exactly the pixel that contains it, with weight and pdf 1 (also on pixel
  // borders, which belong to the pixel on their right / below).
  for (int i = 0; i < 100000; ++i) {
    Vec2 r{64 * rng.next_float(), 48 * rng.next_float()};
    if (i % 10 == 0) r.x = std::floor(r.x);
    int count = 0;
    box.for_each_pixel(r, 64, 48, [&](int x, int y, const FilterSample& s) {
      ++count;
      EXPECT_EQ(x, int(r.x));
      EXPECT_EQ(y, int(r.y));
      EXPECT_EQ(s.pdf, 1.f);
      EXPECT_EQ(s.weight, 1.f);
    });
    ASSERT_EQ(count, 1) << r.x << " " << r.y;
  }
}

// The box-filtered pt image equals the loop caustica ran before pixel filters existed: raster
// point x + u, the same random stream, the film's double-precision average.
TEST(PixelFilter, BoxFilteredImageEqualsThePlainJitterLoop) {
  auto scene = make_builtin_scene("cornell-glass", 24, 20);
  IntegratorSettings settings;
  settings.seed = 5;
  const RenderResult r = test::render_with(*scene, "pt", 2, settings);
  PathTracer pt(settings);
  ScratchArena arena;
  const Camera& camera = scene->camera();
  for (int y = 0; y < camera.height(); ++y)
    for (int x = 0; x < camera.width(); ++x) {
      double sum[3] = {0, 0, 0};
      for (uint32_t it = 0; it < 2; ++it) {
        Pcg32 rng = Pcg32::for_sample(uint64_t(y) * camera.width() + x, it, settings.seed);
        const Vec2 jitter = rng.next_2d();
        const Vec2 lens = rng.next_2d();
        arena.reset();
        const Rgb L = pt.radiance(*scene, camera.generate_ray({x + jitter.x, y + jitter.y}, lens),
                                  rng, arena);
        for (int c = 0; c < 3; ++c) sum[c] += L[c];
      }
      for (int c = 0; c < 3; ++c)
        ASSERT_EQ(r.image.at(x, y)[c], float(sum[c] * 0.5)) << x << " " << y << " channel " << c;
    }
}

// ---- the edge image -------------------------------------------------------------------------

// A diffuse quad (albedo 0.8) facing a pinhole camera, lit head-on by a distant light of
// radiance pi: radiance 0.8 wherever it is seen. It covers the view (and the filter's margin)
// left of a vertical edge at world x = 0.031, and nothing is right of it: the image is a step.
constexpr float kPlateau = 0.8f;
constexpr int kWidth = 24, kHeight = 48;

std::unique_ptr<Scene> edge_scene(const PixelFilterParams& filter) {
  SceneBuilder b;
  TriangleMesh quad;
  const float x0 = -1.4f, x1 = 0.031f, y0 = -2.5f, y1 = 2.5f;
  // Wound so that the face normal is -z, toward the camera.
  quad.positions = {{x0, y0, 0}, {x0, y1, 0}, {x1, y1, 0}, {x1, y0, 0}};
  quad.indices = {0, 1, 3, 1, 2, 3};
  b.add_mesh(quad, make_diffuse(make_constant_texture(Rgb(kPlateau))));
  b.add_light(make_distant_light({0, 0, 1}, Rgb(kPi)));
  CameraParams c;
  c.width = kWidth;
  c.height = kHeight;
  c.fov_degrees = 30;  // spans x: half-width 4 tan 15 = 1.07 at the quad
  c.camera_to_world = Transform::look_at({0, 0, -4}, {0, 0, 0}, {0, 1, 0}).inverse();
  c.filter = filter;
  b.set_camera(c);
  return b.build("edge");
}

// The profile across the edge: per column, the mean over rows and independent renders, and its
// standard error from the spread of the renders' means (rows are not independent: splats and
// the filter spread over neighbouring rows). Light tracing traces 16 light paths per pixel and
// iteration so that its noise is near pt's.
struct Profile {
  std::vector<double> mean, se;
};

Profile render_profile(const Scene& scene, const std::string& integrator, int renders, int spp) {
  std::vector<std::vector<double>> per_render(renders, std::vector<double>(kWidth, 0.0));
  for (int k = 0; k < renders; ++k) {
    IntegratorSettings s;
    s.seed = 1000 + k;
    s.max_depth = 1;
    s.bidir.light_paths = 16 * kWidth * kHeight;
    const RenderResult r = test::render_with(scene, integrator, spp, s);
    EXPECT_EQ(r.nonfinite, 0u);
    for (int y = 0; y < kHeight; ++y)
      for (int x = 0; x < kWidth; ++x) per_render[k][x] += r.image.at(x, y).average() / kHeight;
  }
  Profile p{std::vector<double>(kWidth), std::vector<double>(kWidth)};
  for (int x = 0; x < kWidth; ++x) {
    double s = 0, s2 = 0;
    for (int k = 0; k < renders; ++k) {
      s += per_render[k][x];
      s2 += sqr(per_render[k][x]);
    }
    p.mean[x] = s / renders;
    p.se[x] = std::sqrt(std::max(0.0, s2 / renders - sqr(p.mean[x])) / (renders - 1));
  }
  return p;
}

// Mitchell & Netravali's cubic (1988, eq. 8) at B = C = 1/3, support [-2, 2].
double mitchell_cubic(double x) {
  x = std::abs(x);
  if (x < 1) return (7 * x * x * x - 12 * x * x + 16.0 / 3) / 6;
  if (x < 2) return (-7.0 / 3 * x * x * x + 12 * x * x - 20 * x + 32.0 / 3) / 6;
  return 0;
}

// Fraction of the filter's x-marginal left of t, integral_{-r}^{t} f_x / integral f_x, from the
// closed forms (independent of pixel_filter.cpp; mitchell by Simpson's rule).
double step_response(const PixelFilterParams& p, double t) {
  const double r = p.radius.x;
  if (t <= -r) return 0;
  if (t >= r) return 1;
  if (p.kind == PixelFilterKind::Mitchell) {
    // f_x(x) = k(2x / r) integrates to r / 2.
    const int n = 2000;
    const double h = (t + r) / n;
    double sum = mitchell_cubic(-2) + mitchell_cubic(2 * t / r);
    for (int i = 1; i < n; ++i) sum += (i % 2 ? 4 : 2) * mitchell_cubic(2 * (-r + i * h) / r);
    return sum * h / 3 / (r / 2);
  }
  if (p.kind == PixelFilterKind::Triangle)
    return t <= 0 ? sqr(t + r) / (2 * r * r) : 1 - sqr(r - t) / (2 * r * r);
  if (p.kind == PixelFilterKind::Box) return (t + r) / (2 * r);
  // gaussian minus its value at r: [Phi-part - g(r) (t + r)] / [erf part - 2 r g(r)]
  const double s = p.sigma, gr = std::exp(-r * r / (2 * s * s)) / std::sqrt(2 * M_PI * s * s);
  const double cdf =
      0.5 * (std::erf(t / (s * std::sqrt(2.0))) + std::erf(r / (s * std::sqrt(2.0))));
  return (cdf - gr * (t + r)) / (std::erf(r / (s * std::sqrt(2.0))) - 2 * r * gr);
}

// Expected column values: plateau * P(sample on the bright side of the edge).
std::vector<double> expected_profile(const Scene& scene, const PixelFilterParams& p) {
  const float edge = scene.camera().project({0.031f, 0, 0})->x;
  const bool bright_left = scene.camera().project({-0.5f, 0, 0})->x < edge;
  std::vector<double> e(kWidth);
  for (int x = 0; x < kWidth; ++x) {
    const double left = step_response(p, edge - (x + 0.5));
    e[x] = kPlateau * (bright_left ? left : 1 - left);
  }
  return e;
}

// Every column within 5 standard errors (32 independent renders each: Student t with 31 dof,
// p ~ 2e-5 per column) of the step convolved with the filter; the table's bias (< 1e-3 of the
// plateau) is added to the bound.
void expect_profile(const Profile& got, const std::vector<double>& want, const std::string& what) {
  constexpr double kTableBias = 1e-3 * kPlateau;
  double worst_z = 0, worst = 0, largest_se = 0;
  for (int x = 0; x < kWidth; ++x) {
    const double error = std::abs(got.mean[x] - want[x]);
    EXPECT_LE(error, 5 * got.se[x] + kTableBias)
        << what << " column " << x << " (" << got.mean[x] << " +- " << got.se[x] << ", want "
        << want[x] << ")";
    worst = std::max(worst, error);
    largest_se = std::max(largest_se, got.se[x]);
    // What the bound compares with 5: the error beyond the table's bias, in standard errors
    // (columns the filter keeps wholly on one side are noise-free in pt and have none).
    if (got.se[x] > 1e-7)
      worst_z = std::max(worst_z, std::max(0.0, error - kTableBias) / got.se[x]);
  }
  std::printf(
      "[ edge ] %-15s max |profile - step * filter| = %.4f, beyond the table bias %.2f "
      "standard errors (largest standard error %.4f)\n",
      what.c_str(), worst, worst_z, largest_se);
}

TEST(PixelFilterEdge, CameraSamplesAndSplatsConvolveTheStepWithTheFilter) {
  for (PixelFilterKind kind : {PixelFilterKind::Gaussian, PixelFilterKind::Triangle}) {
    const PixelFilterParams params = PixelFilterParams::defaults(kind);
    auto scene = edge_scene(params);
    const std::vector<double> want = expected_profile(*scene, params);
    const std::string name = pixel_filter_name(kind);
    const Profile pt = render_profile(*scene, "pt", 32, 8);
    const Profile lt = render_profile(*scene, "lt", 32, 8);
    expect_profile(pt, want, name + " pt");
    expect_profile(lt, want, name + " lt");
    // Splats and camera samples agree with each other, not just with the analytic profile.
    double worst = 0;
    for (int x = 0; x < kWidth; ++x) {
      const double se = std::sqrt(sqr(pt.se[x]) + sqr(lt.se[x]));
      if (se > 1e-6) worst = std::max(worst, std::abs(pt.mean[x] - lt.mean[x]) / se);
      EXPECT_NEAR(pt.mean[x], lt.mean[x], 5 * se + 1e-6) << name << " column " << x;
    }
    std::printf("[ edge ] %-15s max |pt - lt| = %.2f standard errors\n", name.c_str(), worst);
    // The test has power: a box filter's profile would be many standard errors away, for
    // the camera samples and for the splats.
    const std::vector<double> box =
        expected_profile(*scene, PixelFilterParams::defaults(PixelFilterKind::Box));
    double separation_pt = 0, separation_lt = 0;
    for (int x = 0; x < kWidth; ++x) {
      separation_pt = std::max(separation_pt, std::abs(box[x] - want[x]) / (pt.se[x] + 1e-9));
      separation_lt = std::max(separation_lt, std::abs(box[x] - want[x]) / (lt.se[x] + 1e-9));
    }
    std::printf(
        "[ edge ] %-15s a box filter would be %.1f (pt) and %.1f (lt) standard errors off\n",
        name.c_str(), separation_pt, separation_lt);
    EXPECT_GT(separation_pt, 10) << name;
    EXPECT_GT(separation_lt, 10) << name;
  }
}

// bpt combines the two by MIS: the camera technique's pdf and the splat's must carry the same
// filter density for the weights to sum to one, else the edge is biased.
TEST(PixelFilterEdge, BidirectionalMisKeepsTheConvolvedStep) {
  const PixelFilterParams params = PixelFilterParams::defaults(PixelFilterKind::Gaussian);
  auto scene = edge_scene(params);
  expect_profile(render_profile(*scene, "bpt", 32, 8), expected_profile(*scene, params),
                 "gaussian bpt");
}

// Negative lobes: the mitchell filter's signed camera weights and signed splats both ring at
// the edge (overshoot and undershoot of 1.6% of the step) as the convolution says.
TEST(PixelFilterEdge, NegativeLobesRingInCameraSamplesAndSplatsAlike) {
  const PixelFilterParams params = PixelFilterParams::defaults(PixelFilterKind::Mitchell);
  auto scene = edge_scene(params);
  const std::vector<double> want = expected_profile(*scene, params);
  EXPECT_LT(*std::min_element(want.begin(), want.end()), -0.01 * kPlateau);
  expect_profile(render_profile(*scene, "pt", 32, 8), want, "mitchell pt");
  expect_profile(render_profile(*scene, "lt", 32, 8), want, "mitchell lt");
}

// ---- the pbrt loader --------------------------------------------------------------------------

std::string scene_with(const std::string& filter_line) {
  return filter_line + "\n" + test::with_camera("Shape \"sphere\"\n");
}

TEST(PbrtPixelFilter, IsReadWithPbrtV4Defaults) {
  auto none = test::load_text(scene_with(""));
  EXPECT_EQ(none->camera().pixel_filter().kind, PixelFilterKind::Gaussian);  // pbrt-v4's default
  EXPECT_EQ(none->camera().pixel_filter().radius.x, 1.5f);
  EXPECT_EQ(none->camera().pixel_filter().sigma, 0.5f);

  auto mitchell = test::load_text(scene_with(
      "PixelFilter \"mitchell\" \"float xradius\" 1.5 \"float B\" 0.5 \"float C\" 0.25"));
  const PixelFilterParams& m = mitchell->camera().pixel_filter();
  EXPECT_EQ(m.kind, PixelFilterKind::Mitchell);
  EXPECT_EQ(m.radius.x, 1.5f);
  EXPECT_EQ(m.radius.y, 2.f);
  EXPECT_EQ(m.b, 0.5f);
  EXPECT_EQ(m.c, 0.25f);
  EXPECT_EQ(test::count_containing(test::captured_warnings(), "PixelFilter"), 0);

  auto sinc = test::load_text(scene_with("PixelFilter \"sinc\" \"float tau\" 2"));
  EXPECT_EQ(sinc->camera().pixel_filter().kind, PixelFilterKind::Lanczos);
  EXPECT_EQ(sinc->camera().pixel_filter().radius.y, 4.f);
  EXPECT_EQ(sinc->camera().pixel_filter().tau, 2.f);
  auto gauss = test::load_text(scene_with("PixelFilter \"gaussian\" \"float sigma\" 0.3"));
  EXPECT_EQ(gauss->camera().pixel_filter().sigma, 0.3f);
  auto tri = test::load_text(scene_with("PixelFilter \"triangle\" \"float yradius\" 1"));
  EXPECT_EQ(tri->camera().pixel_filter().kind, PixelFilterKind::Triangle);
  EXPECT_EQ(tri->camera().pixel_filter().radius.x, 2.f);
  EXPECT_EQ(tri->camera().pixel_filter().radius.y, 1.f);
  auto box = test::load_text(scene_with("PixelFilter \"box\""));
  EXPECT_EQ(box->camera().pixel_filter().kind, PixelFilterKind::Box);
  EXPECT_EQ(box->camera().pixel_filter().radius.x, 0.5f);

  // A parameter the filter does not have warns, as everywhere in the loader.
  test::load_text(scene_with("PixelFilter \"box\" \"float sigma\" 2"));
  EXPECT_EQ(test::count_containing(test::captured_warnings(), "\"float sigma\""), 1);
}

TEST(PbrtPixelFilter, SharedCornellBoxGetsItsTriangleOfRadiusOne) {
  auto scene = load_pbrt(std::string(CAUSTICA_SCENES) + "/pbrt-v4/cornell-box/scene-v4.pbrt",
                         test::capture_warning);
  const PixelFilterParams& f = scene->camera().pixel_filter();
  EXPECT_EQ(f.kind, PixelFilterKind::Triangle);
  EXPECT_EQ(f.radius.x, 1.f);
  EXPECT_EQ(f.radius.y, 1.f);
}

TEST(PbrtPixelFilter, UnknownNamesAndBadValuesAreLocatedErrors) {
  EXPECT_EQ(test::load_error(scene_with("PixelFilter \"blackman\"")),
            "test.pbrt:1:13: error: unknown pixel filter \"blackman\" (expected box, gaussian, "
            "mitchell, sinc (lanczos), triangle)");
  EXPECT_NE(test::load_error(scene_with("PixelFilter \"box\" \"float xradius\" 0"))
                .find("test.pbrt:1:19: error: \"float xradius\""),
            std::string::npos);
  EXPECT_NE(test::load_error(scene_with("PixelFilter \"gaussian\" \"float sigma\" -1"))
                .find("\"float sigma\": must be positive"),
            std::string::npos);
}

// glTF scenes too: neither sets CameraParams::filter, whose default is this box.
TEST(PbrtPixelFilter, BuiltinScenesKeepTheBox) {
  auto scene = make_builtin_scene("cornell", 8, 8);
  EXPECT_EQ(scene->camera().pixel_filter().kind, PixelFilterKind::Box);
  EXPECT_EQ(scene->camera().pixel_filter().radius.x, 0.5f);
}

}  // namespace
}  // namespace caustica
