// The immutable scene: geometry in an Embree BVH, materials, lights, the camera, and the
// one power-based light distribution. Integrators trace rays only through this class.
#pragma once

#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "core/vec.h"
#include "geometry/camera.h"
#include "geometry/interaction.h"
#include "geometry/shapes.h"
#include "geometry/texture.h"

namespace caustica {

class Material;
class Light;
class LightSampler;
struct TriangleVertices;

// Render settings a scene file may carry (pbrt's Sampler/Integrator/Film); the CLI overrides.
struct SceneSettings {
  int spp = 0;              // 0: not set by the scene
  int max_depth = 0;        // 0: not set
  std::string integrator;   // empty: not set
  std::string output_name;  // pbrt Film "filename", informational
};

// Everything a loader or built-in scene hands over. Area lights are created by SceneBuilder.
struct SceneData {
  struct MeshEntry {
    TriangleMesh mesh;
    std::shared_ptr<const Material> material;
    uint32_t first_light = UINT32_MAX;  // index of triangle 0's area light, or none
    MediumInterface media;
    // pbrt-v4's alpha mask (null: opaque): rays ignore a hit where it is 0 and keep one where it
    // is in (0, 1) with that probability, by a hash of the ray (scene.cpp, alpha_filter).
    TexturePtr alpha;
  };
  struct SphereEntry {
    Sphere sphere;
    std::shared_ptr<const Material> material;
    uint32_t light = UINT32_MAX;  // index of its area light, or none
    MediumInterface media;
  };
  // An object defined once and placed many times (pbrt-v4 ObjectBegin / ObjectInstance): its
  // meshes in the object's own space, without emitters. The scene builds one Embree scene
  // for it and places it with one Embree instance per InstanceEntry.
  struct Prototype {
    std::vector<MeshEntry> meshes;
  };
  struct InstanceEntry {
    uint32_t prototype = 0;
    Transform object_to_world;  // affine and invertible
  };
  std::vector<MeshEntry> meshes;
  std::vector<SphereEntry> spheres;
  std::vector<Prototype> prototypes;
  std::vector<InstanceEntry> instances;
  std::vector<std::shared_ptr<class Light>> lights;
  // Absorbing media (geometry/medium.h); a segment no surface assigns to one is in
  // default_medium, the camera's.
  std::vector<HomogeneousMedium> media;
  int16_t default_medium = kNoMedium;
  CameraParams camera;
  SceneSettings settings;
  std::string name;
};

class Scene {
 public:
  explicit Scene(SceneData data);
  ~Scene();
  Scene(const Scene&) = delete;
  Scene& operator=(const Scene&) = delete;

  // Closest hit in (0, ray.tmax). Each call counts one ray (per-thread counters).
  bool intersect(const Ray& ray, SurfaceInteraction* si) const;
  // True if anything blocks the ray in (0, ray.tmax). Counts one ray.
  bool occluded(const Ray& ray) const;
  // With absorbing media: what of the light along the shadow ray survives, 0 if a surface that
  // has a material blocks it. Interfaces (no material) are passed, each piece between them in its
  // own medium (geometry/medium.h); start and end are the shadow ray's ends. Counts a ray per
  // piece. Integrators call it only where traces_transmittance(); else occluded() is the whole
  // answer.
  Rgb shadow_transmittance(Ray ray, SegmentEnd start, SegmentEnd end) const;
  // What of the light along a shadow ray arrives: shadow_transmittance where the scene has media
  // or interfaces, else 0 or 1 by occluded(). Every shadow ray of the integrators asks this.
  Rgb visibility(const Ray& ray, SegmentEnd start, SegmentEnd end) const {
    if (traces_transmittance()) return shadow_transmittance(ray, start, end);
    return Rgb(occluded(ray) ? 0.f : 1.f);
  }
  static constexpr int kMaxInterfaceCrossings = 64;

  const Camera& camera() const { return camera_; }
  // Re-creates the camera at another film resolution (command-line override; call before
  // rendering, never during).
  void override_resolution(int width, int height);
  const std::vector<const Light*>& lights() const { return light_ptrs_; }
  const std::vector<const Light*>& infinite_lights() const { return infinite_lights_; }
  const LightSampler& light_sampler() const { return *light_sampler_; }
  Bounds3 bounds() const { return bounds_; }
  const SceneSettings& settings() const { return settings_; }
  const std::string& name() const { return name_; }

  // Absorbing media (geometry/medium.h). Without any, every transmittance is 1 and the
  // integrators skip asking.
  bool has_media() const { return !media_.empty(); }
  // Media or interfaces (surfaces without a material): shadow rays must then go through
  // shadow_transmittance rather than occluded().
  bool traces_transmittance() const { return !media_.empty() || has_interfaces_; }
  size_t medium_count() const { return media_.size(); }
  int16_t default_medium() const { return default_medium_; }
  // The fraction of light left after `distance` along the segment with these two ends (infinity
  // for a ray that escapes: 0 inside an absorbing medium).
  Rgb transmittance(SegmentEnd a, SegmentEnd b, float distance) const {
    const int16_t m = medium_between(a, b, default_medium_);
    return m < 0 ? Rgb(1.f) : media_[size_t(m)].transmittance(distance);
  }
  // Triangles as rendered: each instance counts its prototype's triangles again.
  size_t triangle_count() const;
  // Triangles held in memory: each prototype counted once.
  size_t stored_triangle_count() const;
  size_t sphere_count() const { return spheres_.size(); }
  size_t instance_count() const { return instances_.size(); }
  // Bytes the geometry holds: the meshes' arrays (each prototype's once), the instances, and
  // Embree's buffers and BVHs as its memory monitor counts them.
  size_t geometry_bytes() const;

  // Rays traced through intersect/occluded since construction (all threads), and how many of
  // them were occlusion rays (the bench weighs the raw Embree bound by this mix).
  uint64_t rays_traced() const;
  uint64_t occlusion_rays_traced() const;

  // The raw Embree kernels, for measuring the bound a renderer on this BVH cannot beat
  // (scene/ray_bench.h): rtcIntersect1 / rtcOccluded1 on rays[0, n) with no hit record and
  // no ray counting. intersect_raw writes each ray's closest-hit distance (infinity on a miss)
  // to t_hit and returns the number of hits; occluded_raw returns the number occluded.
  uint64_t intersect_raw(const Ray* rays, size_t n, float* t_hit) const;
  uint64_t occluded_raw(const Ray* rays, size_t n) const;

  // Compact primitive references for stored path vertices (the bidirectional core keeps light
  // vertices small and rebuilds their hit records on demand): a dense index over all triangles
  // and spheres, each instance with its own range (the instance's first index plus the
  // primitive's index in its prototype), and the hit record at point p of that primitive (p is
  // projected onto it) as intersect() reports it, with wo set to the given direction. Does not
  // count a ray.
  uint32_t primitive_index(const SurfaceInteraction& si) const;
  SurfaceInteraction interaction_at(uint32_t primitive_index, Vec3 p, Vec3 wo) const;
  // The dense primitive indices of the shape si lies on (a whole mesh, or one sphere): merging
  // trusts photons on the query's own shape and tests the visibility of the others.
  struct PrimitiveRange {
    uint32_t begin = 0, end = 0;
    bool contains(uint32_t i) const { return i - begin < end - begin; }
  };
  PrimitiveRange shape_primitives(const SurfaceInteraction& si) const;

 private:
  void build_accelerator();
  void attach_spheres();
  void attach_instances();
  void complete_hit(uint32_t inst_id, uint32_t geom_id, uint32_t prim_id, float b1, float b2,
                    Vec3 p_sphere, SurfaceInteraction* si) const;
  const SceneData::MeshEntry& mesh_entry(uint32_t inst_id, uint32_t geom_id) const;
  TriangleVertices triangle_vertices(uint32_t inst_id, uint32_t geom_id, uint32_t prim_id) const;

  struct Impl;
  std::unique_ptr<Impl> impl_;
  std::vector<SceneData::MeshEntry> meshes_;
  std::vector<SceneData::SphereEntry> spheres_;
  std::vector<SceneData::Prototype> prototypes_;
  std::vector<SceneData::InstanceEntry> instances_;
  std::vector<std::shared_ptr<Light>> lights_;
  std::vector<HomogeneousMedium> media_;
  int16_t default_medium_ = kNoMedium;
  bool has_interfaces_ = false;
  std::vector<const Light*> light_ptrs_, infinite_lights_;
  std::unique_ptr<LightSampler> light_sampler_;
  CameraParams camera_params_;
  Camera camera_;
  Bounds3 bounds_;
  SceneSettings settings_;
  std::string name_;
};

}  // namespace caustica
