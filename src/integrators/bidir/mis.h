// MIS weights of the bidirectional family through incremental partial sums, after Georgiev's
// tech report "Implementing Vertex Connection and Merging" (2012), generalised to a sample count
// per technique class, as efficiency-aware MIS needs (Grittmann et al. 2022):
//
//   emitter      the camera subpath hits an emitter (s = 0) or connects to a light sample
//                (s = 1, NEE): one sample each per camera vertex, or none (bpm);
//   light_trace  a light vertex connected to the lens (t = 1): N light paths per pixel; this
//                includes the emission point of an area light itself (s = 1, t = 1), the
//                other way to see a light directly than the camera ray hitting it (s = 0, t = 2);
//   connect      a light vertex connected to a camera vertex (s, t >= 2): c per camera vertex;
//   merge        vertex merging: N pi r^2 per camera vertex (acceptance area x light paths),
//                or 0 in a pixel that does not merge.
//
// The balance heuristic weights technique k of a path by n_k p_k / sum_j n_j p_j. Each subpath
// vertex carries the sums of p_j / p_current over the techniques "behind" it, split by class
// and free of counts (MisSums); a weight combines them with the counts of the iteration and
// pixel (MisCounts) in O(1). Because the split terms of a weight are exposed (TechniqueTerms),
// the same path also gives the weight it *would* have had under other counts: the proxy
// correction factors with which adaptive-vcm estimates the variance of other configurations.
//
// Conventions: every pdf handed in is in solid angle unless its name ends in _a (area measure
// at the point it samples); area conversions use the *geometric* normal (|ng . w|), both here
// and in the tests' brute-force oracle. Delta (specular) bounces report pdf_fwd = pdf_rev and
// only their cosine survives. Russian roulette is left out of the pdfs (the weights still sum to
// one over the techniques; they are just not the exact balance weights of the RR'd estimator).
// The power heuristic squares every ratio and count (mis()).
#pragma once

#include <algorithm>
#include <array>

#include "integrators/integrator.h"

namespace caustica::bidir {

// Technique classes (see above).
enum class TechniqueClass : uint8_t { Emitter, LightTrace, Connect, Merge };

// Samples per pixel and camera vertex of each class; 0 switches a class off.
struct MisCounts {
  float emitter = 1;
  float light_trace = 0;  // N: the light paths of an iteration each reach every pixel
  float connect = 1;
  float merge = 0;  // N pi r^2
  float of(TechniqueClass c) const {
    switch (c) {
      case TechniqueClass::Emitter:
        return emitter;
      case TechniqueClass::LightTrace:
        return light_trace;
      case TechniqueClass::Connect:
        return connect;
      case TechniqueClass::Merge:
        return merge;
    }
    return 0;
  }
};

// Correlation-aware MIS (Grittmann, Georgiev and Slusallek 2021, "Correlation-Aware Multiple
// Importance Sampling for Bidirectional Rendering Algorithms"; vcm --merge-mis correlation-aware).
// The merges of an iteration share its N light subpaths, so a merge at vertex x_i of a path is
// worth fewer than the N pi r^2 independent samples the balance heuristic counts it as. Its
// count is multiplied by c_i = cam_i / (cam_i + light_i - cam_i light_i), at least 1 / N, where
// cam_i is the product over the vertices from the first camera hit to x_i of
// a = min(1, A p_camera(x)) and light_i the product from the emitter to x_i of
// min(1, A p_light(x)): the acceptance probabilities, in a disc of area A = pi r^2, of the
// area densities with which each side samples the vertex (1 for a vertex sampled through a
// delta lobe, for a delta or infinite light's position). c_i needs both products of the whole
// path, which the partial sums cannot carry, so each subpath also keeps its merges one by one
// (CorrelationTrack): a merge's term of MisSums::merge, its own side's product and the product
// of the reverse acceptances behind the subpath's last vertex. A technique completes them with
// the other side's product and the acceptances its connection defines
// (MisRules::correlated_merges), in O(vertices). The tests' brute-force oracle multiplies the
// same products out over the explicit path.
struct CorrelationEntry {
  float term;  // the merge's share of MisSums::merge
  float own;   // its side's product of acceptances from the subpath's start to the vertex
  float rev;   // the reverse acceptances of the vertex and the later ones, up to the
               // subpath's second-to-last vertex
};
struct CorrelationTrack {
  // Non-delta vertices of a subpath: --max-depth at most this.
  static constexpr int kMaxEntries = 128;
  // A live subpath's own storage (OwnedCorrelationTrack, room for kMaxEntries), or a stored
  // light vertex's entries in the integrator's pool, which nothing writes through.
  CorrelationEntry* entries = nullptr;
  int count = 0;
  float own_total = 1;         // the own-direction product up to the last vertex, included
  float next_pdf = 0;          // solid-angle density of the sample leaving the last vertex
  bool next_specular = false;  // that sample came from a delta lobe
  float seg_cos = 0;           // |cos| at the vertex before the last, toward the last
  float seg_dist2 = 1;         // squared distance between those two vertices
  // A copy of o into this track's storage, of the entries in use only.
  void assign(const CorrelationTrack& o) {
    std::copy_n(o.entries, o.count, entries);
    count = o.count;
    own_total = o.own_total;
    next_pdf = o.next_pdf;
    next_specular = o.next_specular;
    seg_cos = o.seg_cos;
    seg_dist2 = o.seg_dist2;
  }
};
// A track with its own room for kMaxEntries entries (1.5 kB, left uninitialised); copies copy
// the entries in use.
struct OwnedCorrelationTrack : CorrelationTrack {
  OwnedCorrelationTrack() { entries = storage.data(); }
  OwnedCorrelationTrack(const OwnedCorrelationTrack& o) : OwnedCorrelationTrack() { assign(o); }
  OwnedCorrelationTrack& operator=(const OwnedCorrelationTrack& o) {
    assign(o);
    return *this;
  }
  std::array<CorrelationEntry, kMaxEntries> storage;
};

// The partial sums a subpath carries to its last vertex, without counts.
struct MisSums {
  float vcm = 0;      // dVCM: the vertex's own reverse-sampling ratio (tech. rep. section 4)
  float rest = 0;     // techniques behind of the subpath's first class: Emitter on the light
                      // subpath (s' <= 1), LightTrace on the camera subpath (t' = 1)
  float conn = 0;     // connections behind (s', t' >= 2)
  float merge = 0;    // merges behind
  bool first = true;  // the vertex is its subpath's first: vcm belongs to the "rest" class
  // Camera subpaths only (adaptive-vcm's per-pixel photon mapping, PixelMode::Stop): the one
  // term of `merge` that stands for merging at the subpath's first vertex scattered through a
  // non-delta lobe, once there is one (past_delta_chain).
  float first_merge = 0;
  bool past_delta_chain = false;
  // The subpath's merges one by one, kept in step by MisRules::hit and scatter (correlation-
  // aware MIS only; nullptr otherwise).
  CorrelationTrack* corr = nullptr;
};

// The other techniques of one path relative to the current one, sum_k p_k / p_current by class
// (already through mis()), and the current technique's class.
struct TechniqueTerms {
  TechniqueClass own = TechniqueClass::Connect;
  float emitter = 0, light_trace = 0, connect = 0, merge = 0;
  // The photon-mapping estimator of a pixel (camera subpaths that end at their first vertex
  // scattered through a non-delta lobe, PixelMode::Stop) makes a path in one way only: by
  // merging at that vertex, or, if the camera side of the path has none (delta_chain), by the
  // camera subpath hitting the emitter (s = 0). first_merge: that merge's term (mis()'d), or
  // own_first_merge if it is the current technique.
  float first_merge = 0;
  bool own_first_merge = false;
  bool delta_chain = false;
  // Under that estimator with an emitter count n_emitter and a merge count n_merge (mis()'d):
  // the current technique's own count (0 if it is not the one way) and the denominator.
  float stop_own(float n_emitter, float n_merge) const;
  float stop_denominator(float n_emitter, float n_merge) const;
  // The current technique's own count is its class's times this factor (through mis()): the
  // learned probability with which its vertex takes it (guided-bpt, guided-vcm; see
  // MisRules::scale_vcm). The contribution then divides by that probability.
  float own_factor = 1;
  // The weight under `counts` (mis()'d counts, MisRules::counts()).
  float weight(const MisCounts& counts) const;
  // sum_k n_k p_k / p_current including the current technique: 1 / weight * own count.
  float denominator(const MisCounts& counts) const;
};

// Per-iteration constants of the weights and the update rules.
class MisRules {
 public:
  MisRules(MisHeuristic heuristic, const MisCounts& counts);
  // The classic switches: connect = emitter hits, NEE, connections and light tracing (N per
  // pixel); merge = N pi r^2 (tech. rep. eq. 20).
  MisRules(MisHeuristic heuristic, bool connect, bool merge, float light_paths, float radius);

  float mis(float x) const { return power_ ? x * x : x; }
  bool power() const { return power_; }
  // The counts through mis(), as the weights use them.
  const MisCounts& counts() const { return counts_; }
  // Whether any technique of a light subpath (light tracing, connection, merge) counts. Without
  // one (adaptive-vcm rendering path tracing) the camera sums' reverse densities only ever meet
  // counts of zero, so they need not be evaluated (reverse_pdf()).
  bool uses_light_subpaths() const {
    return counts_.light_trace > 0 || counts_.connect > 0 || counts_.merge > 0;
  }
  // The same rules in a pixel that merges or not (merge count 0).
  MisRules with_merging(bool merge) const;

  // Camera subpath start; camera_pdf_w is the per-pixel solid-angle density of the primary ray
  // (pixel_count * pdf_we * the pixel filter's raster density, techniques.h). tech. rep. eqs.
  // 31-33, completed by hit().
  MisSums camera_start(float camera_pdf_w) const;
  // Light subpath at its first surface vertex y1 (the start and the first hit in one, since the
  // direct-sampling pdf of a sphere light depends on y1). direct_pdf: pmf * NEE density of the
  // light point as sampled from y1, in area measure for finite lights (1 for delta positions),
  // solid angle for infinite ones; emission_pdf: pmf * pdf_pos * pdf_dir. eqs. 31-33, 48-50.
  MisSums light_first_hit(float direct_pdf, float emission_pdf, float cos_at_light,
                          bool delta_light, bool finite_light, float dist2, float cos_at_hit) const;
  // Arrival at the next vertex after a scattering: the remaining part of eqs. 34-36.
  void hit(MisSums& s, float dist2, float cos_at_hit) const;
  // Scattering from a vertex: cos_out = |ng . wi| there, pdf_fwd / pdf_rev of the bounce.
  void scatter(MisSums& s, float cos_out, float pdf_fwd, float pdf_rev, bool specular) const;
  // Techniques taken with a per-vertex probability q (guided-bpt, guided-vcm: next event
  // estimation, lens connections and connections where training saw them blocked). Their count
  // is the class's times q of the vertex that takes them, which enters the sums through the
  // one term that stands for each: a vertex's dVCM. On the camera subpath, dVCM at z_j (after
  // hit()) stands for the technique whose light subpath ends at z_j and connects to z_(j-1) (a
  // lens connection at z_1): scaled by that technique's q at z_j. On the light subpath, dVCM
  // at y1 stands for next event estimation from y1, and dVCM at y_(i+1) (after scatter() at
  // y_i) for the connection of y_i to y_(i+1): scaled by their q at y1 and y_i. The other
  // places a probability enters: the own technique (TechniqueTerms::own_factor) and an emitter
  // hit's next event term (hit_light's nee_probability). q = 1 changes nothing, bit for bit.
  void scale_vcm(MisSums& s, float q) const;

  // Correlation-aware MIS (see CorrelationTrack): acceptance area A = pi r^2 and the least
  // factor 1 / N. Off (A = 0) unless enabled.
  void enable_correlation(float acceptance_area, float min_factor);
  bool correlated() const { return corr_area_ > 0; }
  // min(1, A p) for an area density p (an infinite density, a delta lobe's, gives 1).
  float acceptance(float area_density) const;
  // c = cam / (cam + light - cam light), at least 1 / N.
  float correlation(float cam, float light) const;
  // A camera subpath starts (before the hit() of its first vertex): camera_pdf_w as camera_start.
  void correlation_camera_start(CorrelationTrack& t, float camera_pdf_w) const;
  // A light subpath at its first vertex y1: the acceptances of the emission point y0 and of y1.
  void correlation_light_start(CorrelationTrack& t, float a_y0, float a_y1, float cos_at_light,
                               float dist2) const;
  // The acceptance of the vertex before the subpath's last, sampled from the last one with the
  // solid-angle density pdf_rev_w there.
  float reverse_acceptance(const CorrelationTrack& t, float pdf_rev_w) const;
  // The merge terms of one side of a technique's path (the sum that replaces its share of
  // TechniqueTerms::merge): the merge at the side's last vertex with count factor here_scale
  // (0: none), the ones behind it scaled by entries_scale (add_beyond's scale x mis(pdf_rev)),
  // whose other-side product is other x a_rev_prev x their rev. `other`: the other side's
  // product up to the side's last vertex, included. camera_side: t is a camera subpath's.
  float correlated_merges(const CorrelationTrack& t, bool camera_side, float here_scale,
                          float entries_scale, float a_rev_prev, float other) const;
  // The same with add_beyond's arguments (its merge part): the merge at the side's last vertex
  // with `scale` where with_merge_here, the ones behind with scale x mis(pdf_rev) and the
  // reverse acceptance of pdf_rev.
  float correlated_beyond(const CorrelationTrack& t, bool camera_side, float scale, float pdf_rev,
                          bool with_merge_here, float other) const;

  // The terms of each way a path is completed (eq. 37 with counts); weight = terms.weight().
  // Camera subpath hits an emitter (s = 0): direct_pdf in the measure of light_first_hit
  // (area, or solid angle for infinite lights), emission_pdf = pmf * pdf_pos * pdf_dir.
  // nee_probability: that of next event estimation at the vertex before the emitter, toward it.
  TechniqueTerms hit_light(const MisSums& camera, float direct_pdf, float emission_pdf,
                           float nee_probability = 1) const;
  // The camera ray itself hits an area light (s = 0, t = 2): the one other technique is the
  // light subpaths' emission point connected to the lens (s = 1, t = 1). emission_pos_pdf:
  // pmf * pdf_pos of that point (area measure); `camera` the sums after hit() at the light.
  TechniqueTerms hit_light_from_lens(const MisSums& camera, float emission_pos_pdf) const;
  // The converse: a light subpath's emission point connected to the lens (s = 1, t = 1);
  // camera_pdf_a: the per-pixel camera density of the point in area measure.
  TechniqueTerms light_origin_to_camera(float camera_pdf_a, float emission_pos_pdf) const;
  // Next event estimation (s = 1). bsdf_pdf_fwd is 0 for delta lights; direct_pdf_w includes the
  // pmf and is pmf * dist^2 for delta positions (area density 1); cos_to_light = |ng . wi| at the
  // camera vertex; cos_at_light = 1 for point-like and infinite lights. eqs. 44-45.
  TechniqueTerms next_event(const MisSums& camera, float bsdf_pdf_fwd, float bsdf_pdf_rev,
                            float direct_pdf_w, float emission_pdf_w, float cos_to_light,
                            float cos_at_light) const;
  // Connection of a light vertex and a camera vertex (s, t >= 2). camera_pdf_a: the camera
  // vertex's BSDF sampling the light vertex (area at the light vertex); light_pdf_a the converse;
  // the _rev_w pdfs: each vertex's BSDF sampling its own predecessor given the connection. eqs.
  // 40-41.
  TechniqueTerms connect(const MisSums& light, const MisSums& camera, float camera_pdf_a,
                         float camera_rev_w, float light_pdf_a, float light_rev_w) const;
  // Light vertex connected to the camera (t = 1): camera_pdf_a = per-pixel camera density of the
  // light vertex in area measure; light_rev_w its BSDF sampling its predecessor. eqs. 46-47.
  TechniqueTerms light_to_camera(const MisSums& light, float camera_pdf_a, float light_rev_w) const;
  // Merge of a light vertex with a camera vertex: the camera BSDF's pdfs of the light's incoming
  // direction (fwd) and of its own outgoing direction given that one (rev). eqs. 38-39.
  TechniqueTerms merge(const MisSums& light, const MisSums& camera, float camera_pdf_fwd_w,
                       float camera_pdf_rev_w) const;

 private:
  // Adds to t, scaled by `scale`, the techniques that sample this vertex from the other side
  // (`with_merge_here`: merging at the vertex) and those further along the subpath (the sums
  // times mis(pdf_rev)). rest_class: Emitter on the light subpath, LightTrace on the camera's.
  void add_beyond(TechniqueTerms& t, const MisSums& s, TechniqueClass rest_class, float scale,
                  float pdf_rev, bool with_merge_here) const;
  // Sets t's first_merge (or delta_chain) from the camera sums at a camera vertex that a
  // technique with this scale completes (as add_beyond on the camera side, with merging there).
  void add_first_merge(TechniqueTerms& t, const MisSums& camera, float scale, float pdf_rev) const;

  bool power_;
  MisCounts counts_;  // through mis()
  float corr_area_ = 0, corr_min_ = 0;
};

}  // namespace caustica::bidir
