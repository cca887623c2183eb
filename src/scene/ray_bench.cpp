#include "scene/ray_bench.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_reduce.h>

#include <chrono>
#include <cmath>

#include "core/frame.h"
#include "core/rng.h"
#include "core/warp.h"

namespace caustica {

namespace {

constexpr size_t kGrain = 4096;  // rays per task: enough to hide the scheduling

// A ray from si in a cosine-distributed direction on the side of si.wo.
Ray cosine_ray(const SurfaceInteraction& si, Vec2 u) {
  const Vec3 n = face_forward(si.ng, si.wo);
  const Vec3 d = Frame::from_normal(n).to_world(sample_cosine_hemisphere(u));
  return si.spawn_ray(d);
}

double seconds_since(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

}  // namespace

std::vector<Ray> make_incoherent_rays(const Scene& scene, size_t count, uint64_t seed) {
  const Camera& camera = scene.camera();
  std::vector<Ray> rays;
  rays.reserve(count);
  Pcg32 rng = Pcg32::for_sample(0, 0, hash_combine(seed, 0xbe7c4ull));
  // Give up after many misses in a row (a camera that sees nothing).
  for (size_t misses = 0; rays.size() < count && misses < 1000 + 4 * count;) {
    const Vec2 raster(rng.next_float() * float(camera.width()),
                      rng.next_float() * float(camera.height()));
    SurfaceInteraction first;
    if (!scene.intersect(camera.generate_ray(raster, rng.next_2d()), &first)) {
      ++misses;
      continue;
    }
    const Ray bounce = cosine_ray(first, rng.next_2d());
    rays.push_back(cosine_ray(first, rng.next_2d()));
    SurfaceInteraction second;
    if (rays.size() < count && scene.intersect(bounce, &second))
      rays.push_back(cosine_ray(second, rng.next_2d()));
  }
  return rays;
}

double RayBenchResult::mixed_rays_per_second(double occlusion_fraction) const {
  if (!(intersect_rays_per_second > 0) || !(occluded_rays_per_second > 0)) return 0;
  return 1.0 / ((1 - occlusion_fraction) / intersect_rays_per_second +
                occlusion_fraction / occluded_rays_per_second);
}

RayBenchResult measure_raw_rays(const Scene& scene, const std::vector<Ray>& rays) {
  RayBenchResult r;
  r.rays = rays.size();
  if (rays.empty()) return r;
  std::vector<float> t_hit(rays.size());
  const tbb::blocked_range<size_t> all(0, rays.size(), kGrain);

  auto start = std::chrono::steady_clock::now();
  r.hits = tbb::parallel_reduce(
      all, uint64_t(0),
      [&](const tbb::blocked_range<size_t>& b, uint64_t hits) {
        return hits +
               scene.intersect_raw(rays.data() + b.begin(), b.size(), t_hit.data() + b.begin());
      },
      std::plus<uint64_t>());
  r.intersect_rays_per_second = double(rays.size()) / seconds_since(start);

  // Shadow rays: the same rays, each stopping just short of what it hit (outside the timing).
  std::vector<Ray> shadow(rays);
  for (size_t i = 0; i < shadow.size(); ++i)
    if (std::isfinite(t_hit[i])) shadow[i].tmax = t_hit[i] * (1 - 1e-4f);
  start = std::chrono::steady_clock::now();
  r.occluded = tbb::parallel_reduce(
      all, uint64_t(0),
      [&](const tbb::blocked_range<size_t>& b, uint64_t n) {
        return n + scene.occluded_raw(shadow.data() + b.begin(), b.size());
      },
      std::plus<uint64_t>());
  r.occluded_rays_per_second = double(rays.size()) / seconds_since(start);
  return r;
}

}  // namespace caustica
