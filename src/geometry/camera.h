// Perspective camera with pbrt-v4's semantics: camera space is left-handed (+z forward,
// +y up, +x toward raster +x), `fov` spans the shorter image axis, raster y grows downward.
// A lens radius > 0 makes it a thin-lens camera focused at `focal_distance`.
//
// Importance (for light tracing, pbrt-v4 PerspectiveCamera::We): We is normalised over the
// whole image, We = 1 / (A * lens_area * cos^4 theta), with A the image-plane area at
// distance 1 and lens_area = 1 for a pinhole. Pixel p's importance is
// pixel_count() * We * f(r - c_p) / integral f for the pixel filter f (render/pixel_filter.h):
// with the box of radius 1/2, pixel_count() * We inside the pixel.
//
// The film's sensitive region is the image widened by the filter radius less half a pixel
// (pbrt-v4's Film::SampleBounds): camera samples of border pixels land there, so raster_of,
// importance and pdf_we accept it too (We keeps the normalisation of the nominal image).
#pragma once

#include <optional>

#include "core/transform.h"
#include "core/vec.h"
#include "geometry/pixel_filter_params.h"

namespace caustica {

struct CameraParams {
  Transform camera_to_world;
  int width = 512, height = 512;
  float fov_degrees = 90;
  float lens_radius = 0;
  float focal_distance = 1e6f;
  // Optional pbrt "screenwindow" [xmin xmax ymin ymax]; empty = derived from aspect ratio.
  float screen_window[4] = {0, 0, 0, 0};
  // The pixel filter (pbrt-v4's PixelFilter). Built-in and glTF scenes keep this box of radius
  // 1/2; the pbrt loader sets what the file names, else pbrt-v4's default gaussian.
  PixelFilterParams filter;
};

struct CameraWiSample {
  float importance = 0;  // We along the ray from the lens point to ref
  Vec3 wi;               // unit, from ref toward the lens point
  float distance = 0;
  Vec3 p_lens;              // the point on the lens (world)
  float pdf_w = 0;          // solid-angle density at ref of choosing this lens point
  Vec2 raster;              // where the ray lands on the film
  float cos_at_camera = 0;  // cos between the camera axis and the direction to ref
};

class Camera {
 public:
  Camera() = default;
  explicit Camera(const CameraParams& params);

  int width() const { return width_; }
  int height() const { return height_; }
  size_t pixel_count() const { return size_t(width_) * size_t(height_); }
  Vec3 position() const { return origin_; }
  Vec3 forward() const { return forward_; }
  bool is_pinhole() const { return lens_radius_ == 0; }
  float lens_area() const;
  float image_plane_area() const { return image_plane_area_; }
  const PixelFilterParams& pixel_filter() const { return filter_; }

  // Ray through continuous raster position (x right, y down, in pixels) and lens sample.
  Ray generate_ray(Vec2 raster, Vec2 u_lens) const;

  // Raster position of the camera ray with direction dir leaving p_lens; nothing if it
  // misses the film's sensitive region (see above) or points backward.
  std::optional<Vec2> raster_of(Vec3 p_lens, Vec3 dir) const;
  // Raster position of a world point seen through a pinhole (convenience for tests).
  std::optional<Vec2> project(Vec3 p) const { return raster_of(origin_, normalize(p - origin_)); }

  float importance(Vec3 p_lens, Vec3 dir) const;  // We(p_lens, dir): 0 off the film
  // Densities of a camera ray leaving the lens point p_lens along dir (pbrt-v4 PDF_We): the film
  // test uses the point the ray left from, so thin-lens rays near the border are not lost.
  void pdf_we(Vec3 p_lens, Vec3 dir, float* pdf_pos, float* pdf_dir) const;
  // pdf_we's direction density for a ray already known to reach the film (the raster position of
  // a sample_wi): the same value without repeating the film test.
  float pdf_dir_on_film(Vec3 dir) const {
    const float cos_theta = dot(dir, forward_);
    return cos_theta > 0 ? 1.f / (image_plane_area_ * cos_theta * cos_theta * cos_theta) : 0.f;
  }
  std::optional<CameraWiSample> sample_wi(Vec3 ref, Vec2 u_lens) const;

 private:
  Transform camera_to_world_, world_to_camera_;
  int width_ = 0, height_ = 0;
  float lens_radius_ = 0, focal_distance_ = 1;
  float screen_min_x_ = -1, screen_max_x_ = 1, screen_min_y_ = -1, screen_max_y_ = 1;
  float tan_half_fov_ = 1;
  PixelFilterParams filter_;
  Vec2 film_margin_;  // pixels beyond the image that still reach a pixel: filter radius - 1/2
  float image_plane_area_ = 4;
  Vec3 origin_, forward_;
};

}  // namespace caustica
