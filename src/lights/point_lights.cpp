// Point-like lights (pbrt-v4's PointLight and SpotLight). Parameters: position, intensity I
// (radiant intensity, linear RGB); the spot adds its axis, cone_angle (total half-angle, deg)
// and cone_delta (width of the smoothstep falloff band, deg).
//
// Delta positions: sample_li reports pdf_w = 1 and pdf_li is 0. Emission reports pdf_pos = 1
// (the delta's weight, as pbrt-v4's SampleLe does) from both sample_le and pdf_le, so that the
// bidirectional core's ratios of emission to direct pdfs stay finite.
#include <cmath>

#include "core/frame.h"
#include "core/warp.h"
#include "lights/light_power.h"
#include "lights/lights.h"

namespace caustica {

namespace {

class PointLight final : public Light {
 public:
  PointLight(Vec3 position, Rgb intensity) : p_(position), I_(intensity) {}

  LightType type() const override { return LightType::DeltaPosition; }
  Rgb power() const override { return I_ * point_light_power_per_intensity(); }

  std::optional<LightLiSample> sample_li(Vec3 ref, Vec2 u) const override {
    (void)u;
    const Vec3 d = p_ - ref;
    const float dist2 = length_squared(d);
    if (!(dist2 > 0)) return std::nullopt;
    const float dist = std::sqrt(dist2);
    LightLiSample s;
    s.wi = d / dist;
    s.distance = dist;
    s.radiance = I_ / dist2;
    s.p_light = p_;
    s.pdf_w = 1;
    s.pdf_emit_pos = 1;
    s.pdf_emit_dir = uniform_sphere_pdf();
    return s;
  }
  float pdf_li(Vec3, Vec3, Vec3, Vec3) const override { return 0.f; }

  std::optional<LightLeSample> sample_le(Vec2 u_pos, Vec2 u_dir) const override {
    (void)u_pos;
    LightLeSample s;
    s.p = p_;
    s.dir = sample_uniform_sphere(u_dir);
    s.radiance = I_;
    s.pdf_pos = 1;
    s.pdf_dir = uniform_sphere_pdf();
    return s;
  }
  void pdf_le(Vec3, Vec3, Vec3, float* pdf_pos, float* pdf_dir) const override {
    *pdf_pos = 1;
    *pdf_dir = uniform_sphere_pdf();
  }

 private:
  Vec3 p_;
  Rgb I_;
};

float smoothstep(float a, float b, float x) {
  if (a == b) return x < a ? 0.f : 1.f;
  const float t = clamp((x - a) / (b - a), 0.f, 1.f);
  return t * t * (3 - 2 * t);
}

class SpotLight final : public Light {
 public:
  SpotLight(Vec3 position, Vec3 direction, Rgb intensity, float cone_angle, float cone_delta)
      : p_(position), frame_(Frame::from_normal(normalize(direction))), I_(intensity) {
    // pbrt-v4: cosFalloffEnd = cos(coneangle), cosFalloffStart = cos(coneangle - conedelta).
    // The start angle is clamped to [0, coneangle] so a delta wider than the cone is a full
    // falloff rather than pbrt's reflected angle.
    cone_angle = clamp(cone_angle, 0.f, 180.f);
    cos_end_ = std::cos(radians(cone_angle));
    cos_start_ = std::cos(radians(clamp(cone_angle - cone_delta, 0.f, cone_angle)));
  }

  LightType type() const override { return LightType::DeltaPosition; }
  Rgb power() const override { return I_ * spot_light_power_per_intensity(cos_start_, cos_end_); }

  std::optional<LightLiSample> sample_li(Vec3 ref, Vec2 u) const override {
    (void)u;
    const Vec3 d = p_ - ref;
    const float dist2 = length_squared(d);
    if (!(dist2 > 0)) return std::nullopt;
    const float dist = std::sqrt(dist2);
    const Vec3 wi = d / dist;
    const float cos_axis = dot(frame_.n, -wi);
    const Rgb I = intensity(cos_axis);
    if (I.is_black()) return std::nullopt;
    LightLiSample s;
    s.wi = wi;
    s.distance = dist;
    s.radiance = I / dist2;
    s.p_light = p_;
    s.pdf_w = 1;
    s.pdf_emit_pos = 1;
    s.pdf_emit_dir = dir_pdf(cos_axis);
    return s;
  }
  float pdf_li(Vec3, Vec3, Vec3, Vec3) const override { return 0.f; }

  std::optional<LightLeSample> sample_le(Vec2 u_pos, Vec2 u_dir) const override {
    (void)u_pos;
    const Vec3 local = sample_uniform_cone(u_dir, cos_end_);
    LightLeSample s;
    s.p = p_;
    s.dir = frame_.to_world(local);
    s.radiance = intensity(local.z);
    s.pdf_pos = 1;
    s.pdf_dir = uniform_cone_pdf(cos_end_);
    return s;
  }
  void pdf_le(Vec3, Vec3, Vec3 dir, float* pdf_pos, float* pdf_dir) const override {
    *pdf_pos = 1;
    *pdf_dir = dir_pdf(dot(frame_.n, dir));
  }

  // Intensity toward a direction at cos_axis from the spot axis (pbrt-v4 SpotLight::I).
  Rgb intensity(float cos_axis) const { return I_ * smoothstep(cos_end_, cos_start_, cos_axis); }

 private:
  float dir_pdf(float cos_axis) const {
    return cos_axis >= cos_end_ ? uniform_cone_pdf(cos_end_) : 0.f;
  }

  Vec3 p_;
  Frame frame_;  // n = spot axis
  Rgb I_;
  float cos_start_, cos_end_;
};

}  // namespace

LightPtr make_point_light(Vec3 position, Rgb intensity) {
  return std::make_shared<PointLight>(position, intensity);
}

LightPtr make_spot_light(Vec3 position, Vec3 direction, Rgb intensity, float cone_angle_degrees,
                         float cone_delta_degrees) {
  return std::make_shared<SpotLight>(position, direction, intensity, cone_angle_degrees,
                                     cone_delta_degrees);
}

}  // namespace caustica
