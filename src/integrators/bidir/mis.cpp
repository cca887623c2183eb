#include "integrators/bidir/mis.h"

#include <algorithm>

#include "core/math.h"

namespace caustica::bidir {

namespace {
// Products of the partial sums. A zero factor is the pdf of another technique (or the mark that
// no technique exists there): those techniques cannot make the path, so their term is 0 whatever
// the other factor. An infinite factor comes from the current technique's own vanishing density
// (a grazing cosine or a zero pdf in a denominator). The limit of the product as the zero factor
// goes to 0 is 0, so 0 * inf is 0 here, where IEEE says NaN.
float times(float a, float b) { return a == 0.f || b == 0.f ? 0.f : a * b; }

float& term(TechniqueTerms& t, TechniqueClass c) {
  switch (c) {
    case TechniqueClass::Emitter:
      return t.emitter;
    case TechniqueClass::LightTrace:
      return t.light_trace;
    case TechniqueClass::Merge:
      return t.merge;
    case TechniqueClass::Connect:
      break;
  }
  return t.connect;
}

float others(const TechniqueTerms& t, const MisCounts& n) {
  return times(n.emitter, t.emitter) + times(n.light_trace, t.light_trace) +
         times(n.connect, t.connect) + times(n.merge, t.merge);
}
}  // namespace

float TechniqueTerms::weight(const MisCounts& counts) const {
  const float own_count = counts.of(own) * own_factor;
  if (!(own_count > 0)) return 0.f;
  // 1 / (1 + others): an infinite sum of other techniques is the limit weight 0. A NaN can only
  // come from a 0 / 0 inside one pdf ratio, which has no limit to give; it gets weight 0.
  const float x = others(*this, counts) / own_count;
  return x == x ? 1.f / (1.f + x) : 0.f;
}

float TechniqueTerms::denominator(const MisCounts& counts) const {
  return counts.of(own) * own_factor + others(*this, counts);
}

float TechniqueTerms::stop_own(float n_emitter, float n_merge) const {
  if (delta_chain) return own == TechniqueClass::Emitter ? n_emitter : 0.f;
  return own_first_merge ? n_merge : 0.f;
}

float TechniqueTerms::stop_denominator(float n_emitter, float n_merge) const {
  if (delta_chain) return own == TechniqueClass::Emitter ? n_emitter : times(n_emitter, emitter);
  return own_first_merge ? n_merge : times(n_merge, first_merge);
}

MisRules::MisRules(MisHeuristic heuristic, const MisCounts& counts)
    : power_(heuristic == MisHeuristic::Power) {
  counts_ = {mis(counts.emitter), mis(counts.light_trace), mis(counts.connect), mis(counts.merge)};
}

namespace {
MisCounts classic_counts(bool connect, bool merge, float light_paths, float radius) {
  MisCounts c;
  c.emitter = c.connect = connect ? 1.f : 0.f;
  c.light_trace = connect ? light_paths : 0.f;
  c.merge = merge ? kPi * radius * radius * light_paths : 0.f;  // tech. rep. eq. 20
  return c;
}
}  // namespace

MisRules::MisRules(MisHeuristic heuristic, bool connect, bool merge, float light_paths,
                   float radius)
    : MisRules(heuristic, classic_counts(connect, merge, light_paths, radius)) {}

MisRules MisRules::with_merging(bool merge) const {
  MisRules r = *this;
  if (!merge) r.counts_.merge = 0;
  return r;
}

MisSums MisRules::camera_start(float camera_pdf_w) const {
  // dVCM = 1 / p(camera ray): the light-tracing technique (its count enters at the weights).
  MisSums s;
  s.vcm = mis(1.f / camera_pdf_w);
  return s;
}

MisSums MisRules::light_first_hit(float direct_pdf, float emission_pdf, float cos_at_light,
                                  bool delta_light, bool finite_light, float dist2,
                                  float cos_at_hit) const {
  MisSums s;
  // eq. 31: the ratio of the direct-sampling pdf of y0 to the emission pdf of (y0, y1).
  s.vcm = mis(direct_pdf / emission_pdf);
  // eqs. 32-33: the camera subpath hitting y0; delta lights cannot be hit (eqs. 48-50).
  // Infinite lights measure y0 in solid angle: cos at the light is 1 and no distance enters
  // (tech. rep. section 5.1).
  s.rest = delta_light ? 0.f : mis((finite_light ? cos_at_light : 1.f) / emission_pdf);
  if (finite_light) s.vcm = times(s.vcm, mis(dist2));
  hit(s, 1.f, cos_at_hit);
  return s;
}

void MisRules::hit(MisSums& s, float dist2, float cos_at_hit) const {
  // Completes eqs. 34-36: the forward pdf of this vertex gains |cos| / dist^2.
  const float inv_cos = 1.f / mis(cos_at_hit);
  s.vcm = times(times(s.vcm, mis(dist2)), inv_cos);
  s.rest = times(s.rest, inv_cos);
  s.conn = times(s.conn, inv_cos);
  s.merge = times(s.merge, inv_cos);
  s.first_merge = times(s.first_merge, inv_cos);
  if (s.corr && correlated()) {
    CorrelationTrack& t = *s.corr;
    for (int i = 0; i < t.count; ++i) t.entries[i].term = times(t.entries[i].term, inv_cos);
    if (!t.next_specular) t.own_total *= acceptance(t.next_pdf * cos_at_hit / dist2);
    t.seg_dist2 = dist2;
  }
}

void MisRules::scatter(MisSums& s, float cos_out, float pdf_fwd, float pdf_rev,
                       bool specular) const {
  const bool first = s.first;
  s.first = false;
  if (specular) {
    // eqs. 53-55: no technique can end at a specular vertex (dVCM = 0); pdf_rev == pdf_fwd
    // cancels and only the cosine of the reverse area conversion remains.
    s.vcm = 0.f;
    const float c = mis(cos_out);
    s.rest = times(s.rest, c);
    s.conn = times(s.conn, c);
    s.merge = times(s.merge, c);
    s.first_merge = times(s.first_merge, c);
    if (s.corr && correlated()) {
      // The vertex before is sampled from this one through a delta lobe: acceptance 1.
      CorrelationTrack& t = *s.corr;
      for (int i = 0; i < t.count; ++i) t.entries[i].term = times(t.entries[i].term, c);
      t.next_specular = true;
      t.seg_cos = cos_out;
    }
    return;
  }
  // eqs. 34-36 (the 1/dist^2 and 1/cos of the next vertex follow in hit()). The vertex's own
  // ratio dVCM joins the class of the technique it stands for: at a subpath's first vertex NEE
  // (light subpath) or light tracing (camera subpath), further on a connection. Merging at this
  // vertex adds 1 (its count enters at the weights).
  const float g = mis(cos_out / pdf_fwd);
  const float rev = mis(pdf_rev);
  s.rest = times(g, times(s.rest, rev) + (first ? s.vcm : 0.f));
  s.conn = times(g, times(s.conn, rev) + (first ? 0.f : s.vcm));
  s.merge = times(g, times(s.merge, rev) + 1.f);
  s.first_merge = s.past_delta_chain ? times(g, times(s.first_merge, rev)) : g;
  s.past_delta_chain = true;
  s.vcm = mis(1.f / pdf_fwd);
  if (s.corr && correlated()) {
    // As merge: the merges behind gain g x rev and the vertex before this one its reverse
    // acceptance; the merge here joins with g.
    CorrelationTrack& t = *s.corr;
    const float a_prev = reverse_acceptance(t, pdf_rev);
    for (int i = 0; i < t.count; ++i) {
      CorrelationEntry& e = t.entries[i];
      e.term = times(g, times(e.term, rev));
      e.rev *= a_prev;
    }
    if (t.count < CorrelationTrack::kMaxEntries) t.entries[t.count++] = {g, t.own_total, 1.f};
    t.next_pdf = pdf_fwd;
    t.next_specular = false;
    t.seg_cos = cos_out;
  }
}

void MisRules::scale_vcm(MisSums& s, float q) const {
  if (q != 1.f) s.vcm = times(s.vcm, mis(q));
}

void MisRules::enable_correlation(float acceptance_area, float min_factor) {
  corr_area_ = acceptance_area;
  corr_min_ = min_factor;
}

float MisRules::acceptance(float area_density) const {
  const float a = corr_area_ * area_density;
  if (a >= 1.f) return 1.f;  // an infinite density too
  return a > 0.f ? a : 0.f;  // NaN (0 x inf) counts as 0
}

float MisRules::correlation(float cam, float light) const {
  const float denominator = cam + light - cam * light;
  if (!(denominator > 0)) return 1.f;  // both 0: nothing is shared
  return std::max(cam / denominator, corr_min_);
}

void MisRules::correlation_camera_start(CorrelationTrack& t, float camera_pdf_w) const {
  t.count = 0;
  t.own_total = 1;
  t.next_pdf = camera_pdf_w;
  t.next_specular = false;
  t.seg_cos = 0;
  t.seg_dist2 = 1;
}

void MisRules::correlation_light_start(CorrelationTrack& t, float a_y0, float a_y1,
                                       float cos_at_light, float dist2) const {
  t.count = 0;
  t.next_pdf = 0;
  t.next_specular = false;
  t.own_total = a_y0 * a_y1;
  t.seg_cos = cos_at_light;
  t.seg_dist2 = dist2;
}

float MisRules::reverse_acceptance(const CorrelationTrack& t, float pdf_rev_w) const {
  return acceptance(pdf_rev_w * t.seg_cos / t.seg_dist2);
}

float MisRules::correlated_merges(const CorrelationTrack& t, bool camera_side, float here_scale,
                                  float entries_scale, float a_rev_prev, float other) const {
  auto factor = [&](float own, float others) {
    return mis(camera_side ? correlation(own, others) : correlation(others, own));
  };
  float sum = here_scale > 0 ? here_scale * factor(t.own_total, other) : 0.f;
  for (int i = 0; i < t.count; ++i) {
    const CorrelationEntry& e = t.entries[i];
    sum += times(times(entries_scale, e.term), factor(e.own, other * a_rev_prev * e.rev));
  }
  return sum;
}

float MisRules::correlated_beyond(const CorrelationTrack& t, bool camera_side, float scale,
                                  float pdf_rev, bool with_merge_here, float other) const {
  return correlated_merges(t, camera_side, with_merge_here ? scale : 0.f,
                           times(scale, mis(pdf_rev)), reverse_acceptance(t, pdf_rev), other);
}

void MisRules::add_beyond(TechniqueTerms& t, const MisSums& s, TechniqueClass rest_class,
                          float scale, float pdf_rev, bool with_merge_here) const {
  if (with_merge_here) t.merge += scale;
  term(t, s.first ? rest_class : TechniqueClass::Connect) += times(scale, s.vcm);
  const float r = times(scale, mis(pdf_rev));
  term(t, rest_class) += times(r, s.rest);
  t.connect += times(r, s.conn);
  t.merge += times(r, s.merge);
}

void MisRules::add_first_merge(TechniqueTerms& t, const MisSums& camera, float scale,
                               float pdf_rev) const {
  t.first_merge =
      camera.past_delta_chain ? times(times(scale, mis(pdf_rev)), camera.first_merge) : scale;
}

TechniqueTerms MisRules::hit_light(const MisSums& camera, float direct_pdf, float emission_pdf,
                                   float nee_probability) const {
  // eqs. 42-43: the light subpath is empty; the camera side holds NEE and everything further.
  TechniqueTerms t;
  t.own = TechniqueClass::Emitter;
  t.emitter = times(mis(direct_pdf), camera.vcm);
  if (nee_probability != 1.f) t.emitter = times(t.emitter, mis(nee_probability));
  const float e = mis(emission_pdf);
  t.light_trace = times(e, camera.rest);
  t.connect = times(e, camera.conn);
  t.merge = times(e, camera.merge);
  t.first_merge = times(e, camera.first_merge);
  t.delta_chain = !camera.past_delta_chain;
  return t;
}

TechniqueTerms MisRules::hit_light_from_lens(const MisSums& camera, float emission_pos_pdf) const {
  // camera.vcm is 1 / p_camera in area measure at the light (camera_start, then hit()).
  TechniqueTerms t;
  t.own = TechniqueClass::Emitter;
  t.light_trace = times(mis(emission_pos_pdf), camera.vcm);
  t.delta_chain = true;
  return t;
}

TechniqueTerms MisRules::light_origin_to_camera(float camera_pdf_a, float emission_pos_pdf) const {
  TechniqueTerms t;
  t.own = TechniqueClass::LightTrace;
  t.emitter = mis(camera_pdf_a / emission_pos_pdf);
  t.delta_chain = true;
  return t;
}

TechniqueTerms MisRules::next_event(const MisSums& camera, float bsdf_pdf_fwd, float bsdf_pdf_rev,
                                    float direct_pdf_w, float emission_pdf_w, float cos_to_light,
                                    float cos_at_light) const {
  TechniqueTerms t;
  t.own = TechniqueClass::Emitter;
  // eq. 44: BSDF sampling hitting the light instead (both solid angle at the camera vertex).
  t.emitter = mis(bsdf_pdf_fwd / direct_pdf_w);
  // eq. 45: emission_pdf_a / direct_pdf_a at the camera vertex; the dist^2 of both cancel.
  const float scale = mis(emission_pdf_w * cos_to_light / (direct_pdf_w * cos_at_light));
  add_beyond(t, camera, TechniqueClass::LightTrace, scale, bsdf_pdf_rev, true);
  add_first_merge(t, camera, scale, bsdf_pdf_rev);
  return t;
}

TechniqueTerms MisRules::connect(const MisSums& light, const MisSums& camera, float camera_pdf_a,
                                 float camera_rev_w, float light_pdf_a, float light_rev_w) const {
  TechniqueTerms t;
  t.own = TechniqueClass::Connect;
  add_beyond(t, light, TechniqueClass::Emitter, mis(camera_pdf_a), light_rev_w, true);  // eq. 40
  add_beyond(t, camera, TechniqueClass::LightTrace, mis(light_pdf_a), camera_rev_w,
             true);  // eq. 41
  add_first_merge(t, camera, mis(light_pdf_a), camera_rev_w);
  return t;
}

TechniqueTerms MisRules::light_to_camera(const MisSums& light, float camera_pdf_a,
                                         float light_rev_w) const {
  TechniqueTerms t;
  t.own = TechniqueClass::LightTrace;
  add_beyond(t, light, TechniqueClass::Emitter, mis(camera_pdf_a), light_rev_w, true);  // eq. 46
  // The light vertex is the first the camera side of the path has: merging there.
  t.first_merge = mis(camera_pdf_a);
  return t;
}

TechniqueTerms MisRules::merge(const MisSums& light, const MisSums& camera, float camera_pdf_fwd_w,
                               float camera_pdf_rev_w) const {
  TechniqueTerms t;
  t.own = TechniqueClass::Merge;
  add_beyond(t, light, TechniqueClass::Emitter, 1.f, camera_pdf_fwd_w, false);      // eq. 38
  add_beyond(t, camera, TechniqueClass::LightTrace, 1.f, camera_pdf_rev_w, false);  // eq. 39
  t.own_first_merge = !camera.past_delta_chain;
  if (camera.past_delta_chain) add_first_merge(t, camera, 1.f, camera_pdf_rev_w);
  return t;
}

}  // namespace caustica::bidir
