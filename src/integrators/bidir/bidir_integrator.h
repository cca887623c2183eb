// The bidirectional family as one core with technique switches (Georgiev et al. 2012, "Light
// Transport Simulation with Vertex Connection and Merging", and the tech report "Implementing
// Vertex Connection and Merging"):
//
//   lt   light subpaths only; every non-delta light vertex is connected to the camera. Camera
//        rays add only the emission they see directly or through delta-only chains (paths no
//        light-tracing technique can make), so D S+ E paths (caustics seen in mirrors) are black.
//   bpt  + camera subpaths with NEE, connections to the vertices of one light subpath, emitter
//        hits, all combined by MIS.
//   ppm  camera subpaths stop at their first non-delta vertex and merge there with every light
//        vertex within r (Hachisuka et al. 2008); emission through delta-only chains counted once.
//   bpm  merging at every camera vertex, MIS over merges (no connections).
//   vcm  bpt + bpm with MIS over all (merge acceptance p_acc = pi r^2 per light path).
//   adaptive-vcm  vcm whose light-path count, connections per camera vertex and per-pixel
//        merging are chosen while rendering by efficiency-aware MIS (adaptive_plan.h).
//   guided-bpt, guided-vcm  bpt and vcm whose camera subpaths are guided by the incident
//        radiance and whose light subpaths by the incident importance, both learned while
//        rendering, with the MIS densities of the guided mixtures (bidir_guiding.h).
//
// Per iteration: N light subpaths (settings.bidir.light_paths, 0 = one per pixel) are traced in
// chunks whose size depends on N only (at most 1024 paths; at least 64 chunks when N allows),
// their non-delta vertices stored in 40 bytes each (light_vertex.h) and concatenated in chunk
// order; light-tracing splats are recorded per chunk and applied in chunk order; a hash grid
// over the vertices serves merging; then one camera subpath per pixel.
// Every random stream is keyed by (path or pixel, iteration, seed): images are bit-identical for
// any thread count.
//
// Settings: max_depth (scattering vertices, pbrt-v4); mis (the family defaults to balance: the
// power heuristic is used only when settings.mis says --mis power was asked for);
// radius (initial merge radius r_1, default 0.003 * the scene's bounding-sphere radius, as
// SmallVCM) shrinking as r_i = r_1 i^((alpha - 1) / 2) for the 1-based iteration i;
// radius_alpha (0.75); techniques_dir (one EXR per technique; their sum is the image).
#pragma once

#include <memory>

#include "integrators/integrator.h"

namespace caustica {

enum class BidirAlgorithm { LightTracing, Bpt, Ppm, Bpm, Vcm, AdaptiveVcm, GuidedBpt, GuidedVcm };

std::unique_ptr<Integrator> make_bidir_integrator(BidirAlgorithm algorithm,
                                                  const IntegratorSettings& settings);

}  // namespace caustica
