// MIS weights of the bidirectional family through the incremental partial sums dVCM, dVC, dVM
// of Georgiev's tech report "Implementing Vertex Connection and Merging" (2012). Each subpath
// vertex carries three numbers from which the weight of any technique that ends the subpath
// there follows in O(1); the updates below are the report's equations, written once and used
// by the renderer and by the tests' replay of explicit paths alike.
//
// Conventions: every pdf handed in is in solid angle unless its name ends in _a (area measure
// at the point it samples); area conversions use the *geometric* normal (|ng . w|), both here
// and in the tests' brute-force oracle. Delta (specular) bounces report pdf_fwd = pdf_rev and
// only their cosine survives. Russian roulette is left out of the pdfs (the weights still sum to
// one over the techniques; they are just not the exact balance weights of the RR'd estimator).
#pragma once

#include "integrators/integrator.h"

namespace caustica::bidir {

// The three partial sums a subpath carries to its last vertex (tech. rep. section 4).
struct MisSums {
  float vcm = 0;  // dVCM: terms shared by connection and merging (the vertex's own pdf ratio)
  float vc = 0;   // dVC: techniques that connect further along the subpath
  float vm = 0;   // dVM: techniques that merge further along the subpath
};

// Per-iteration constants of the weights and the update rules.
class MisRules {
 public:
  // light_paths = N; radius = the iteration's merge radius. Technique switches decide which
  // families take part: eta_VCM = N pi r^2 (tech. rep. eq. 20 with n_VC = 1, n_VM = N).
  MisRules(MisHeuristic heuristic, bool connect, bool merge, float light_paths, float radius);

  float mis(float x) const { return power_ ? x * x : x; }
  float light_paths() const { return light_paths_; }

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

  // Full weights 1 / (w_light + 1 + w_camera), eq. 37, for each way a path is completed.
  // Camera subpath hits an emitter (s = 0): direct_pdf in the measure of light_first_hit
  // (area, or solid angle for infinite lights), emission_pdf = pmf * pdf_pos * pdf_dir.
  float hit_light(const MisSums& camera, float direct_pdf, float emission_pdf) const;
  // Next event estimation (s = 1). bsdf_pdf_fwd is 0 for delta lights; direct_pdf_w includes the
  // pmf and is pmf * dist^2 for delta positions (area density 1); cos_to_light = |ng . wi| at the
  // camera vertex; cos_at_light = 1 for point-like and infinite lights. eqs. 44-45.
  float next_event(const MisSums& camera, float bsdf_pdf_fwd, float bsdf_pdf_rev,
                   float direct_pdf_w, float emission_pdf_w, float cos_to_light,
                   float cos_at_light) const;
  // Connection of a light vertex and a camera vertex (s, t >= 2). camera_pdf_a: the camera
  // vertex's BSDF sampling the light vertex (area at the light vertex); light_pdf_a the converse;
  // the _rev_w pdfs: each vertex's BSDF sampling its own predecessor given the connection. eqs.
  // 40-41.
  float connect(const MisSums& light, const MisSums& camera, float camera_pdf_a, float camera_rev_w,
                float light_pdf_a, float light_rev_w) const;
  // Light vertex connected to the camera (t = 1): camera_pdf_a = per-pixel camera density of the
  // light vertex in area measure; light_rev_w its BSDF sampling its predecessor. eqs. 46-47.
  float light_to_camera(const MisSums& light, float camera_pdf_a, float light_rev_w) const;
  // Merge of a light vertex with a camera vertex: the camera BSDF's pdfs of the light's incoming
  // direction (fwd) and of its own outgoing direction given that one (rev). eqs. 38-39.
  float merge(const MisSums& light, const MisSums& camera, float camera_pdf_fwd_w,
              float camera_pdf_rev_w) const;

 private:
  bool power_;
  float light_paths_;
  float vm_factor_;  // Mis(eta_VCM) if merging takes part, else 0
  float vc_factor_;  // Mis(1 / eta_VCM) if connections take part, else 0
};

}  // namespace caustica::bidir
