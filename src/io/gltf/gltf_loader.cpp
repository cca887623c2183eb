// tinygltf is compiled once, in tinygltf_impl.cpp; this file sees only its declarations.
#define TINYGLTF_NO_STB_IMAGE_WRITE
#define TINYGLTF_NO_INCLUDE_STB_IMAGE_WRITE
#include "io/gltf/gltf_loader.h"

#include <tiny_gltf.h>

#include <cmath>
#include <cstring>
#include <filesystem>
#include <map>
#include <optional>

#include "image/image.h"
#include "io/pbrt/warnings.h"
#include "io/scene_builder.h"
#include "lights/lights.h"
#include "materials/materials.h"

namespace caustica {

namespace {

using pbrt::Warnings;

class GltfConverter {
 public:
  GltfConverter(const tinygltf::Model& model, const std::string& path, Warnings& warnings)
      : model_(model), path_(path), warnings_(warnings) {}

  std::unique_ptr<Scene> convert(int camera_index);

 private:
  [[noreturn]] void fail(const std::string& message) const {
    throw SceneLoadError({path_, 0, 0}, message);
  }
  void warn(const std::string& message) { warnings_.warn({path_, 0, 0}, message); }

  void visit(int node_index, const Transform& parent, int depth);
  void add_primitive(const tinygltf::Primitive& prim, const Transform& to_world,
                     const std::string& mesh_name);
  // Reads accessor `index` as floats, `components` per element (normalized integers are
  // mapped to [0, 1] or [-1, 1]).
  std::vector<float> read_floats(int index, int components, const char* what) const;
  std::vector<uint32_t> read_indices(int index) const;
  MaterialPtr material(int index);
  TexturePtr base_color_texture(const tinygltf::Material& m);
  const tinygltf::Value* extension(const tinygltf::ExtensionMap& ext, const char* name) const {
    auto it = ext.find(name);
    return it == ext.end() ? nullptr : &it->second;
  }

  const tinygltf::Model& model_;
  std::string path_;
  Warnings& warnings_;
  SceneBuilder builder_;
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

Mat4 node_matrix(const tinygltf::Node& n) {
  if (n.matrix.size() == 16) {
    float v[16];
    for (int i = 0; i < 16; ++i) v[i] = float(n.matrix[i]);
    return Mat4::from_column_major(v);
  }
  Mat4 t = Mat4::identity(), r = Mat4::identity(), s = Mat4::identity();
  if (n.translation.size() == 3)
    for (int i = 0; i < 3; ++i) t.m[i][3] = float(n.translation[i]);
  if (n.scale.size() == 3)
    for (int i = 0; i < 3; ++i) s.m[i][i] = float(n.scale[i]);
  if (n.rotation.size() == 4) {  // unit quaternion (x, y, z, w)
    const double x = n.rotation[0], y = n.rotation[1], z = n.rotation[2], w = n.rotation[3];
    const double q[3][3] = {{1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)},
                            {2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)},
                            {2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)}};
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j) r.m[i][j] = float(q[i][j]);
  }
  return t * r * s;
}

Transform to_transform(const Mat4& m) {
  Mat4 inv;
  if (!m.inverse(&inv)) inv = Mat4::identity();  // singular nodes only lose their normals
  return Transform(m, inv);
}

std::vector<float> GltfConverter::read_floats(int index, int components, const char* what) const {
  if (index < 0 || size_t(index) >= model_.accessors.size())
    fail(std::string(what) + ": accessor index out of range");
  const tinygltf::Accessor& a = model_.accessors[index];
  if (tinygltf::GetNumComponentsInType(uint32_t(a.type)) != components)
    fail(std::string(what) + ": accessor " + std::to_string(index) + " has the wrong type");
  if (a.sparse.isSparse) fail(std::string(what) + ": sparse accessors are not supported");
  std::vector<float> out(a.count * components, 0.f);
  if (a.bufferView < 0) return out;  // all zeros, as the spec says
  if (size_t(a.bufferView) >= model_.bufferViews.size())
    fail(std::string(what) + ": buffer view out of range");
  const tinygltf::BufferView& view = model_.bufferViews[a.bufferView];
  if (view.buffer < 0 || size_t(view.buffer) >= model_.buffers.size())
    fail(std::string(what) + ": buffer out of range");
  const std::vector<unsigned char>& data = model_.buffers[view.buffer].data;
  const int size = tinygltf::GetComponentSizeInBytes(uint32_t(a.componentType));
  if (size <= 0) fail(std::string(what) + ": unknown component type");
  const size_t stride = view.byteStride ? view.byteStride : size_t(size) * components;
  const size_t begin = view.byteOffset + a.byteOffset;
  if (a.count > 0 && (begin + (a.count - 1) * stride + size_t(size) * components >
                          view.byteOffset + view.byteLength ||
                      view.byteOffset + view.byteLength > data.size()))
    fail(std::string(what) + ": accessor " + std::to_string(index) +
         " reads past the end of its buffer");
  for (size_t i = 0; i < a.count; ++i)
    for (int c = 0; c < components; ++c) {
      const unsigned char* p = data.data() + begin + i * stride + size_t(c) * size;
      float v = 0;
      switch (a.componentType) {
        case TINYGLTF_COMPONENT_TYPE_FLOAT:
          std::memcpy(&v, p, 4);
          break;
        case TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE:
          v = a.normalized ? p[0] / 255.f : p[0];
          break;
        case TINYGLTF_COMPONENT_TYPE_BYTE:
          v = a.normalized ? std::max(int8_t(p[0]) / 127.f, -1.f) : float(int8_t(p[0]));
          break;
        case TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT: {
          uint16_t u;
          std::memcpy(&u, p, 2);
          v = a.normalized ? u / 65535.f : u;
          break;
        }
        case TINYGLTF_COMPONENT_TYPE_SHORT: {
          int16_t s;
          std::memcpy(&s, p, 2);
          v = a.normalized ? std::max(s / 32767.f, -1.f) : s;
          break;
        }
        case TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT: {
          uint32_t u;
          std::memcpy(&u, p, 4);
          v = float(u);
          break;
        }
        default:
          fail(std::string(what) + ": unsupported component type");
      }
      out[i * components + c] = v;
    }
  return out;
}

std::vector<uint32_t> GltfConverter::read_indices(int index) const {
  const tinygltf::Accessor& a = model_.accessors.at(index);
  if (a.componentType != TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE &&
      a.componentType != TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT &&
      a.componentType != TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT)
    fail("indices: accessor " + std::to_string(index) + " is not of an unsigned integer type");
  if (a.componentType == TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT) {
    // Read exactly (floats lose precision above 2^24).
    std::vector<uint32_t> out(a.count);
    if (a.bufferView < 0) return out;
    const tinygltf::BufferView& view = model_.bufferViews.at(a.bufferView);
    const std::vector<unsigned char>& data = model_.buffers.at(view.buffer).data;
    const size_t stride = view.byteStride ? view.byteStride : 4,
                 begin = view.byteOffset + a.byteOffset;
    if (a.count > 0 && (begin + (a.count - 1) * stride + 4 > view.byteOffset + view.byteLength ||
                        view.byteOffset + view.byteLength > data.size()))
      fail("indices: accessor " + std::to_string(index) + " reads past the end of its buffer");
    for (size_t i = 0; i < a.count; ++i) std::memcpy(&out[i], data.data() + begin + i * stride, 4);
    return out;
  }
  const std::vector<float> f = read_floats(index, 1, "indices");
  return std::vector<uint32_t>(f.begin(), f.end());
}

TexturePtr GltfConverter::base_color_texture(const tinygltf::Material& m) {
  const auto& pbr = m.pbrMetallicRoughness;
  Rgb factor(1.f);
  if (pbr.baseColorFactor.size() >= 3)
    factor = Rgb(float(pbr.baseColorFactor[0]), float(pbr.baseColorFactor[1]),
                 float(pbr.baseColorFactor[2]));
  factor = clamp(factor, 0.f, 1.f);
  const int tex = pbr.baseColorTexture.index;
  if (tex < 0) return make_constant_texture(factor);
  if (size_t(tex) >= model_.textures.size())
    fail("material \"" + m.name + "\": texture index out of range");
  if (pbr.baseColorTexture.texCoord != 0)
    warn("texture coordinate sets other than TEXCOORD_0 are not supported");
  if (!pbr.baseColorTexture.extensions.empty())
    warn("texture extensions (KHR_texture_transform) are not supported; ignored");
  const int source = model_.textures[tex].source;
  if (source < 0 || size_t(source) >= model_.images.size()) {
    warn("texture without a supported image source; using the base colour factor");
    return make_constant_texture(factor);
  }
  auto it = images_.find(source);
  if (it == images_.end()) {
    const tinygltf::Image& src = model_.images[source];
    if (src.width <= 0 || src.height <= 0 || src.image.empty() ||
        (src.bits != 8 && src.bits != 16) || src.component < 1)
      fail("image " + std::to_string(source) + " (\"" + src.uri + "\") could not be decoded");
    auto image = std::make_shared<Image>(src.width, src.height);
    const size_t bytes = size_t(src.bits / 8), comps = size_t(src.component);
    if (src.image.size() < size_t(src.width) * src.height * comps * bytes)
      fail("image " + std::to_string(source) + " is truncated");
    for (int y = 0; y < src.height; ++y)
      for (int x = 0; x < src.width; ++x) {
        const size_t base = (size_t(y) * src.width + x) * comps;
        Rgb c;
        for (size_t k = 0; k < 3; ++k) {
          const size_t ch = std::min(k, comps > 2 ? k : size_t(0));
          float v;
          if (bytes == 1)
            v = src.image[base + ch] / 255.f;
          else {
            uint16_t u;
            std::memcpy(&u, &src.image[(base + ch) * 2], 2);
            v = u / 65535.f;
          }
          c[int(k)] = srgb_to_linear(v);  // base colour textures are sRGB-encoded
        }
        image->at(x, y) = c;
      }
    it = images_.emplace(source, image).first;
  }
  // glTF's uv origin is the top-left of the image; ImageTexture's v = 0 is the bottom row.
  UvMapping flip;
  flip.sv = -1;
  flip.dv = 1;
  return std::make_shared<ImageTexture>(it->second, flip, factor);
}

MaterialPtr GltfConverter::material(int index) {
  auto found = materials_.find(index);
  if (found != materials_.end()) return found->second;
  MaterialPtr result;
  std::optional<AreaEmission> emission;
  if (index < 0) {
    result =
        make_diffuse(make_constant_texture(Rgb(0.8f)));  // glTF's default material is white-ish
  } else {
    if (size_t(index) >= model_.materials.size())
      fail("material index " + std::to_string(index) + " out of range");
    const tinygltf::Material& m = model_.materials[index];
    const auto& pbr = m.pbrMetallicRoughness;
    const float metallic = clamp(float(pbr.metallicFactor), 0.f, 1.f);
    const float roughness = clamp(float(pbr.roughnessFactor), 0.f, 1.f);
    // glTF roughness is perceptual: GGX alpha = roughness^2.
    TexturePtr alpha = roughness > 0 ? make_constant_texture(Rgb(roughness * roughness)) : nullptr;
    TexturePtr base = base_color_texture(m);
    if (pbr.metallicRoughnessTexture.index >= 0)
      warn("metallicRoughnessTexture is not supported; using the factors");
    if (m.normalTexture.index >= 0) warn("normal textures are not supported; ignored");
    if (m.occlusionTexture.index >= 0) warn("occlusion textures are not supported; ignored");
    if (m.emissiveTexture.index >= 0)
      warn("emissive textures are not supported; using emissiveFactor");
    if (m.alphaMode != "OPAQUE")
      warn("alphaMode " + m.alphaMode + " is not supported; surfaces are opaque");

    float ior = 1.5f, transmission = 0, strength = 1;
    if (const tinygltf::Value* v = extension(m.extensions, "KHR_materials_ior"))
      if (v->Has("ior")) ior = float(v->Get("ior").GetNumberAsDouble());
    if (const tinygltf::Value* v = extension(m.extensions, "KHR_materials_transmission"))
      if (v->Has("transmissionFactor"))
        transmission = float(v->Get("transmissionFactor").GetNumberAsDouble());
    if (const tinygltf::Value* v = extension(m.extensions, "KHR_materials_emissive_strength"))
      if (v->Has("emissiveStrength"))
        strength = float(v->Get("emissiveStrength").GetNumberAsDouble());
    for (const auto& [name, value] : m.extensions)
      if (name != "KHR_materials_ior" && name != "KHR_materials_transmission" &&
          name != "KHR_materials_emissive_strength")
        warn("material extension " + name + " is not supported; ignored");
    if (!(ior >= 1)) ior = 1.5f;  // ior 0 means "no refraction" in glTF; 1.5 is its default

    if (transmission > 0) {
      DielectricParams d;
      d.eta = ior;
      d.u_roughness = d.v_roughness = alpha;
      d.remap_roughness = false;
      result = make_dielectric(d);
    } else {
      MaterialPtr metal, plastic;
      if (metallic > 0) {
        ConductorParams c;
        c.reflectance = base;
        c.u_roughness = c.v_roughness = alpha;
        c.remap_roughness = false;
        metal = make_conductor(c);
      }
      if (metallic < 1) {
        CoatedDiffuseParams c;
        c.reflectance = base;
        c.u_roughness = c.v_roughness = alpha ? alpha : make_constant_texture(Rgb(0.f));
        c.remap_roughness = false;
        c.eta = ior;
        plastic = make_coated_diffuse(c);
      }
      result = !metal     ? plastic
               : !plastic ? metal
                          : make_mix(plastic, metal, make_constant_texture(Rgb(metallic)));
    }
    if (m.emissiveFactor.size() == 3) {
      const Rgb e =
          Rgb(float(m.emissiveFactor[0]), float(m.emissiveFactor[1]), float(m.emissiveFactor[2])) *
          strength;
      if (!e.is_black() && e.is_finite()) emission = AreaEmission{e, m.doubleSided};
    }
  }
  materials_[index] = result;
  emission_[index] = emission;
  return result;
}

void GltfConverter::add_primitive(const tinygltf::Primitive& prim, const Transform& to_world,
                                  const std::string& mesh_name) {
  const int mode = prim.mode < 0 ? TINYGLTF_MODE_TRIANGLES : prim.mode;
  if (mode != TINYGLTF_MODE_TRIANGLES && mode != TINYGLTF_MODE_TRIANGLE_STRIP &&
      mode != TINYGLTF_MODE_TRIANGLE_FAN) {
    warn("points and lines are not rendered (mesh \"" + mesh_name + "\")");
    return;
  }
  auto pos = prim.attributes.find("POSITION");
  if (pos == prim.attributes.end()) fail("mesh \"" + mesh_name + "\": a primitive has no POSITION");
  if (!prim.targets.empty()) warn("morph targets are not supported; using the base mesh");
  TriangleMesh mesh;
  const std::vector<float> p = read_floats(pos->second, 3, "POSITION");
  for (size_t i = 0; i + 2 < p.size(); i += 3)
    mesh.positions.emplace_back(p[i], p[i + 1], p[i + 2]);
  const size_t n = mesh.positions.size();
  if (auto it = prim.attributes.find("NORMAL"); it != prim.attributes.end()) {
    const std::vector<float> v = read_floats(it->second, 3, "NORMAL");
    for (size_t i = 0; i + 2 < v.size(); i += 3)
      mesh.normals.emplace_back(v[i], v[i + 1], v[i + 2]);
    if (mesh.normals.size() != n) mesh.normals.clear();
  }
  if (auto it = prim.attributes.find("TEXCOORD_0"); it != prim.attributes.end()) {
    const std::vector<float> v = read_floats(it->second, 2, "TEXCOORD_0");
    for (size_t i = 0; i + 1 < v.size(); i += 2) mesh.uvs.emplace_back(v[i], v[i + 1]);
    if (mesh.uvs.size() != n) mesh.uvs.clear();
  }
  std::vector<uint32_t> idx;
  if (prim.indices >= 0) {
    if (size_t(prim.indices) >= model_.accessors.size())
      fail("mesh \"" + mesh_name + "\": indices accessor out of range");
    idx = read_indices(prim.indices);
  } else {
    idx.resize(n);
    for (size_t i = 0; i < n; ++i) idx[i] = uint32_t(i);
  }
  for (uint32_t i : idx)
    if (i >= n)
      fail("mesh \"" + mesh_name + "\": vertex index " + std::to_string(i) + " out of range");
  if (mode == TINYGLTF_MODE_TRIANGLES) {
    idx.resize(idx.size() / 3 * 3);
    mesh.indices = std::move(idx);
  } else {
    for (size_t i = 2; i < idx.size(); ++i) {
      if (mode == TINYGLTF_MODE_TRIANGLE_FAN)
        mesh.indices.insert(mesh.indices.end(), {idx[0], idx[i - 1], idx[i]});
      else if (i % 2 == 0)
        mesh.indices.insert(mesh.indices.end(), {idx[i - 2], idx[i - 1], idx[i]});
      else
        mesh.indices.insert(mesh.indices.end(), {idx[i - 1], idx[i - 2], idx[i]});
    }
  }
  if (mesh.indices.empty()) return;
  mesh.transform(to_world);
  for (const Vec3& q : mesh.positions) bounds_.extend(q);
  MaterialPtr m = material(prim.material);
  const std::optional<AreaEmission>& e = emission_[prim.material];
  builder_.add_mesh(std::move(mesh), m, e ? &*e : nullptr);
}

void GltfConverter::visit(int node_index, const Transform& parent, int depth) {
  if (node_index < 0 || size_t(node_index) >= model_.nodes.size())
    fail("node index " + std::to_string(node_index) + " out of range");
  if (depth > 256) fail("the node hierarchy is deeper than 256 (a cycle?)");
  const tinygltf::Node& node = model_.nodes[node_index];
  const Transform to_world = parent * to_transform(node_matrix(node));
  if (node.skin >= 0) warn("skins are not supported; meshes are rendered in their bind pose");
  if (node.mesh >= 0) {
    if (size_t(node.mesh) >= model_.meshes.size())
      fail("mesh index " + std::to_string(node.mesh) + " out of range");
    const tinygltf::Mesh& mesh = model_.meshes[node.mesh];
    for (const tinygltf::Primitive& prim : mesh.primitives)
      add_primitive(prim, to_world, mesh.name);
  }
  if (node.camera >= 0) cameras_.push_back({node.camera, to_world});
  if (const tinygltf::Value* v = extension(node.extensions, "KHR_lights_punctual")) {
    const int li = v->Has("light") ? v->Get("light").GetNumberAsInt() : -1;
    if (li < 0 || size_t(li) >= model_.lights.size())
      fail("KHR_lights_punctual: light index out of range");
    const tinygltf::Light& l = model_.lights[li];
    Rgb color(1.f);
    if (l.color.size() == 3) color = Rgb(float(l.color[0]), float(l.color[1]), float(l.color[2]));
    const Rgb value = color * float(l.intensity);
    // Punctual lights shine along the node's -z.
    const Vec3 pos = to_world.point({0, 0, 0}), dir = normalize(to_world.vector({0, 0, -1}));
    if (l.type == "point") {
      builder_.add_light(make_point_light(pos, value));
    } else if (l.type == "spot") {
      const float outer = degrees(float(l.spot.outerConeAngle)),
                  inner = degrees(float(l.spot.innerConeAngle));
      builder_.add_light(make_spot_light(pos, dir, value, outer, std::max(outer - inner, 0.f)));
    } else if (l.type == "directional") {
      builder_.add_light(make_distant_light(dir, value));
    } else {
      warn("light type \"" + l.type + "\" is not supported; skipped");
    }
  }
  for (int child : node.children) visit(child, to_world, depth + 1);
}

std::unique_ptr<Scene> GltfConverter::convert(int camera_index) {
  if (!model_.animations.empty()) warn("animations are not supported; using the rest pose");
  int scene = model_.defaultScene >= 0 ? model_.defaultScene : 0;
  if (model_.scenes.empty()) {
    // No scene: every root node.
    std::vector<bool> is_child(model_.nodes.size(), false);
    for (const auto& n : model_.nodes)
      for (int c : n.children)
        if (c >= 0 && size_t(c) < is_child.size()) is_child[c] = true;
    for (size_t i = 0; i < model_.nodes.size(); ++i)
      if (!is_child[i]) visit(int(i), Transform(), 0);
  } else {
    if (size_t(scene) >= model_.scenes.size()) fail("defaultScene is out of range");
    for (int n : model_.scenes[scene].nodes) visit(n, Transform(), 0);
  }

  CameraParams cp;
  cp.width = 1280;
  cp.height = 720;
  const CameraInstance* chosen = nullptr;
  if (camera_index >= 0) {
    for (const CameraInstance& c : cameras_)
      if (c.camera == camera_index) {
        chosen = &c;
        break;
      }
    if (!chosen)
      fail("camera " + std::to_string(camera_index) + " is not used by any node of the scene (" +
           std::to_string(model_.cameras.size()) + " cameras in the file)");
  } else if (!cameras_.empty()) {
    chosen = &cameras_.front();
  }
  if (chosen) {
    const tinygltf::Camera& c = model_.cameras.at(chosen->camera);
    float yfov = radians(45.f), aspect = 16.f / 9.f;
    if (c.type == "perspective") {
      if (c.perspective.yfov > 0) yfov = float(c.perspective.yfov);
      if (c.perspective.aspectRatio > 0) aspect = float(c.perspective.aspectRatio);
    } else {
      warn("camera type \"" + c.type + "\" is not supported; using a perspective camera");
    }
    cp.height = 720;
    cp.width = std::max(1, int(std::lround(720 * aspect)));
    // Our fov spans the shorter image axis (pbrt); glTF's yfov is always vertical.
    cp.fov_degrees =
        cp.width >= cp.height ? degrees(yfov) : degrees(2 * std::atan(std::tan(yfov / 2) * aspect));
    // glTF cameras look down -z with +y up and +x right; ours look down +z (left-handed).
    cp.camera_to_world = chosen->to_world * Transform::scale({1, 1, -1});
  } else {
    warn("no camera; placing one that frames the scene");
    Vec3 center(0, 0, 0);
    float radius = 1;
    if (!bounds_.empty()) bounds_.bounding_sphere(&center, &radius);
    radius = std::max(radius, 1e-3f);
    cp.fov_degrees = 45;
    const Vec3 eye = center + Vec3(0, 0, radius / std::tan(radians(22.5f)) * 1.1f);
    cp.camera_to_world =
        Transform::look_at(eye, center, {0, 1, 0}).inverse() * Transform::scale({-1, 1, 1});
  }
  builder_.set_camera(cp);
  return builder_.build(std::filesystem::path(path_).stem().string());
}

}  // namespace

std::unique_ptr<Scene> load_gltf(const std::string& path, WarningSink warn, int camera_index) {
  tinygltf::Model model;
  tinygltf::TinyGLTF loader;
  std::string err, warning;
  const bool binary = std::filesystem::path(path).extension() == ".glb";
  if (!std::filesystem::exists(path))
    throw SceneLoadError({path, 0, 0}, "cannot open the scene file");
  const bool ok = binary ? loader.LoadBinaryFromFile(&model, &err, &warning, path)
                         : loader.LoadASCIIFromFile(&model, &err, &warning, path);
  Warnings warnings(warn);
  if (!warning.empty()) warnings.warn({path, 0, 0}, warning);
  if (!ok) throw SceneLoadError({path, 0, 0}, err.empty() ? "not a valid glTF file" : err);
  try {
    return GltfConverter(model, path, warnings).convert(camera_index);
  } catch (const SceneLoadError&) {
    throw;
  } catch (const std::exception& e) {
    throw SceneLoadError({path, 0, 0}, e.what());
  }
}

}  // namespace caustica
