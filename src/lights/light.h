// The light interface. Every light serves both next event estimation from a camera path
// (sample_li / pdf_li) and emission of light subpaths (sample_le / pdf_le), with all the
// densities the bidirectional core needs for MIS. Densities never include the light
// selection probability: that comes from the scene's one LightSampler.
//
// Measures: pdf_w are solid angle at the receiving point; pdf_pos is area density on the
// light (for distant and infinite lights: on the disk of radius R that covers the scene,
// perpendicular to the direction, 1/(pi R^2)); pdf_dir is solid angle around the emission
// point. Delta lights report pdf_w = 1 (and is_delta()), so MIS gives their NEE weight 1.
#pragma once

#include <cstdint>
#include <memory>
#include <optional>

#include "core/rgb.h"
#include "core/vec.h"
#include "geometry/medium.h"

namespace caustica {

enum class LightType : uint8_t {
  DeltaPosition,   // point, spot
  DeltaDirection,  // distant
  Area,            // diffuse emitter on a triangle or sphere: can be hit by rays
  Infinite,        // environment: seen by rays that escape the scene
};

struct LightLiSample {
  Rgb radiance;            // radiance (intensity / dist^2 for point lights) arriving at ref
  Vec3 wi;                 // unit direction from ref toward the light
  float distance = 0;      // from ref to p_light; kInfinity for distant and infinite lights
  Vec3 p_light;            // the sampled point on the light (shadow ray target)
  Vec3 n_light;            // the light's surface normal there (zero for point-like lights)
  float pdf_w = 0;         // solid-angle density at ref of this sample (1 for delta lights)
  float pdf_emit_pos = 0;  // what pdf_le would report for (p_light, -wi): area density
  float pdf_emit_dir = 0;  // ... and solid-angle density of direction -wi
  float cos_at_light = 1;  // |cos| between -wi and n_light (1 for point-like lights)
};

struct LightLeSample {
  Rgb radiance;            // emitted radiance (intensity for point lights) along dir
  Vec3 p;                  // emission point
  Vec3 n;                  // surface normal at p (zero for point lights, = dir for distant/env)
  Vec3 dir;                // unit propagation direction, leaving the light
  float pdf_pos = 0;       // area density of p
  float pdf_dir = 0;       // solid-angle density of dir
  float cos_at_light = 1;  // |cos(n, dir)| (1 for point lights, distant and env)
};

class Light {
 public:
  virtual ~Light() = default;
  virtual LightType type() const = 0;
  bool is_delta() const {
    return type() == LightType::DeltaPosition || type() == LightType::DeltaDirection;
  }
  bool is_infinite() const {
    return type() == LightType::Infinite || type() == LightType::DeltaDirection;
  }

  // Called once with the scene bounds before rendering (infinite lights need the radius).
  virtual void preprocess(Vec3 scene_center, float scene_radius) {
    (void)scene_center;
    (void)scene_radius;
  }
  // Total emitted power (flux), for the power-based light distribution.
  virtual Rgb power() const = 0;

  // --- Next event estimation ----------------------------------------------------------
  virtual std::optional<LightLiSample> sample_li(Vec3 ref, Vec2 u) const = 0;
  // Density of sample_li at ref for direction wi reaching the light at (p_light, n_light).
  // Infinite lights read only wi. Delta lights return 0 (they cannot be hit).
  virtual float pdf_li(Vec3 ref, Vec3 wi, Vec3 p_light, Vec3 n_light) const = 0;

  // --- Radiance seen by a ray that hits the light ----------------------------------------
  // Area lights: radiance leaving point p with normal n (the primitive's geometric normal)
  // and uv, toward w (unit, pointing away from the light).
  virtual Rgb radiance(Vec3 p, Vec3 n, Vec2 uv, Vec3 w) const {
    (void)p;
    (void)n;
    (void)uv;
    (void)w;
    return {};
  }
  // Infinite lights: radiance arriving along a ray that escaped in direction d (unit).
  virtual Rgb radiance_escaped(Vec3 d) const {
    (void)d;
    return {};
  }

  // --- Emission of light subpaths ----------------------------------------------------------
  virtual std::optional<LightLeSample> sample_le(Vec2 u_pos, Vec2 u_dir) const = 0;
  // Densities of sample_le emitting from p (normal n) along dir (leaving the light).
  // Infinite lights read only dir (the propagation direction, pointing into the scene).
  virtual void pdf_le(Vec3 p, Vec3 n, Vec3 dir, float* pdf_pos, float* pdf_dir) const = 0;

  // Index in the scene's light list (set by the scene), used to look up selection pmfs.
  uint32_t index = 0;
  // An area light's surface may bound media: an end of a segment on it names the medium on its
  // side (geometry/medium.h). Other lights name none.
  MediumInterface media;
  SegmentEnd medium_toward(Vec3 n, Vec3 w) const { return segment_end(media, n, w); }
};

using LightPtr = std::shared_ptr<Light>;

}  // namespace caustica
