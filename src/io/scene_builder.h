// Assembles a Scene from world-space shapes, materials and lights. Built-in scenes and every
// loader go through it, so area-light creation (one light per emissive triangle or sphere)
// and scene validation live in one place.
#pragma once

#include <memory>
#include <string>

#include "lights/light.h"
#include "materials/material.h"
#include "scene/scene.h"

namespace caustica {

class SceneBuilder {
 public:
  // mesh must already be in world space. With emission, every triangle becomes an area light.
  // A null material makes an interface: rays pass it (it may bound media, `media`).
  // alpha: pbrt-v4's alpha mask (SceneData::MeshEntry::alpha), null for opaque.
  void add_mesh(TriangleMesh mesh, MaterialPtr material, const AreaEmission* emission = nullptr,
                MediumInterface media = {}, TexturePtr alpha = nullptr);
  void add_sphere(const Sphere& sphere, MaterialPtr material,
                  const AreaEmission* emission = nullptr, MediumInterface media = {});
  // Absorbing media: add_medium returns the index MediumInterface names it by; the camera's
  // (default) medium holds wherever no surface says otherwise (geometry/medium.h).
  int16_t add_medium(const HomogeneousMedium& medium) {
    data_.media.push_back(medium);
    return int16_t(data_.media.size() - 1);
  }
  void set_default_medium(int16_t medium) { data_.default_medium = medium; }
  void add_light(LightPtr light);
  // An object placed many times (pbrt-v4 ObjectBegin / ObjectInstance) is stored once: its
  // meshes, in the object's own space and never emitting, go into a prototype, and each
  // placement is an instance (an Embree instance, not a copy). add_prototype returns the index
  // that the other two take; object_to_world must be affine and invertible.
  uint32_t add_prototype();
  void add_prototype_mesh(uint32_t prototype, TriangleMesh mesh, MaterialPtr material);
  void add_instance(uint32_t prototype, const Transform& object_to_world);
  void set_camera(const CameraParams& camera) {
    data_.camera = camera;
    has_camera_ = true;
  }
  SceneSettings& settings() { return data_.settings; }

  // Throws std::runtime_error if the scene has no camera resolution or is otherwise unusable.
  std::unique_ptr<Scene> build(const std::string& name);

 private:
  SceneData data_;
  bool has_camera_ = false;
};

}  // namespace caustica
