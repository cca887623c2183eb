// The Embree side of Scene, shared by its translation units (scene.cpp builds it and traces
// rays; scene_hits.cpp turns hits into SurfaceInteractions). Not part of the interface.
#pragma once

#include <embree3/rtcore.h>
#include <tbb/enumerable_thread_specific.h>

#include <atomic>
#include <string>
#include <vector>

#include "scene/scene.h"

namespace caustica {

// gamma(n) of Higham / pbrt: bound on the relative error of n float operations.
constexpr float gamma_bound(int n) {
  constexpr float eps = 0x1p-24f;
  return (n * eps) / (1 - n * eps);
}

// One Embree scene and what its geometry ids mean: the top-level scene, or one prototype's.
struct GeometryTable {
  RTCScene scene = nullptr;
  std::vector<int> mesh_of_geom;          // geometry id -> mesh index (-1: spheres, instance)
  std::vector<uint32_t> first_primitive;  // geometry id -> its first dense primitive index
  uint64_t primitive_count = 0;           // all of its primitives (instances' included)
  // The geometry whose range [first_primitive[g], first_primitive[g + 1]) holds the index.
  uint32_t geometry_of(uint32_t primitive_index) const;
};

// Embree user geometry for exact spheres: ray-sphere in double precision, as pbrt-v4 does
// to keep the roots accurate for glass (rays leaving the surface from inside).
struct SphereGeometry {
  const std::vector<SceneData::SphereEntry>* spheres;
};

struct Scene::Impl {
  RTCDevice device = nullptr;
  GeometryTable top;
  unsigned sphere_geom_id = RTC_INVALID_GEOMETRY_ID;
  std::vector<uint32_t> instance_of_geom;  // top-level geometry id -> instance (or UINT32_MAX)
  std::vector<GeometryTable> prototypes;
  std::vector<bool> instance_swaps_handedness;
  SphereGeometry sphere_geometry{};
  struct RayCounts {
    uint64_t all = 0, occlusion = 0;
  };
  mutable tbb::enumerable_thread_specific<RayCounts> rays;
  // This thread's counts. rays.local() hashes the thread id on every call (about 1.5% of a
  // render's profile, one lookup per ray); a one-entry thread-local cache keyed by this scene's
  // process-unique id finds them without it (a later scene at the same address has another id).
  RayCounts& local_counts() const {
    thread_local uint64_t cached_id = 0;
    thread_local RayCounts* cached = nullptr;
    if (cached_id != id) {
      cached = &rays.local();  // ets elements never move
      cached_id = id;
    }
    return *cached;
  }
  static uint64_t next_id() {
    static std::atomic<uint64_t> counter{0};
    return ++counter;
  }
  const uint64_t id = next_id();
  std::atomic<int64_t> embree_bytes{0};  // what Embree's memory monitor reports it holds
  std::string error;

  ~Impl() {
    for (GeometryTable& p : prototypes)
      if (p.scene) rtcReleaseScene(p.scene);
    if (top.scene) rtcReleaseScene(top.scene);
    if (device) rtcReleaseDevice(device);
  }
};

// A triangle's vertex attributes in world space (an instanced triangle's transformed per hit).
struct TriangleVertices {
  Vec3 p[3];
  Vec3 n[3];
  Vec2 uv[3] = {{0, 0}, {1, 0}, {1, 1}};  // the default parameterisation when the mesh has none
  bool has_normals = false;
  bool reverse_orientation = false;
};

}  // namespace caustica
