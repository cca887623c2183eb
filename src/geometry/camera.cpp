#include "geometry/camera.h"

#include <algorithm>
#include <cmath>

#include "core/warp.h"

namespace caustica {

Camera::Camera(const CameraParams& p)
    : camera_to_world_(p.camera_to_world),
      world_to_camera_(p.camera_to_world.inverse()),
      width_(p.width),
      height_(p.height),
      lens_radius_(p.lens_radius),
      focal_distance_(p.focal_distance),
      filter_(p.filter),
      film_margin_(std::max(0.f, p.filter.radius.x - 0.5f),
                   std::max(0.f, p.filter.radius.y - 0.5f)) {
  const float aspect = float(width_) / float(height_);
  if (p.screen_window[0] != p.screen_window[1]) {
    screen_min_x_ = p.screen_window[0];
    screen_max_x_ = p.screen_window[1];
    screen_min_y_ = p.screen_window[2];
    screen_max_y_ = p.screen_window[3];
  } else if (aspect > 1) {  // fov spans the shorter (vertical) axis
    screen_min_x_ = -aspect;
    screen_max_x_ = aspect;
  } else {
    screen_min_y_ = -1.f / aspect;
    screen_max_y_ = 1.f / aspect;
  }
  tan_half_fov_ = std::tan(radians(p.fov_degrees) * 0.5f);
  image_plane_area_ =
      (screen_max_x_ - screen_min_x_) * (screen_max_y_ - screen_min_y_) * sqr(tan_half_fov_);
  origin_ = camera_to_world_.point({0, 0, 0});
  forward_ = normalize(camera_to_world_.vector({0, 0, 1}));
}

float Camera::lens_area() const { return lens_radius_ > 0 ? kPi * sqr(lens_radius_) : 1.f; }

Ray Camera::generate_ray(Vec2 raster, Vec2 u_lens) const {
  const float sx = screen_min_x_ + raster.x / float(width_) * (screen_max_x_ - screen_min_x_);
  const float sy = screen_max_y_ - raster.y / float(height_) * (screen_max_y_ - screen_min_y_);
  Vec3 dir = normalize(Vec3(sx * tan_half_fov_, sy * tan_half_fov_, 1.f));
  Vec3 o(0, 0, 0);
  if (lens_radius_ > 0) {
    const Vec2 lens = sample_uniform_disk_concentric(u_lens) * lens_radius_;
    const Vec3 focus = dir * (focal_distance_ / dir.z);
    o = Vec3(lens.x, lens.y, 0);
    dir = normalize(focus - o);
  }
  return {camera_to_world_.point(o), normalize(camera_to_world_.vector(dir)), kInfinity};
}

std::optional<Vec2> Camera::raster_of(Vec3 p_lens, Vec3 dir) const {
  Vec3 d = normalize(world_to_camera_.vector(dir));
  if (d.z <= 0) return std::nullopt;
  // Thin lens: the film point is where the ray crosses the plane of focus, seen from the lens
  // centre. A pinhole ray already starts at the centre.
  if (lens_radius_ > 0) d = world_to_camera_.point(p_lens) + d * (focal_distance_ / d.z);
  const float sx = d.x / d.z / tan_half_fov_, sy = d.y / d.z / tan_half_fov_;
  const float rx = (sx - screen_min_x_) / (screen_max_x_ - screen_min_x_) * float(width_);
  const float ry = (screen_max_y_ - sy) / (screen_max_y_ - screen_min_y_) * float(height_);
  if (!(rx >= -film_margin_.x && rx < float(width_) + film_margin_.x && ry >= -film_margin_.y &&
        ry < float(height_) + film_margin_.y))
    return std::nullopt;
  return Vec2(rx, ry);
}

float Camera::importance(Vec3 p_lens, Vec3 dir) const {
  const float cos_theta = dot(dir, forward_);
  if (cos_theta <= 0 || !raster_of(p_lens, dir)) return 0.f;
  return 1.f / (image_plane_area_ * lens_area() * sqr(sqr(cos_theta)));
}

void Camera::pdf_we(Vec3 p_lens, Vec3 dir, float* pdf_pos, float* pdf_dir) const {
  const float cos_theta = dot(dir, forward_);
  if (cos_theta <= 0 || !raster_of(p_lens, dir)) {
    *pdf_pos = *pdf_dir = 0;
    return;
  }
  *pdf_pos = 1.f / lens_area();
  *pdf_dir = pdf_dir_on_film(dir);
}

std::optional<CameraWiSample> Camera::sample_wi(Vec3 ref, Vec2 u_lens) const {
  Vec3 p_lens = origin_;
  if (lens_radius_ > 0) {
    const Vec2 l = sample_uniform_disk_concentric(u_lens) * lens_radius_;
    p_lens = camera_to_world_.point({l.x, l.y, 0});
  }
  const Vec3 to_ref = ref - p_lens;
  const float dist2 = length_squared(to_ref);
  if (dist2 == 0) return std::nullopt;
  const float dist = std::sqrt(dist2);
  const Vec3 dir = to_ref / dist;  // leaving the camera
  const float cos_theta = dot(dir, forward_);
  if (cos_theta <= 0) return std::nullopt;
  const auto raster = raster_of(p_lens, dir);
  if (!raster) return std::nullopt;
  CameraWiSample s;
  s.importance = 1.f / (image_plane_area_ * lens_area() * sqr(sqr(cos_theta)));
  s.wi = -dir;
  s.distance = dist;
  s.p_lens = p_lens;
  s.pdf_w = dist2 / (cos_theta * lens_area());
  s.raster = *raster;
  s.cos_at_camera = cos_theta;
  return s;
}

}  // namespace caustica
