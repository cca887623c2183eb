// The price of an adaptive-vcm configuration (adaptive_plan.h): microseconds per pixel and
// iteration of each operation, fixed (CostModel's defaults, deterministic) or measured in the
// probes, and what a pixel costs in each PixelMode under a candidate's light paths and
// connections, from the work the probes counted.
#pragma once

#include <nlohmann/json.hpp>

#include "integrators/bidir/adaptive_plan.h"

namespace caustica::bidir {

// The fixed cost model, in microseconds per operation: a least-squares fit of camera-pass and
// light-pass times to the operation counts (statistics "work_per_iteration") of vcm and bpt at
// 1 and 4 connections and 0.25-2 light paths per pixel on door-ajar, cornell-box, veach-bidir
// and water-caustic (1 thread, 2-core x86-64, g++ 12 Release, 2026-11-30; per scene the camera
// vertex ranged 0.6-1.0 us, a connection 0.5-0.7, a light vertex 0.8-2.0). Scenes whose BSDFs
// are expensive to evaluate (coated materials: material-testball fits 2.9 / 8.6 / 4.4) are
// mispriced; --adaptive-costs measured times the probes instead. Used whenever costs are not
// measured, so that a render at fixed spp and seed chooses the same configurations on every
// machine and for every thread count.
struct CostModel {
  double camera_vertex = 0.75;  // trace, BSDF, NEE with its shadow ray
  // A camera vertex of a path-tracing iteration, which pt's own estimator renders (no MIS sums
  // for other techniques): fitted so that the predicted bpt / pt cost ratio matches the
  // measured one (1 thread, 160 px wide, 16 spp, 2026-11-30: door-ajar 5.3, cornell-box 4.1,
  // veach-bidir 5.0, mis-plates 1.75, coffee 2.7; at 0.75 the model predicted 1.25x less).
  double path_tracing_vertex = 0.6;
  // A light path: its start on a light and its rays (0.35), and each vertex it stores: traced,
  // its BSDF, stored (0.41); plus the vertex's connection to the lens (0.44), which only pixels
  // that take light-tracing splats pay (a light subpath skips the lens connections no pixel
  // takes: BidirIntegrator::splat_can_land). Until 2026-12-06 a light path was priced by its
  // vertices alone (0.66 each): open scenes, whose light paths mostly leave the scene after
  // at most one vertex, were priced at half of what their light passes took (sun-glass 0.58x,
  // material-spheres 0.63x, mis-plates 0.59x), closed ones at up to 1.6x (door-ajar). Fitted to
  // the light passes of photon mapping everywhere (no lens connections) at 1-2 light paths per
  // pixel on the 14 scenes of the equal-time table, minimising relative error (2 threads,
  // 2026-12-06, docs/adaptive-vcm.md "A light path's price"): per path 0.345, per vertex 0.406,
  // rms log error 0.42 against 0.76 for the old price (0.79 for the best per vertex alone). What
  // is left (coffee and material-testball 2.1x, water-caustic 2.7x, veach-bidir 1.6x) is not one
  // count: not the light rays that store no vertex, and on veach-bidir not its lamp's material
  // (docs/adaptive-vcm.md, "veach-bidir's light paths").
  double light_path = 0.35;
  double light_vertex = 0.41;
  double lens_connection = 0.44;
  // One light vertex connected to one camera vertex: of a light path drawn at random, and of
  // the pixel's own light path, which costs less. The fit above had one connection, the
  // pixel's own, and four: its slope is the random ones'. Measured 2026-12-04 (door-ajar
  // 160 x 120, 2 threads, adaptive-vcm's core at fixed configurations, thread-microseconds per
  // pixel and iteration from "checks"): 1, 2, 4 connections at one light path per pixel 5.88,
  // 8.78, 14.19, none 3.81, so the first 0.32 us, each further one 0.42-0.45, against a
  // camera vertex of 0.54 (0.45 and 0.6 at this model's 0.75). Priced alike, the model
  // preferred two connections, or none, to one (door-ajar: 1.18x bpt's relMSE over 4 seeds).
  double connection = 0.6;
  double own_connection = 0.45;
  // One range query at up to one light path per pixel; above that its price grows with the
  // light paths (query_price): the grid and the vertices it points to outgrow the caches.
  // door-ajar, as above: a query, the grid's build shared among them included, took 0.19 us
  // at one light path per pixel and 0.43 at two, beside a camera vertex of 0.54 (0.26 and 0.6
  // at this model's 0.75; the fit above gave 0.18, which priced merging at two light paths
  // per pixel at half of what it took).
  double merge_query = 0.25;
  double photon = 0.03;  // one photon gathered
};

// The operation costs: the model, or what the probes measured (seconds summed over threads).
CostModel costs_of(const ProbeWork& w, bool measured);
nlohmann::json to_json(const CostModel& t);

// Per pixel and iteration, from the probes' work (light paths at one per pixel).
struct PixelWork {
  // connections: light vertices connected per pixel with one connection per camera vertex
  // (from the probes', which make two: depth limits and early rejections make it far fewer than
  // vertices x vertices).
  double camera_vertices, connections, light_vertices_per_path, merge_queries, photons;
  double stop_camera_vertices, stop_merge_queries, stop_photons;
};
// Per pixel and iteration: the work `probes` probes counted over `pixels` recorded pixels, each
// camera vertex of which made `probe_connections` connections.
PixelWork pixel_work_of(const ProbeWork& w, double probes, double pixels, int probe_connections);

// One light path's cost (its start and its vertices); with `splats`, the lens connections of its
// vertices too (those a pixel that takes no splat does not cause).
double light_path_cost(const PixelWork& w, const CostModel& t, bool splats);
// A pixel's share of the light paths' cost: the candidate's light paths per pixel at
// light_path_cost.
double light_cost(const AdaptivePlan::Candidate& c, const PixelWork& w, const CostModel& t,
                  bool splats);
// A pixel that path traces: pt's camera vertices, and its share of the light paths (which the
// other pixels use).
double path_tracing_cost(const AdaptivePlan::Candidate& c, const PixelWork& w, const CostModel& t);
// A pixel that runs the bidirectional core (without merging).
double base_cost(const AdaptivePlan::Candidate& c, const PixelWork& w, const CostModel& t);
// What merging adds to it. Photon density grows with the light paths: photons per query scale
// with the factor, and so does a query's price above one light path per pixel
// (CostModel::merge_query).
double merge_cost(const AdaptivePlan::Candidate& c, const PixelWork& w, const CostModel& t);
// A pixel that maps photons alone: its camera vertices up to the first non-delta scattering (no
// next event estimation there: priced as path tracing's, an upper bound), one query there, and
// its share of the light paths.
double stop_cost(const AdaptivePlan::Candidate& c, const PixelWork& w, const CostModel& t);

}  // namespace caustica::bidir
