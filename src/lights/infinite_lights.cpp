// Lights at infinity: distant (pbrt-v4 DistantLight), uniform environment (UniformInfiniteLight)
// and image environment (ImageInfiniteLight, plus a lat-long mapping pbrt-v4 does not have).
//
// Parameters: distant: direction (propagation, to - from), radiance L. Uniform: radiance L.
// Image: image (linear RGB), mapping (equal-area octahedral or lat-long), light_to_world
// (rotation orienting the map), scale (multiplies every texel).
//
// Emission of light subpaths (pbrt-v4 SampleLe): a direction, then an origin uniform on the disk
// of radius R (the scene's bounding radius from preprocess) perpendicular to it, centred on the
// scene and moved R back against the direction, so the ray starts outside the scene. Hence
// pdf_pos = 1 / (pi R^2) and power = pi R^2 * integral of L over directions. The emission normal
// is the propagation direction (cos_at_light = 1).
#include <cmath>
#include <vector>

#include "core/distribution.h"
#include "core/frame.h"
#include "core/warp.h"
#include "image/image.h"
#include "lights/env_mapping.h"
#include "lights/lights.h"

namespace caustica {

namespace {

// State shared by the lights at infinity: the scene's bounding sphere.
class InfiniteLightBase : public Light {
 public:
  void preprocess(Vec3 scene_center, float scene_radius) override {
    center_ = scene_center;
    radius_ = scene_radius;
  }

 protected:
  float disk_pdf() const { return radius_ > 0 ? 1.f / (kPi * radius_ * radius_) : 0.f; }
  float disk_area() const { return kPi * radius_ * radius_; }
  // Origin for a ray propagating along dir that covers the scene's bounding sphere.
  Vec3 disk_origin(Vec3 dir, Vec2 u) const {
    const Frame f = Frame::from_normal(dir);
    const Vec2 d = sample_uniform_disk_concentric(u);
    return center_ + radius_ * (f.s * d.x + f.t * d.y) - dir * radius_;
  }
  // A point beyond the scene along wi from ref, for shadow rays (pbrt-v4: 2R away).
  Vec3 far_point(Vec3 ref, Vec3 wi) const { return ref + wi * (2 * radius_); }

  LightLiSample li_sample(Vec3 ref, Vec3 wi, Rgb radiance, float pdf_w, float pdf_emit_dir) const {
    LightLiSample s;
    s.radiance = radiance;
    s.wi = wi;
    s.distance = kInfinity;
    s.p_light = far_point(ref, wi);
    s.n_light = -wi;
    s.pdf_w = pdf_w;
    s.pdf_emit_pos = disk_pdf();
    s.pdf_emit_dir = pdf_emit_dir;
    s.cos_at_light = 1;
    return s;
  }
  LightLeSample le_sample(Vec3 dir, Vec2 u_pos, Rgb radiance, float pdf_dir) const {
    LightLeSample s;
    s.radiance = radiance;
    s.p = disk_origin(dir, u_pos);
    s.n = dir;
    s.dir = dir;
    s.pdf_pos = disk_pdf();
    s.pdf_dir = pdf_dir;
    s.cos_at_light = 1;
    return s;
  }

  Vec3 center_;
  float radius_ = 0;
};

class DistantLight final : public InfiniteLightBase {
 public:
  DistantLight(Vec3 direction, Rgb radiance) : dir_(normalize(direction)), L_(radiance) {}

  LightType type() const override { return LightType::DeltaDirection; }
  Rgb power() const override { return L_ * disk_area(); }

  std::optional<LightLiSample> sample_li(Vec3 ref, Vec2 u) const override {
    (void)u;
    // Delta in direction: pdf_w = 1 by convention, and emission's pdf_dir is 1 likewise.
    return li_sample(ref, -dir_, L_, 1.f, 1.f);
  }
  float pdf_li(Vec3, Vec3, Vec3, Vec3) const override { return 0.f; }

  std::optional<LightLeSample> sample_le(Vec2 u_pos, Vec2 u_dir) const override {
    (void)u_dir;
    return le_sample(dir_, u_pos, L_, 1.f);
  }
  // The light emits along its one direction only; dir is not checked.
  void pdf_le(Vec3, Vec3, Vec3, float* pdf_pos, float* pdf_dir) const override {
    *pdf_pos = disk_pdf();
    *pdf_dir = 1.f;
  }

 private:
  Vec3 dir_;  // propagation direction
  Rgb L_;
};

// NEE samples the sphere uniformly (as pbrt-v4 without MIS compensation): pdf_w = 1 / 4pi.
class UniformEnvironment final : public InfiniteLightBase {
 public:
  explicit UniformEnvironment(Rgb radiance) : L_(radiance) {}

  LightType type() const override { return LightType::Infinite; }
  Rgb power() const override { return L_ * (4 * kPi * disk_area()); }

  std::optional<LightLiSample> sample_li(Vec3 ref, Vec2 u) const override {
    return li_sample(ref, sample_uniform_sphere(u), L_, uniform_sphere_pdf(), uniform_sphere_pdf());
  }
  float pdf_li(Vec3, Vec3, Vec3, Vec3) const override { return uniform_sphere_pdf(); }
  Rgb radiance_escaped(Vec3) const override { return L_; }

  std::optional<LightLeSample> sample_le(Vec2 u_pos, Vec2 u_dir) const override {
    return le_sample(sample_uniform_sphere(u_dir), u_pos, L_, uniform_sphere_pdf());
  }
  void pdf_le(Vec3, Vec3, Vec3, float* pdf_pos, float* pdf_dir) const override {
    *pdf_pos = disk_pdf();
    *pdf_dir = uniform_sphere_pdf();
  }

 private:
  Rgb L_;
};

// Radiance is looked up at the nearest texel, as pbrt-v4's ImageInfiniteLight does, so the map is
// piecewise constant and a distribution proportional to texel luminance (times the mapping's
// solid angle per texel) samples it exactly in proportion to luminance.
class ImageEnvironment final : public InfiniteLightBase {
 public:
  ImageEnvironment(std::shared_ptr<const Image> image, EnvironmentMapping mapping,
                   const Transform& light_to_world, Rgb scale)
      : image_(std::move(image)),
        mapping_(mapping),
        light_to_world_(light_to_world),
        world_to_light_(light_to_world.inverse()),
        scale_(scale) {
    if (!image_ || image_->empty()) image_ = std::make_shared<Image>(1, 1, Rgb(0.f));
    const int w = image_->width(), h = image_->height();
    std::vector<float> weights(size_t(w) * h);
    Rgb flux_per_r2(0.f);  // integral of L over the sphere
    for (int y = 0; y < h; ++y) {
      const float row_solid_angle = texel_solid_angle(y);
      for (int x = 0; x < w; ++x) {
        const Rgb L = texel(x, y);
        // The row's solid angle is exact for the map's cells, so the distribution's density in
        // uv divided by the mapping's Jacobian is proportional to luminance in solid angle.
        weights[size_t(y) * w + x] = std::max(0.f, L.luminance()) * row_solid_angle;
        flux_per_r2 += L * row_solid_angle;
      }
    }
    radiance_integral_ = flux_per_r2;
    distribution_ = Distribution2D(weights, w, h);
  }

  LightType type() const override { return LightType::Infinite; }
  Rgb power() const override { return radiance_integral_ * disk_area(); }

  std::optional<LightLiSample> sample_li(Vec3 ref, Vec2 u) const override {
    float map_pdf;
    const Vec2 uv = distribution_.sample(u, &map_pdf);
    if (!(map_pdf > 0)) return std::nullopt;
    const Vec3 wi = normalize(light_to_world_.vector(to_sphere(uv)));
    // Radiance and density are re-evaluated from wi, the way radiance_escaped and pdf_li see
    // it, so all three agree even when rounding moves wi across a texel edge.
    float pdf;
    const Rgb L = lookup(wi, &pdf);
    if (!(pdf > 0)) return std::nullopt;
    return li_sample(ref, wi, L, pdf, pdf);
  }
  float pdf_li(Vec3, Vec3 wi, Vec3, Vec3) const override {
    float pdf;
    lookup(wi, &pdf);
    return pdf;
  }
  Rgb radiance_escaped(Vec3 d) const override { return lookup(d, nullptr); }

  std::optional<LightLeSample> sample_le(Vec2 u_pos, Vec2 u_dir) const override {
    float map_pdf;
    const Vec2 uv = distribution_.sample(u_dir, &map_pdf);
    if (!(map_pdf > 0)) return std::nullopt;
    const Vec3 wi = normalize(light_to_world_.vector(to_sphere(uv)));  // toward the light
    float pdf;
    const Rgb L = lookup(wi, &pdf);
    if (!(pdf > 0)) return std::nullopt;
    return le_sample(-wi, u_pos, L, pdf);
  }
  void pdf_le(Vec3, Vec3, Vec3 dir, float* pdf_pos, float* pdf_dir) const override {
    *pdf_pos = disk_pdf();
    lookup(-dir, pdf_dir);
  }

 private:
  Rgb texel(int x, int y) const { return image_->at(x, y) * scale_; }

  // Solid angle of one texel in row y: 4pi / (w h) for the equal-area map; for lat-long the
  // exact band (cos theta0 - cos theta1) * 2pi / w.
  float texel_solid_angle(int y) const {
    const int w = image_->width(), h = image_->height();
    if (mapping_ == EnvironmentMapping::EqualAreaOctahedral) return 4 * kPi / (float(w) * float(h));
    const double t0 = M_PI * y / h, t1 = M_PI * (y + 1) / h;
    return float((std::cos(t0) - std::cos(t1)) * 2 * M_PI / w);
  }

  Vec3 to_sphere(Vec2 uv) const {
    return mapping_ == EnvironmentMapping::EqualAreaOctahedral ? equal_area_square_to_sphere(uv)
                                                               : lat_long_to_sphere(uv);
  }

  // Radiance arriving along world direction wi (toward the light) and, if pdf is given, the
  // solid-angle density with which sample_li picks it.
  Rgb lookup(Vec3 wi, float* pdf) const {
    const Vec3 wl = normalize(world_to_light_.vector(wi));
    Vec2 uv = mapping_ == EnvironmentMapping::EqualAreaOctahedral ? equal_area_sphere_to_square(wl)
                                                                  : lat_long_from_sphere(wl);
    uv.x = clamp(uv.x, 0.f, kOneMinusEpsilon);
    uv.y = clamp(uv.y, 0.f, kOneMinusEpsilon);
    if (pdf) {
      // d omega = 4 pi du dv (equal-area) or 2 pi^2 sin(theta) du dv (lat-long).
      const float map_pdf = distribution_.pdf(uv);
      if (mapping_ == EnvironmentMapping::EqualAreaOctahedral) {
        *pdf = map_pdf * kInv4Pi;
      } else {
        const float sin_theta = safe_sqrt(1 - wl.z * wl.z);
        *pdf = sin_theta > 0 ? map_pdf / (2 * kPi * kPi * sin_theta) : 0.f;
      }
    }
    const int x = std::min(int(uv.x * float(image_->width())), image_->width() - 1);
    const int y = std::min(int(uv.y * float(image_->height())), image_->height() - 1);
    return texel(x, y);
  }

  std::shared_ptr<const Image> image_;
  EnvironmentMapping mapping_;
  Transform light_to_world_, world_to_light_;
  Rgb scale_;
  Distribution2D distribution_;
  Rgb radiance_integral_;
};

}  // namespace

LightPtr make_distant_light(Vec3 direction, Rgb radiance) {
  return std::make_shared<DistantLight>(direction, radiance);
}

LightPtr make_uniform_environment(Rgb radiance) {
  return std::make_shared<UniformEnvironment>(radiance);
}

LightPtr make_image_environment(std::shared_ptr<const Image> image, EnvironmentMapping mapping,
                                const Transform& light_to_world, Rgb scale) {
  return std::make_shared<ImageEnvironment>(std::move(image), mapping, light_to_world, scale);
}

}  // namespace caustica
