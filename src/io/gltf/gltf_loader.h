// glTF 2.0 scenes (.gltf with external or embedded buffers, and .glb), parsed by tinygltf.
//
// What is mapped (see gltf_loader.cpp for the details of each):
// - the default scene's node hierarchy (matrix or TRS) into world-space triangle meshes
//   (TRIANGLES, TRIANGLE_STRIP and TRIANGLE_FAN primitives; POSITION, NORMAL, TEXCOORD_n);
// - metallic-roughness materials: metallic 0 -> coateddiffuse (base colour under a
//   dielectric coat of IOR 1.5, GGX alpha = roughness^2), metallic 1 -> conductor with the
//   base colour as reflectance, in between -> mix of the two by metallic;
//   KHR_materials_transmission (> 0) with KHR_materials_ior -> rough dielectric;
//   baseColorTexture (sRGB) times baseColorFactor;
// - emissiveFactor x KHR_materials_emissive_strength -> diffuse area lights (two-sided
//   when the material is doubleSided);
// - KHR_lights_punctual point, spot and directional lights (intensity used as given);
// - perspective cameras: yfov is glTF's vertical field of view; the film is 720 pixels
//   high and aspectRatio wide (1280x720 without one).
// Textures other than base colour, alpha modes, skins, morph targets, animations and
// texture transforms warn once and are ignored.
#pragma once

#include <memory>
#include <string>

#include "io/load_error.h"
#include "io/scene_builder.h"
#include "scene/scene.h"

namespace caustica {

// camera_index: which glTF camera (in the order of model.cameras) to render from; -1 takes
// the first camera a node uses, or, without one, a camera that frames the scene; any other
// index outside the file's cameras is an error.
// Throws SceneLoadError ("file: error: accessors[3]: ...", naming the JSON element) for files
// that cannot be read or are invalid. Every count, offset and stride in the file is checked
// against the bytes really there before anything is allocated for it; images are checked
// against the pixels their data can hold before they are decoded; nodes must form trees.
std::unique_ptr<Scene> load_gltf(const std::string& path, WarningSink warn, int camera_index = -1);

// Parses a glTF file held in memory (JSON, or GLB when it starts with "glTF") into
// `builder` without building the scene and without file access: external buffer and image
// URIs are errors (data: URIs work). `name` is the file name used in messages. A nonzero
// `max_triangles` bounds the geometry (for fuzzing). Throws SceneLoadError.
void parse_gltf_memory(const std::string& bytes, const std::string& name, SceneBuilder& builder,
                       WarningSink warn, int camera_index = -1, size_t max_triangles = 0);

}  // namespace caustica
