// Diffuse area lights on triangles and spheres (pbrt-v4's DiffuseAreaLight with a constant
// radiance). Parameters: radiance L (linear RGB), two_sided (emit on both sides, default false:
// only on the side of the shape's oriented normal).
//
// Normals: every normal these lights report or read is the shape's *oriented* geometric normal
// (TriangleMesh::face_normal, or the sphere's outward normal flipped by reverse_orientation).
// The lights recompute it from their own geometry rather than trusting the caller's n, so a
// caller may pass either orientation of the geometric normal.
#include <cmath>

#include "core/frame.h"
#include "core/warp.h"
#include "lights/light_power.h"
#include "lights/lights.h"

namespace caustica {

namespace {

// Cosine-weighted emission around n_emit; two-sided lights pick a side with probability 1/2
// (pbrt-v4 DiffuseAreaLight::SampleLe). Returns the world direction and its solid-angle pdf.
Vec3 sample_diffuse_emission(Vec3 n_emit, bool two_sided, Vec2 u, float* pdf_dir) {
  Vec3 w;
  if (two_sided) {
    const bool front = u.x < 0.5f;
    u.x =
        front ? std::min(u.x * 2, kOneMinusEpsilon) : std::min((u.x - 0.5f) * 2, kOneMinusEpsilon);
    w = sample_cosine_hemisphere(u);
    if (!front) w.z = -w.z;
    *pdf_dir = cosine_hemisphere_pdf(std::abs(w.z)) * 0.5f;
  } else {
    w = sample_cosine_hemisphere(u);
    *pdf_dir = cosine_hemisphere_pdf(w.z);
  }
  return Frame::from_normal(n_emit).to_world(w);
}

float diffuse_emission_pdf(Vec3 n_emit, bool two_sided, Vec3 dir) {
  const float c = dot(n_emit, dir);
  return two_sided ? std::abs(c) * kInvPi * 0.5f : cosine_hemisphere_pdf(c);
}

// Solid-angle pdf of a uniformly area-sampled point: pdf_A * dist^2 / |cos at the light|.
float area_to_solid_angle(float inv_area, float dist2, float cos_light) {
  return cos_light > 0 ? inv_area * dist2 / cos_light : 0.f;
}

// The NEE record of a diffuse emitter: radiance L leaving p (oriented normal n) toward the
// reference point along -wi, with its solid-angle density and the emission densities the
// bidirectional core needs for MIS.
std::optional<LightLiSample> diffuse_li_sample(Rgb L, Vec3 p, Vec3 n, Vec3 wi, float dist,
                                               float pdf_w, float inv_area, bool two_sided) {
  if (!(pdf_w > 0) || !std::isfinite(pdf_w)) return std::nullopt;
  LightLiSample s;
  s.radiance = L;
  s.wi = wi;
  s.distance = dist;
  s.p_light = p;
  s.n_light = n;
  s.pdf_w = pdf_w;
  s.pdf_emit_pos = inv_area;
  s.pdf_emit_dir = diffuse_emission_pdf(n, two_sided, -wi);
  s.cos_at_light = abs_dot(n, wi);
  return s;
}

class TriangleAreaLight final : public Light {
 public:
  TriangleAreaLight(const TriangleMesh& mesh, size_t tri, Rgb radiance, bool two_sided)
      : L_(radiance), two_sided_(two_sided) {
    p_[0] = mesh.positions[mesh.indices[3 * tri]];
    p_[1] = mesh.positions[mesh.indices[3 * tri + 1]];
    p_[2] = mesh.positions[mesh.indices[3 * tri + 2]];
    n_ = mesh.face_normal(tri);
    area_ = mesh.area(tri);
    inv_area_ = area_ > 0 ? 1.f / area_ : 0.f;
  }

  LightType type() const override { return LightType::Area; }
  Rgb power() const override {
    return L_ * diffuse_area_light_power_per_radiance(area_, two_sided_);
  }

  std::optional<LightLiSample> sample_li(Vec3 ref, Vec2 u) const override {
    if (area_ <= 0) return std::nullopt;
    const Vec3 p = point_at(sample_uniform_triangle(u));
    const Vec3 d = p - ref;
    const float dist2 = length_squared(d);
    if (!(dist2 > 0)) return std::nullopt;
    const float dist = std::sqrt(dist2);
    const Vec3 wi = d / dist;
    if (!emits_toward(-wi)) return std::nullopt;
    const float cos_light = abs_dot(n_, wi);
    return diffuse_li_sample(L_, p, n_, wi, dist, area_to_solid_angle(inv_area_, dist2, cos_light),
                             inv_area_, two_sided_);
  }

  float pdf_li(Vec3 ref, Vec3 wi, Vec3 p_light, Vec3 n_light) const override {
    (void)n_light;
    if (!emits_toward(-wi)) return 0.f;
    return area_to_solid_angle(inv_area_, distance_squared(ref, p_light), abs_dot(n_, wi));
  }

  Rgb radiance(Vec3 p, Vec3 n, Vec2 uv, Vec3 w) const override {
    (void)p, (void)n, (void)uv;
    return emits_toward(w) ? L_ : Rgb();
  }

  std::optional<LightLeSample> sample_le(Vec2 u_pos, Vec2 u_dir) const override {
    if (area_ <= 0) return std::nullopt;
    LightLeSample s;
    s.p = point_at(sample_uniform_triangle(u_pos));
    s.n = n_;
    s.dir = sample_diffuse_emission(n_, two_sided_, u_dir, &s.pdf_dir);
    if (!(s.pdf_dir > 0)) return std::nullopt;
    s.pdf_pos = inv_area_;
    s.radiance = L_;
    s.cos_at_light = abs_dot(n_, s.dir);
    return s;
  }

  void pdf_le(Vec3 p, Vec3 n, Vec3 dir, float* pdf_pos, float* pdf_dir) const override {
    (void)p, (void)n;
    *pdf_pos = inv_area_;
    *pdf_dir = diffuse_emission_pdf(n_, two_sided_, dir);
  }

 private:
  Vec3 point_at(Vec2 b) const { return p_[0] * b.x + p_[1] * b.y + p_[2] * (1.f - b.x - b.y); }
  bool emits_toward(Vec3 w) const { return two_sided_ ? dot(n_, w) != 0.f : dot(n_, w) > 0.f; }

  Vec3 p_[3];
  Vec3 n_;  // oriented geometric normal: the emitting side
  float area_ = 0, inv_area_ = 0;
  Rgb L_;
  bool two_sided_;
};

class SphereAreaLight final : public Light {
 public:
  SphereAreaLight(const Sphere& sphere, Rgb radiance, bool two_sided)
      : c_(sphere.center),
        r_(sphere.radius),
        reverse_(sphere.reverse_orientation),
        L_(radiance),
        two_sided_(two_sided) {
    area_ = 4 * kPi * r_ * r_;
    inv_area_ = area_ > 0 ? 1.f / area_ : 0.f;
  }

  LightType type() const override { return LightType::Area; }
  Rgb power() const override {
    return L_ * diffuse_area_light_power_per_radiance(area_, two_sided_);
  }

  std::optional<LightLiSample> sample_li(Vec3 ref, Vec2 u) const override {
    if (!(r_ > 0)) return std::nullopt;
    Vec3 p;
    float pdf;
    const float dc2 = distance_squared(ref, c_);
    if (use_area_sampling(dc2)) {
      // Inside: uniform area sampling (every direction sees exactly one point).
      p = c_ + r_ * sample_uniform_sphere(u);
      pdf = -1;  // converted below, once the distance is known
    } else {
      // Outside: uniform in the cone subtended by the sphere (pbrt-v4 Sphere::Sample), and the
      // point on the sphere it reaches computed analytically (no ray-sphere intersection, which
      // loses precision near the silhouette). alpha is the angle at the centre between the
      // direction back to ref and the sampled point.
      const Cone cone = cone_from(distance_squared(ref, c_));
      float cos_theta = (cone.cos_max - 1) * u.x + 1;
      float sin2_theta = 1 - cos_theta * cos_theta;
      if (cone.small) {
        sin2_theta = cone.sin2_max * u.x;
        cos_theta = std::sqrt(1 - sin2_theta);
      }
      const float cos_alpha =
          sin2_theta / cone.sin_max + cos_theta * safe_sqrt(1 - sin2_theta / cone.sin2_max);
      const float sin_alpha = safe_sqrt(1 - cos_alpha * cos_alpha);
      const float phi = u.y * 2 * kPi;
      const Vec3 w(sin_alpha * std::cos(phi), sin_alpha * std::sin(phi), cos_alpha);
      const Frame frame = Frame::from_normal(normalize(c_ - ref));
      p = c_ + r_ * frame.to_world(-w);
      pdf = cone.pdf;
    }
    const Vec3 d = p - ref;
    const float dist2 = length_squared(d);
    if (!(dist2 > 0)) return std::nullopt;
    const float dist = std::sqrt(dist2);
    const Vec3 wi = d / dist;
    const Vec3 n = emit_normal(p);
    if (!emits_toward(n, -wi)) return std::nullopt;
    const float cos_light = abs_dot(n, wi);
    if (pdf < 0) pdf = area_to_solid_angle(inv_area_, dist2, cos_light);
    return diffuse_li_sample(L_, p, n, wi, dist, pdf, inv_area_, two_sided_);
  }

  // p_light must be where the ray (ref, wi) first hits the sphere.
  float pdf_li(Vec3 ref, Vec3 wi, Vec3 p_light, Vec3 n_light) const override {
    (void)n_light;
    if (!(r_ > 0)) return 0.f;
    const Vec3 n = emit_normal(p_light);
    if (!emits_toward(n, -wi)) return 0.f;
    const float dc2 = distance_squared(ref, c_);
    if (use_area_sampling(dc2))
      return area_to_solid_angle(inv_area_, distance_squared(ref, p_light), abs_dot(n, wi));
    return cone_from(dc2).pdf;
  }

  Rgb radiance(Vec3 p, Vec3 n, Vec2 uv, Vec3 w) const override {
    (void)n, (void)uv;
    return emits_toward(emit_normal(p), w) ? L_ : Rgb();
  }

  std::optional<LightLeSample> sample_le(Vec2 u_pos, Vec2 u_dir) const override {
    if (!(r_ > 0)) return std::nullopt;
    LightLeSample s;
    const Vec3 n_out = sample_uniform_sphere(u_pos);
    s.p = c_ + r_ * n_out;
    s.n = reverse_ ? -n_out : n_out;
    s.dir = sample_diffuse_emission(s.n, two_sided_, u_dir, &s.pdf_dir);
    if (!(s.pdf_dir > 0)) return std::nullopt;
    s.pdf_pos = inv_area_;
    s.radiance = L_;
    s.cos_at_light = abs_dot(s.n, s.dir);
    return s;
  }

  void pdf_le(Vec3 p, Vec3 n, Vec3 dir, float* pdf_pos, float* pdf_dir) const override {
    (void)n;
    *pdf_pos = inv_area_;
    *pdf_dir = diffuse_emission_pdf(emit_normal(p), two_sided_, dir);
  }

 private:
  // Points on the sphere itself (shading points of the emitter, which land on either side of it
  // by rounding) count as inside, so that they see the whole sphere by area sampling; pbrt-v4
  // gets the same effect by offsetting the reference point along its normal first. Cone
  // sampling from there would collapse onto ref's own neighbourhood. Area sampling from a
  // point just outside stays unbiased (the far side is then occluded by the near side).
  bool treat_as_inside(Vec3 ref) const {
    return distance_squared(ref, c_) <= r_ * r_ * (1 + 1e-4f);
  }

  struct Cone {
    float sin2_max, sin_max, cos_max, pdf;
    bool small;  // below ~1.5 degrees: 1 - cos_max by its Taylor series (pbrt-v4)
  };
  // Inside, or on the surface up to rounding (a reference point on this very sphere, as in
  // the furnace): uniform area sampling, valid from anywhere. The cone of a point on the
  // surface degenerates to a hemisphere whose "nearest points" collapse onto the point itself;
  // pbrt-v4 avoids it by offsetting the reference point, we by a relative tolerance. Shared by
  // sample_li and pdf_li so both always take the same branch.
  bool use_area_sampling(float dist_to_center2) const {
    return dist_to_center2 <= r_ * r_ * (1.f + 1e-4f);
  }
  // Shared by sample_li and pdf_li so that both report bit-identical densities.
  Cone cone_from(float dist_to_center2) const {
    Cone c;
    c.sin2_max = r_ * r_ / dist_to_center2;
    c.sin_max = std::sqrt(c.sin2_max);
    c.cos_max = safe_sqrt(1 - c.sin2_max);
    c.small = c.sin2_max < 0.00068523f;  // sin^2(1.5 degrees)
    const float one_minus_cos_max = c.small ? c.sin2_max / 2 : 1 - c.cos_max;
    c.pdf = 1.f / (2 * kPi * one_minus_cos_max);
    return c;
  }
  Vec3 emit_normal(Vec3 p) const {
    const Vec3 n = normalize(p - c_);
    return reverse_ ? -n : n;
  }
  bool emits_toward(Vec3 n, Vec3 w) const {
    return two_sided_ ? dot(n, w) != 0.f : dot(n, w) > 0.f;
  }

  Vec3 c_;
  float r_;
  bool reverse_;
  float area_ = 0, inv_area_ = 0;
  Rgb L_;
  bool two_sided_;
};

}  // namespace

LightPtr make_triangle_area_light(const TriangleMesh& mesh, size_t tri, Rgb radiance,
                                  bool two_sided) {
  return std::make_shared<TriangleAreaLight>(mesh, tri, radiance, two_sided);
}

LightPtr make_sphere_area_light(const Sphere& sphere, Rgb radiance, bool two_sided) {
  return std::make_shared<SphereAreaLight>(sphere, radiance, two_sided);
}

}  // namespace caustica
