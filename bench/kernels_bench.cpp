// Microbenchmarks of the hot kernels (Google Benchmark). Build with
//   cmake -S . -B build-bench -G Ninja -DCMAKE_BUILD_TYPE=Release -DCAUSTICA_BUILD_BENCH=ON
//   ninja -C build-bench caustica_bench && build-bench/bench/caustica_bench
//   --benchmark_repetitions=5
// Google Benchmark prints the machine (CPUs, caches, load) with the results; report medians.
#include <benchmark/benchmark.h>
#include <tbb/global_control.h>

#include "core/rng.h"
#include "core/warp.h"
#include "integrators/bidir/hash_grid.h"
#include "io/builtin_scenes.h"
#include "lights/light.h"
#include "lights/light_sampler.h"
#include "materials/material.h"
#include "materials/materials.h"
#include "scene/scene.h"

using namespace caustica;

namespace {

const Scene& glass_scene() {
  static auto scene = make_builtin_scene("cornell-glass", 512, 512);
  return *scene;
}

SurfaceInteraction hit_of(const Scene& scene, Vec2 raster) {
  SurfaceInteraction si;
  scene.intersect(scene.camera().generate_ray(raster, {0.5f, 0.5f}), &si);
  return si;
}

template <typename MakeMaterial>
void bench_bsdf_sample(benchmark::State& state, MakeMaterial make) {
  const MaterialPtr m = make();
  SurfaceInteraction si;
  si.shading = Frame::from_normal({0, 0, 1});
  si.ng = {0, 0, 1};
  ScratchArena arena;
  Pcg32 rng(1, 1);
  const Vec3 wo = normalize(Vec3(0.3f, 0.2f, 0.9f));
  for (auto _ : state) {
    arena.reset();
    const Bsdf b = m->bsdf(si, arena);
    auto s = b.sample(wo, rng.next_float(), rng.next_2d(), TransportMode::Radiance);
    benchmark::DoNotOptimize(s);
  }
}

void BM_DiffuseSample(benchmark::State& st) {
  bench_bsdf_sample(st, [] { return make_diffuse(make_constant_texture(Rgb(0.5f))); });
}
void BM_RoughConductorSample(benchmark::State& st) {
  bench_bsdf_sample(st, [] {
    ConductorParams p;
    p.reflectance = make_constant_texture(Rgb(0.9f));
    p.u_roughness = p.v_roughness = make_constant_texture(Rgb(0.2f));
    return make_conductor(p);
  });
}
void BM_DielectricSample(benchmark::State& st) {
  bench_bsdf_sample(st, [] { return make_dielectric(DielectricParams{}); });
}

void BM_RoughConductorEval(benchmark::State& state) {
  ConductorParams p;
  p.reflectance = make_constant_texture(Rgb(0.9f));
  p.u_roughness = p.v_roughness = make_constant_texture(Rgb(0.2f));
  const MaterialPtr m = make_conductor(p);
  SurfaceInteraction si;
  si.shading = Frame::from_normal({0, 0, 1});
  si.ng = {0, 0, 1};
  ScratchArena arena;
  Pcg32 rng(2, 2);
  const Vec3 wo = normalize(Vec3(0.3f, 0.2f, 0.9f));
  for (auto _ : state) {
    arena.reset();
    const Bsdf b = m->bsdf(si, arena);
    const Vec3 wi = sample_cosine_hemisphere(rng.next_2d());
    benchmark::DoNotOptimize(b.f(wo, wi, TransportMode::Radiance));
    benchmark::DoNotOptimize(b.pdf(wo, wi, TransportMode::Radiance));
  }
}

void BM_LightSampleLi(benchmark::State& state) {
  const Scene& scene = glass_scene();
  const SurfaceInteraction si = hit_of(scene, {256, 400});
  Pcg32 rng(3, 3);
  for (auto _ : state) {
    float pmf;
    const Light* l = scene.light_sampler().sample(rng.next_float(), &pmf);
    benchmark::DoNotOptimize(l->sample_li(si.p, rng.next_2d()));
  }
}

void BM_IntersectIncoherent(benchmark::State& state) {
  const Scene& scene = glass_scene();
  const SurfaceInteraction si = hit_of(scene, {256, 400});
  Pcg32 rng(4, 4);
  const Frame f = Frame::from_normal(si.ng);
  for (auto _ : state) {
    SurfaceInteraction out;
    benchmark::DoNotOptimize(
        scene.intersect(si.spawn_ray(f.to_world(sample_cosine_hemisphere(rng.next_2d()))), &out));
  }
  state.SetItemsProcessed(state.iterations());
}

// About as many light vertices as one iteration of vcm on cornell-glass 512x512 (550k), spread
// over the faces of a box of the same size, and its merge radius.
const std::vector<bidir::LightVertex>& box_photons() {
  static const std::vector<bidir::LightVertex> vertices = [] {
    std::vector<bidir::LightVertex> v(550000);
    Pcg32 rng(5, 5);
    for (bidir::LightVertex& x : v) {
      const int face = int(rng.next_float() * 6) % 6;
      const Vec2 u = rng.next_2d();
      float p[3] = {2 * u.x - 1, 2 * u.y - 1, 2 * u.x - 1};
      p[face % 3] = face < 3 ? -1.f : 1.f;
      p[(face + 1) % 3] = 2 * u.x - 1;
      p[(face + 2) % 3] = 2 * u.y - 1;
      x = {};
      for (int a = 0; a < 3; ++a) x.position[a] = p[a];
    }
    return v;
  }();
  return vertices;
}
constexpr float kBoxMergeRadius = 0.0067f;

// Argument: threads.
void BM_HashGridBuild(benchmark::State& state) {
  tbb::global_control limit(tbb::global_control::max_allowed_parallelism, size_t(state.range(0)));
  const auto& vertices = box_photons();
  bidir::HashGrid grid;
  for (auto _ : state) grid.build(vertices, kBoxMergeRadius);
  state.SetItemsProcessed(state.iterations() * int64_t(vertices.size()));
}

void BM_HashGridQuery(benchmark::State& state) {
  const auto& vertices = box_photons();
  bidir::HashGrid grid;
  grid.build(vertices, kBoxMergeRadius);
  Pcg32 rng(6, 6);
  for (auto _ : state) {
    float sum = 0;
    const Vec3 p = vertices[size_t(rng.next_float() * float(vertices.size()))].p();
    grid.for_each_near(p, vertices, [&](uint32_t, Vec3 q) { sum += q.x; });
    benchmark::DoNotOptimize(sum);
  }
  state.SetItemsProcessed(state.iterations());
}

}  // namespace

BENCHMARK(BM_HashGridBuild)->Arg(1)->Arg(2)->UseRealTime()->Unit(benchmark::kMillisecond);
BENCHMARK(BM_HashGridQuery);
BENCHMARK(BM_DiffuseSample);
BENCHMARK(BM_RoughConductorSample);
BENCHMARK(BM_DielectricSample);
BENCHMARK(BM_RoughConductorEval);
BENCHMARK(BM_LightSampleLi);
BENCHMARK(BM_IntersectIncoherent);
