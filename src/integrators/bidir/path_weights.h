// The MIS weights the renderer gives one explicit path under each technique that can make it,
// computed by replaying both subpaths through the renderer's own update and weight code
// (techniques.h, with light sums stored and reloaded through the 40-byte light vertex). It is
// the hook for the tests' brute-force MIS oracle; the renderer never calls it.
#pragma once

#include <vector>

#include "core/arena.h"
#include "geometry/interaction.h"
#include "integrators/bidir/bidir_guiding.h"
#include "integrators/bidir/bidir_integrator.h"

namespace caustica {
class Scene;
class Light;
}  // namespace caustica

namespace caustica::bidir {

// A path x0 ... xk, light end first: x0 on `light` (for infinite lights only `emit_dir`
// matters), x1 ... x(k-1) surface hits, xk the lens point.
struct ExplicitPath {
  const Light* light = nullptr;
  Vec3 light_point, light_normal;
  Vec3 emit_dir;  // propagation direction of infinite lights (unused for finite ones)
  std::vector<SurfaceInteraction> surfaces;
  Vec3 lens_point;
};

struct TechniqueWeight {
  bool merge = false;
  int s = 0, t = 0;  // light / camera vertices (a merge counts the merged vertex on both sides)
  float weight = 0;
  // The weight under the photon-mapping estimator of a pixel (TechniqueTerms::stop_own): 1 for
  // the one technique that makes the path there, 0 for the others.
  float stop_weight = 0;
  // That estimator's density relative to all techniques' (its n' p' over sum_k n_k p_k): the
  // same from every technique of the path, as the proxy correction needs (adaptive_plan.h).
  float stop_ratio = 0;
};

// Weights of every technique of `algorithm` (Bpt, Bpm or Vcm) able to produce the path
// (delta vertices are recognised by Bsdf::is_delta; mixed BSDFs are treated as non-delta).
// raster_density: the pixel filter's density of the path's raster offset from the centre of the
// pixel it is estimated for (camera_pdf_w; 1 for the box of radius 1/2).
// connections: light subpaths each camera vertex connects to (their count in the weights);
// pixel_merges: false for a pixel of adaptive-vcm that does not merge.
// guiding: the learned fields of guided-bpt / guided-vcm (their vertices' densities are the
// guided mixtures'); nullptr: unguided.
// merge_mis_scale: --merge-mis-scale, the factor of the merges' count N pi r^2 in the weights.
// correlation_aware: --merge-mis correlation-aware (vcm).
std::vector<TechniqueWeight> production_weights(
    const Scene& scene, BidirAlgorithm algorithm, MisHeuristic heuristic, float light_paths,
    float radius, const ExplicitPath& path, ScratchArena& arena, float raster_density = 1.f,
    int connections = 1, bool pixel_merges = true, const BidirGuiding* guiding = nullptr,
    float merge_mis_scale = 1.f, bool correlation_aware = false);

}  // namespace caustica::bidir
