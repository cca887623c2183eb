// The glTF converter: a parsed tinygltf model to SceneBuilder calls, every number the file gives
// checked before it is used. Private to the glTF loader; its definitions are split by meaning
// over gltf_loader.cpp (nodes, meshes, cameras, lights), gltf_accessors.cpp (reading accessors
// within their buffers) and gltf_materials.cpp (the material mapping).
#pragma once

#include <tiny_gltf.h>

#include <cmath>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "geometry/texture.h"
#include "image/image.h"
#include "io/load_error.h"
#include "io/pbrt/warnings.h"
#include "io/scene_builder.h"

namespace caustica::gltf_input {

using pbrt::Warnings;

class GltfConverter {
 public:
  GltfConverter(const tinygltf::Model& model, const std::string& path, Warnings& warnings,
                SceneBuilder& builder, size_t max_triangles)
      : model_(model),
        path_(path),
        warnings_(warnings),
        builder_(builder),
        max_triangles_(max_triangles) {}

  void convert(int camera_index);

 private:
  [[noreturn]] void fail(const std::string& message) const {
    throw SceneLoadError({path_, 0, 0}, message);
  }
  void warn(const std::string& message) { warnings_.warn({path_, 0, 0}, message); }

  // Where the elements of an accessor lie, after every number the file gives for them
  // (count, byteOffset, byteStride, the bufferView's range) has been checked against the
  // bytes that are really there; null `first` when the accessor has no bufferView.
  struct AccessorSpan {
    const unsigned char* first = nullptr;
    size_t count = 0, stride = 0;
  };
  AccessorSpan accessor_span(int index, int components, const std::string& what) const;

  void check_cameras_and_lights() const;
  void visit(int node_index, const Transform& parent, int depth);
  void add_primitive(const tinygltf::Primitive& prim, const Transform& to_world,
                     const std::string& where);
  // Reads accessor `index` as floats, `components` per element (normalized integers are
  // mapped to [0, 1] or [-1, 1]). Empty, with a warning, if it has no bufferView.
  std::vector<float> read_floats(int index, int components, const std::string& what);
  std::vector<uint32_t> read_indices(int index, const std::string& what);
  MaterialPtr material(int index);
  TexturePtr base_color_texture(const tinygltf::Material& m, const std::string& where);
  const tinygltf::Value* extension(const tinygltf::ExtensionMap& ext, const char* name) const {
    auto it = ext.find(name);
    return it == ext.end() ? nullptr : &it->second;
  }

  const tinygltf::Model& model_;
  std::string path_;
  Warnings& warnings_;
  SceneBuilder& builder_;
  size_t max_triangles_;
  size_t triangles_ = 0;
  std::vector<bool> visited_;
  std::map<int, MaterialPtr> materials_;
  std::map<int, std::optional<AreaEmission>> emission_;
  std::map<int, std::shared_ptr<const Image>> images_;
  struct CameraInstance {
    int camera;
    Transform to_world;
  };
  std::vector<CameraInstance> cameras_;
  Bounds3 bounds_;
};

inline bool in_range(double v, double lo, double hi) {
  return std::isfinite(float(v)) && v >= lo && v <= hi;
}

}  // namespace caustica::gltf_input
