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
  void add_mesh(TriangleMesh mesh, MaterialPtr material, const AreaEmission* emission = nullptr);
  void add_sphere(const Sphere& sphere, MaterialPtr material,
                  const AreaEmission* emission = nullptr);
  void add_light(LightPtr light);
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
