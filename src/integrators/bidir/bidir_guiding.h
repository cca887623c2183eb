// What guided-bpt and guided-vcm learn while rendering: two SD-trees (guiding/guiding_field.h,
// Müller et al. 2017), one of the incident radiance, which guides camera subpaths, and one of
// the incident importance, which guides light subpaths (Vorba et al. 2014, "On-line Learning of
// Parametric Mixture Models for Light Transport Simulation": photons train the radiance,
// "importons" the importance). Both come from the subpaths the core traces anyway. By default
// (GuidingSettings::radiance_records, importance_records) each field learns from the subpaths it
// guides, as guided-pt: a guided camera vertex records the radiance its later vertices found
// through every technique, a guided light vertex the importance its later lens connections
// found (subpath_records.h); those records carry the product f |cos| L too, so the BSDF
// selection probability is learned. Vorba et al.'s records, still available:
//  - radiance: every stored light vertex (a photon) is a sample of the flux arriving at its
//    position from its wo, weighted by its throughput: splatted at wo with the luminance of
//    its throughput;
//  - importance: every non-delta camera vertex is a sample of the importance arriving from its
//    wo (toward the camera), weighted by the camera subpath's throughput, except where the
//    camera subpath had only specular bounces before it: importance straight from the lens is
//    light tracing's to connect to, and a light subpath scattered toward a pinhole finds nothing.
//    Learned from those vertices too, the guides of visible surfaces pointed at the camera
//    (door-ajar 320x240, 48 spp, guided-vcm relMSE 0.91 -> 0.80; vcm 1.04).
// The sums over a directional quadrant are flux estimates, as Müller's L_i / pdf records are;
// they need no backward pass over the paths. At most kMaxRecords per field and iteration are
// kept (every k-th vertex, weighted by k, the k-th shifted with the iteration), which bounds the
// memory of the records independently of the resolution.
//
// Schedule: guided-pt's (guiding/training_schedule.h): two unguided iterations, doubling
// training passes that sample with what the passes before them learned, then rendering passes
// that record nothing; with a time budget, trials decide whether guiding pays for its time
// (variance x seconds of a guided and an unguided pass of equal length), and an unguided
// render is plain bpt / vcm. The passes' variances come from the integrator's per-pass pixel
// moments (an InverseVarianceCombiner fed with each iteration's pixel values, splats included).
// Every iteration is an unbiased estimate; the image is the plain average of all iterations.
//
// Sides: both fields are sided (GuidingField::side_class: the geometric normal facing the side a
// record arrived on), so that the two faces of a thin wall, or a floor and the wall it meets, do
// not share a distribution; a subpath arriving on one side samples that side's (vertex_guides.h).
//
// Where a vertex is guided: where the BSDF has no delta or near-specular lobe and is not
// stochastic (as guided-pt), once its leaf has learned something. The probability of sampling
// the BSDF instead of the guide is learned from the subpaths' own records, fixed at 0.5 for
// photons and importons (no product estimate) or by --guiding-bsdf-fraction. Memory: each field
// gets half of --guiding-max-mb.
//
// Determinism: the light vertices' records go to the field in the vertices' order, the camera
// vertices' in (pixel, depth) order (pixel_records.h), both independent of threads.
#pragma once

#include <tbb/enumerable_thread_specific.h>

#include <array>
#include <nlohmann/json.hpp>
#include <span>
#include <vector>

#include "guiding/guiding_field.h"
#include "guiding/pixel_records.h"
#include "guiding/training_schedule.h"
#include "image/inverse_variance.h"
#include "integrators/bidir/light_vertex.h"
#include "integrators/bidir/subpath_records.h"
#include "integrators/bidir/technique_probabilities.h"
#include "integrators/bidir/vertex_guides.h"

namespace caustica {
class Scene;
}

namespace caustica::bidir {

class BidirGuiding {
 public:
  static constexpr size_t kMaxRecords = size_t(1) << 18;

  BidirGuiding() = default;
  // spp, seconds: the render's budget (Integrator::set_budget).
  void prepare(const Bounds3& bounds, GuidingSettings settings, uint64_t pixels, int spp,
               double seconds);
  bool enabled() const { return enabled_; }

  // Before iteration i, `elapsed` seconds into the render.
  // light_paths: the iteration's light subpaths (0: as many as pixels).
  void begin_iteration(uint32_t iteration, double elapsed, uint64_t light_paths = 0);
  // After iteration i and its pixel moments in `passes`: when the next iteration starts a new
  // pass, the schedule weighs the pass that ended (its variance: the last of `passes`), its
  // fields learn what it recorded, and true is returned (the caller then ends the pass in
  // `passes`). At the end of a pass, not the start of the next, so that what the next
  // iteration does is known before it starts (teaches()).
  bool end_pass_after(uint32_t iteration, double elapsed, const InverseVarianceCombiner& passes);
  // Whether the iterations from the next on teach the fields or decide the schedule (training
  // and trial passes): every MPI rank renders them (Integrator::shared_iteration).
  bool teaches() const { return enabled_ && !schedule_.final_pass(); }
  // The guides at a vertex at p with geometric normal ng and this BSDF (empty where it is not
  // guided).
  VertexGuides at(Vec3 p, Vec3 ng, const Bsdf& bsdf) const;
  // The learned probabilities of the deterministic techniques at a vertex at p with geometric
  // normal ng (technique_probabilities.h); empty (all 1) outside guided and training passes.
  // guides: the vertex's own (at p and ng), whose radiance leaves are shared, or nullptr.
  VertexProbabilities probabilities_at(Vec3 p, Vec3 ng,
                                       const VertexGuides* guides = nullptr) const {
    VertexProbabilities v;
    if (!reduces() && !counts_techniques()) return v;
    v.fields = this;
    v.p = p;
    v.ng = ng;
    if (guides && guides->fields && guide_camera_) v.guides = guides;
    return v;
  }
  // Whether a probability can be below 1 in this pass (it samples the fields, and a leaf
  // learned one).
  bool reduces() const {
    return enabled_ && (reduced_[0] || reduced_[1] || reduced_[2]) && schedule_.guided();
  }
  // Whether this pass counts the techniques taken and what they saw (training passes).
  bool counts_techniques() const { return enabled_ && count_techniques_ && schedule_.learning(); }
  // A technique taken at `leaf` (VertexProbabilities::leaf_toward) saw something (unoccluded,
  // a non-zero contribution) or not; from any thread (counts_techniques() only).
  void count_technique(GuidingField::Technique t, uint32_t leaf, bool seen) const;
  // The leaf of the radiance field holding p on the side n points to.
  uint32_t probability_leaf(Vec3 p, Vec3 n) const {
    return radiance_.leaf_at(p, GuidingField::side_class(n));
  }
  // Whether technique t is taken at its learned probabilities in this pass (else they are 1 and
  // nothing is looked up for it).
  bool reduces(GuidingField::Technique t) const { return reduces() && reduced_[t]; }
  // Whether a vertex with this BSDF is guided once its leaf has learned (no delta, near-specular
  // or stochastic lobes: those sample the BSDF alone, as in guided-pt).
  static bool guidable(const Bsdf& bsdf);

  // Camera vertices of `pixel` are recorded this iteration (one pixel in k, while training).
  bool records_pixel(uint64_t pixel) const {
    return guide_light_ && importance_from_camera_ && schedule_.learning() &&
           (pixel + iteration_) % camera_stride_ == 0;
  }
  // The importance field learns from light subpath `path` this iteration.
  bool records_importance_path(uint64_t path) const {
    return guide_light_ && importance_from_light_ && schedule_.learning() &&
           (path + iteration_) % light_stride_ == 0;
  }
  // A light vertex of `path` received `importance` along its wi (subpath_records.h).
  void record_light_importance(uint64_t path, const SubpathRecords::Vertex& v, float importance,
                               float product) const {
    record_subpath_vertex(importance_, light_records_, path, light_stride_, v, importance, product);
  }
  // The camera subpath of `pixel` reached a non-delta vertex at p (geometric normal ng),
  // arriving along -wo with throughput beta (from estimate(): any thread).
  void record_camera_vertex(uint64_t pixel, int depth, Vec3 p, Vec3 ng, Vec3 wo, Rgb beta) const;
  // The radiance field learns from the camera subpaths of `pixel` this iteration
  // (GuidingSettings::RadianceRecords; the same pixels as record_camera_vertex's).
  bool records_radiance_pixel(uint64_t pixel) const {
    return guide_camera_ && radiance_from_camera_ && schedule_.learning() &&
           (pixel + iteration_) % camera_stride_ == 0;
  }
  // A camera vertex of `pixel` received `radiance` along its wi, with `product` for the BSDF
  // selection (subpath_records.h).
  void record_camera_radiance(uint64_t pixel, const SubpathRecords::Vertex& v, float radiance,
                              float product) const {
    record_subpath_vertex(radiance_, camera_radiance_records_, pixel, camera_stride_, v, radiance,
                          product);
  }
  // After the camera pass: learns from this iteration's light vertices (their normals from the
  // scene) and camera records (training passes only).
  void end_iteration(const Scene& scene, const std::vector<LightVertex>& light_vertices);

  // What was learned at a few pixels (guide_views.h): the radiance camera subpaths see and the
  // importance light subpaths arriving there would be guided by. Kept for report().
  void make_views(const Scene& scene);
  void report(nlohmann::json& stats) const;
  const GuidingField& radiance() const { return radiance_; }
  const GuidingField& importance() const { return importance_; }

 private:
  friend struct VertexGuides;
  // A record of `value` arriving at p (geometric normal ng) along -wo.
  // A subpath's own record (subpath_records.h): one record of `stride`, keyed by the subpath
  // (pixel or light path) and the vertex's depth, in the subpath's slot of `records`.
  void record_subpath_vertex(const GuidingField& field, const PixelRecords& records,
                             uint64_t subpath, uint64_t stride, const SubpathRecords::Vertex& v,
                             float value, float product) const;
  GuidingRecord record_at(const GuidingField& field, uint64_t key, Vec3 p, Vec3 ng, Vec3 wo,
                          float value) const;
  static void learn(GuidingField& field, std::span<const std::span<const GuidingRecord>> runs,
                    uint64_t stride);

  bool enabled_ = false;
  bool count_techniques_ = false;  // GuidingSettings::nee_floor < 1
  // Per technique: its probabilities below 1 apply (they cover at least kMinReducedShare of its
  // attempts in the last training pass that counted it; else every probability is 1).
  static constexpr double kMinReducedShare = 0.1;
  bool reduced_[GuidingField::kTechniques] = {false, false, false};
  // Per thread, per technique: counts[2 leaf] taken, counts[2 leaf + 1] seeing something.
  using TechniqueCounts = std::array<std::vector<uint32_t>, GuidingField::kTechniques>;
  mutable tbb::enumerable_thread_specific<TechniqueCounts> technique_counts_;
  bool guide_camera_ = true, guide_light_ = true;  // GuidingSettings::guide_*_paths
  bool radiance_from_photons_ = true, radiance_from_camera_ = false;    // ::radiance_records
  bool importance_from_camera_ = true, importance_from_light_ = false;  // ::importance_records
  uint64_t light_stride_ = 1;
  GuidingField radiance_, importance_;
  TrainingSchedule schedule_;
  uint32_t iteration_ = 0;
  uint64_t camera_stride_ = 1;
  uint64_t radiance_records_ = 0, importance_records_ = 0;
  uint64_t pixels_ = 0;
  PixelRecords camera_records_;           // slot: pixel / camera_stride_
  PixelRecords camera_radiance_records_;  // the same slots
  PixelRecords light_records_;            // slot: light path / light_stride_
  std::vector<GuidingRecord> merged_;     // the light vertices' records, in their order
  nlohmann::json views_;
};

}  // namespace caustica::bidir
