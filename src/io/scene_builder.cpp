#include "io/scene_builder.h"

#include <stdexcept>

#include "lights/lights.h"

namespace caustica {

namespace {
// Lights are chosen in proportion to their power: one infinite or NaN power (radiance times
// a huge area) would break the distribution for every light.
void check_power(const Light& light) {
  if (!light.power().is_finite())
    throw std::runtime_error("an area light's total power overflows to infinity");
}

void check_mesh(const TriangleMesh& mesh) {
  if (mesh.indices.size() % 3 != 0)
    throw std::runtime_error("triangle mesh index count is not a multiple of 3");
  for (uint32_t i : mesh.indices)
    if (i >= mesh.positions.size()) throw std::runtime_error("triangle mesh index out of range");
}
}  // namespace

void SceneBuilder::add_mesh(TriangleMesh mesh, MaterialPtr material, const AreaEmission* emission,
                            MediumInterface media, TexturePtr alpha) {
  check_mesh(mesh);
  SceneData::MeshEntry entry;
  if (emission && !emission->radiance.is_black()) {
    entry.first_light = uint32_t(data_.lights.size());
    for (size_t t = 0; t < mesh.triangle_count(); ++t) {
      data_.lights.push_back(
          make_triangle_area_light(mesh, t, emission->radiance, emission->two_sided));
      data_.lights.back()->media = media;
      check_power(*data_.lights.back());
    }
  }
  entry.mesh = std::move(mesh);
  entry.material = std::move(material);
  entry.media = media;
  entry.alpha = std::move(alpha);
  data_.meshes.push_back(std::move(entry));
}

void SceneBuilder::add_sphere(const Sphere& sphere, MaterialPtr material,
                              const AreaEmission* emission, MediumInterface media) {
  SceneData::SphereEntry entry;
  entry.sphere = sphere;
  entry.material = std::move(material);
  if (emission && !emission->radiance.is_black()) {
    entry.light = uint32_t(data_.lights.size());
    data_.lights.push_back(make_sphere_area_light(sphere, emission->radiance, emission->two_sided));
    data_.lights.back()->media = media;
    check_power(*data_.lights.back());
  }
  entry.media = media;
  data_.spheres.push_back(std::move(entry));
}

void SceneBuilder::add_light(LightPtr light) { data_.lights.push_back(std::move(light)); }

uint32_t SceneBuilder::add_prototype() {
  data_.prototypes.emplace_back();
  return uint32_t(data_.prototypes.size() - 1);
}

void SceneBuilder::add_prototype_mesh(uint32_t prototype, TriangleMesh mesh, MaterialPtr material) {
  check_mesh(mesh);
  SceneData::MeshEntry entry;
  entry.mesh = std::move(mesh);
  entry.material = std::move(material);
  data_.prototypes.at(prototype).meshes.push_back(std::move(entry));
}

void SceneBuilder::add_instance(uint32_t prototype, const Transform& object_to_world) {
  if (prototype >= data_.prototypes.size())
    throw std::runtime_error("an instance of a prototype that does not exist");
  const Mat4& m = object_to_world.matrix();
  if (m(3, 0) != 0 || m(3, 1) != 0 || m(3, 2) != 0 || m(3, 3) != 1)
    throw std::runtime_error("an instance transform must be affine");
  data_.instances.push_back({prototype, object_to_world});
}

std::unique_ptr<Scene> SceneBuilder::build(const std::string& name) {
  if (!has_camera_) throw std::runtime_error("scene has no camera");
  if (data_.camera.width <= 0 || data_.camera.height <= 0)
    throw std::runtime_error("scene has an empty film");
  data_.name = name;
  return std::make_unique<Scene>(std::move(data_));
}

}  // namespace caustica
