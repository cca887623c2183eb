// The raw Embree bound of a scene: how many incoherent rays per second Embree alone traces on
// this scene's BVH, with no shading, no hit records and no ray counting. A renderer's rays/s
// divided by this bound says how much of its time goes to everything but traversal
// (`caustica bench`). It lives in the scene layer because nothing above may call Embree.
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

#include "scene/scene.h"

namespace caustica {

// Incoherent rays as a path tracer's bounces make them: surface points found by camera rays
// through random pixels and by one cosine-distributed bounce from each of those, and from every
// point a ray in a cosine-distributed direction about its normal, on the side it was reached
// from. Deterministic for a seed; fewer than `count` only if the camera sees nothing.
std::vector<Ray> make_incoherent_rays(const Scene& scene, size_t count, uint64_t seed);

struct RayBenchResult {
  size_t rays = 0;
  double intersect_rays_per_second = 0;  // rtcIntersect1
  double occluded_rays_per_second = 0;   // rtcOccluded1
  // Results, so that the work is observable: closest-hit rays that hit, and occlusion rays
  // found occluded (about 0, as each ends before its hit).
  uint64_t hits = 0, occluded = 0;
  // Rays per second of Embree alone for a mix with this fraction of occlusion rays: the total
  // time is the sum of each kind's count over its rate.
  double mixed_rays_per_second(double occlusion_fraction) const;
};

// Traces the rays once with rtcIntersect1, then with rtcOccluded1 each ending just before its
// closest hit (a shadow ray between two mutually visible points: a full traversal, no early
// exit), in parallel over the threads the caller's TBB limit allows.
RayBenchResult measure_raw_rays(const Scene& scene, const std::vector<Ray>& rays);

}  // namespace caustica
