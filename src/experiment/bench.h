// `caustica bench`: what each integrator costs on each scene, next to the raw Embree bound of
// that scene measured in the same run (scene/ray_bench.h).
//
// For every scene, integrator and thread count, `runs` renders of `iterations` iterations each;
// each run first measures the Embree bound at that thread count, then renders, so that the two
// see the same machine load. Reported per thread count are medians over the runs:
//   ms_per_iteration, rays_per_second (caustica's intersect + occluded calls),
//   paths_per_second ((camera paths + light paths) per second; one camera path per pixel),
//   embree_*_rays_per_second and embree_bound_rays_per_second (Embree alone on caustica's mix of
//   closest-hit and occlusion rays), ratio_to_embree (caustica / bound). The bound's rays are
//   incoherent bounce rays; caustica's also include camera rays and shadow rays toward a small
//   light, which traverse less, so the ratio can exceed 1 on a large scene (many-triangles pt):
//   read it as "Embree time share", not as a hard limit,
//   peak_memory_mb (the process's peak resident memory during that render, when Linux lets the
//   peak be reset; else the process's peak so far, and peak_memory_scope says "process"; it
//   includes the scene and the bench's own ray buffers), render_memory_mb (that peak less the
//   resident memory just before the render: what the render itself added);
// and from the integrator's own report: light vertices per iteration and bytes each, light
// vertex and hash grid bytes, hash grid build time. speedup_vs_1_thread = median ms of 1 thread
// / median ms of N threads.
#pragma once

#include <cstdint>
#include <functional>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

namespace caustica {

struct BenchConfig {
  std::vector<std::string> scenes{"cornell-glass"};
  std::vector<std::string> integrators{"pt", "vcm"};
  int width = 0, height = 0;  // 0: the scene's resolution
  int iterations = 4;         // per run
  int runs = 3;               // the median is reported
  std::vector<int> threads{1, 2};
  int max_depth = -1;  // -1: the scene's, else 10
  uint64_t seed = 0;
  size_t bound_rays = size_t(1) << 20;  // rays per Embree-bound measurement
};

// Called after each render with the fraction done and the last render's Mrays/s.
using BenchProgress = std::function<void(double fraction, double mrays_per_second)>;

// Throws std::runtime_error (or the loader's errors) for a scene or integrator it cannot make.
nlohmann::json run_bench(const BenchConfig& config, const BenchProgress& progress = {});

// A plain-text table of a run_bench result, one line per scene, integrator and thread count.
std::string bench_table(const nlohmann::json& result);

}  // namespace caustica
