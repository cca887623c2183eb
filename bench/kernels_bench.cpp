// Microbenchmarks of the hot kernels (Google Benchmark). Build with
//   cmake -S . -B build-bench -G Ninja -DCMAKE_BUILD_TYPE=Release -DCAUSTICA_BUILD_BENCH=ON
//   ninja -C build-bench caustica_bench && build-bench/bench/caustica_bench
//   --benchmark_repetitions=5
// Google Benchmark prints the machine (CPUs, caches, load) with the results; report medians.
#include <benchmark/benchmark.h>

#include "core/rng.h"
#include "core/warp.h"
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

}  // namespace

BENCHMARK(BM_DiffuseSample);
BENCHMARK(BM_RoughConductorSample);
BENCHMARK(BM_DielectricSample);
BENCHMARK(BM_RoughConductorEval);
BENCHMARK(BM_LightSampleLi);
BENCHMARK(BM_IntersectIncoherent);
