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
#include "scene/scene.h"

namespace caustica {

// camera_index: which glTF camera (in the order of model.cameras) to render from; -1 takes
// the first camera a node uses, or, without one, a camera that frames the scene.
// Throws SceneLoadError ("file: error: ...") for files that cannot be read or are invalid.
std::unique_ptr<Scene> load_gltf(const std::string& path, WarningSink warn, int camera_index = -1);

}  // namespace caustica
