#include "integrators/bidir/mis.h"

#include "core/math.h"

namespace caustica::bidir {

namespace {
// Products of the partial sums. A zero factor is the pdf of another technique (or the mark that
// no technique exists there): those techniques cannot make the path, so their term is 0 whatever
// the other factor. An infinite factor comes from the current technique's own vanishing density
// (a grazing cosine or a zero pdf in a denominator). The limit of the product as the zero factor
// goes to 0 is 0, so 0 * inf is 0 here, where IEEE says NaN.
float times(float a, float b) { return a == 0.f || b == 0.f ? 0.f : a * b; }
// 1 / (1 + others): an infinite sum of other techniques is the limit weight 0. A NaN can now only
// come from a 0 / 0 inside one pdf ratio, which has no limit to give; it gets weight 0.
float full_weight(float others) { return others == others ? 1.f / (1.f + others) : 0.f; }
}  // namespace

MisRules::MisRules(MisHeuristic heuristic, bool connect, bool merge, float light_paths,
                   float radius)
    : power_(heuristic == MisHeuristic::Power), light_paths_(light_paths) {
  const float eta_vcm = kPi * radius * radius * light_paths;  // tech. rep. eq. 20
  vm_factor_ = merge ? mis(eta_vcm) : 0.f;
  vc_factor_ = connect && eta_vcm > 0 ? mis(1.f / eta_vcm) : 0.f;
}

MisSums MisRules::camera_start(float camera_pdf_w) const {
  // dVCM = n_LT / p(camera ray): the light-tracing technique uses N samples per pixel.
  return {mis(light_paths_ / camera_pdf_w), 0.f, 0.f};
}

MisSums MisRules::light_first_hit(float direct_pdf, float emission_pdf, float cos_at_light,
                                  bool delta_light, bool finite_light, float dist2,
                                  float cos_at_hit) const {
  MisSums s;
  // eq. 31: the ratio of the direct-sampling pdf of y0 to the emission pdf of (y0, y1).
  s.vcm = mis(direct_pdf / emission_pdf);
  // eqs. 32-33; delta lights cannot be hit, so nothing connects "behind" them (eqs. 48-50).
  // Infinite lights measure y0 in solid angle: cos at the light is 1 and no distance enters
  // (tech. rep. section 5.1).
  s.vc = delta_light ? 0.f : mis((finite_light ? cos_at_light : 1.f) / emission_pdf);
  s.vm = times(s.vc, vc_factor_);
  if (finite_light) s.vcm = times(s.vcm, mis(dist2));
  hit(s, 1.f, cos_at_hit);
  return s;
}

void MisRules::hit(MisSums& s, float dist2, float cos_at_hit) const {
  // Completes eqs. 34-36: the forward pdf of this vertex gains |cos| / dist^2.
  const float inv_cos = 1.f / mis(cos_at_hit);
  s.vcm = times(times(s.vcm, mis(dist2)), inv_cos);
  s.vc = times(s.vc, inv_cos);
  s.vm = times(s.vm, inv_cos);
}

void MisRules::scatter(MisSums& s, float cos_out, float pdf_fwd, float pdf_rev,
                       bool specular) const {
  if (specular) {
    // eqs. 53-55: no technique can end at a specular vertex (dVCM = 0); pdf_rev == pdf_fwd
    // cancels and only the cosine of the reverse area conversion remains.
    s.vcm = 0.f;
    s.vc = times(s.vc, mis(cos_out));
    s.vm = times(s.vm, mis(cos_out));
    return;
  }
  // eqs. 34-36 (the 1/dist^2 and 1/cos of the next vertex follow in hit()).
  const float g = mis(cos_out / pdf_fwd);
  const float rev = mis(pdf_rev);
  const float vc = times(g, times(s.vc, rev) + s.vcm + vm_factor_);
  const float vm = times(g, times(s.vm, rev) + times(s.vcm, vc_factor_) + 1.f);
  s.vcm = mis(1.f / pdf_fwd);
  s.vc = vc;
  s.vm = vm;
}

float MisRules::hit_light(const MisSums& camera, float direct_pdf, float emission_pdf) const {
  // eqs. 42-43: the light subpath is empty; the camera side sums NEE and all connections.
  const float w_camera = times(mis(direct_pdf), camera.vcm) + times(mis(emission_pdf), camera.vc);
  return full_weight(w_camera);
}

float MisRules::next_event(const MisSums& camera, float bsdf_pdf_fwd, float bsdf_pdf_rev,
                           float direct_pdf_w, float emission_pdf_w, float cos_to_light,
                           float cos_at_light) const {
  // eq. 44: BSDF sampling hitting the light instead (both solid angle at the camera vertex).
  const float w_light = mis(bsdf_pdf_fwd / direct_pdf_w);
  // eq. 45: emission_pdf_a / direct_pdf_a at the camera vertex; the dist^2 of both cancel.
  const float w_camera = times(mis(emission_pdf_w * cos_to_light / (direct_pdf_w * cos_at_light)),
                               vm_factor_ + camera.vcm + times(camera.vc, mis(bsdf_pdf_rev)));
  return full_weight(w_light + w_camera);
}

float MisRules::connect(const MisSums& light, const MisSums& camera, float camera_pdf_a,
                        float camera_rev_w, float light_pdf_a, float light_rev_w) const {
  const float w_light = times(
      mis(camera_pdf_a), vm_factor_ + light.vcm + times(light.vc, mis(light_rev_w)));  // eq. 40
  const float w_camera = times(
      mis(light_pdf_a), vm_factor_ + camera.vcm + times(camera.vc, mis(camera_rev_w)));  // eq. 41
  return full_weight(w_light + w_camera);
}

float MisRules::light_to_camera(const MisSums& light, float camera_pdf_a, float light_rev_w) const {
  // eq. 46, with the camera density divided by the N light paths that share each pixel.
  const float w_light = times(mis(camera_pdf_a / light_paths_),
                              vm_factor_ + light.vcm + times(light.vc, mis(light_rev_w)));
  return full_weight(w_light);
}

float MisRules::merge(const MisSums& light, const MisSums& camera, float camera_pdf_fwd_w,
                      float camera_pdf_rev_w) const {
  const float w_light =
      times(light.vcm, vc_factor_) + times(light.vm, mis(camera_pdf_fwd_w));  // eq. 38
  const float w_camera =
      times(camera.vcm, vc_factor_) + times(camera.vm, mis(camera_pdf_rev_w));  // eq. 39
  return full_weight(w_light + w_camera);
}

}  // namespace caustica::bidir
