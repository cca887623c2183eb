// tinygltf is compiled once, in tinygltf_impl.cpp; this file sees only its declarations.
#define TINYGLTF_NO_STB_IMAGE_WRITE
#define TINYGLTF_NO_INCLUDE_STB_IMAGE_WRITE
#include "io/gltf/gltf_loader.h"

#include <stb_image.h>
#include <tiny_gltf.h>

#include <climits>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <map>
#include <optional>

#include "image/image.h"
#include "io/gltf/gltf_converter.h"
#include "io/gltf/gltf_input.h"
#include "io/input_file.h"
#include "io/pbrt/warnings.h"
#include "io/scene_builder.h"
#include "lights/light_power.h"
#include "lights/lights.h"
#include "materials/materials.h"

namespace caustica {

namespace gltf_input {

namespace {

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

bool is_finite(const Mat4& m) {
  for (int i = 0; i < 4; ++i)
    for (int j = 0; j < 4; ++j)
      if (!std::isfinite(m.m[i][j])) return false;
  return true;
}

Transform to_transform(const Mat4& m) {
  Mat4 inv;
  if (!m.inverse(&inv)) inv = Mat4::identity();  // singular nodes only lose their normals
  return Transform(m, inv);
}

// A double from the JSON that must be a finite float in [lo, hi].
}  // namespace

void GltfConverter::add_primitive(const tinygltf::Primitive& prim, const Transform& to_world,
                                  const std::string& where) {
  const int mode = prim.mode < 0 ? TINYGLTF_MODE_TRIANGLES : prim.mode;
  if (mode != TINYGLTF_MODE_TRIANGLES && mode != TINYGLTF_MODE_TRIANGLE_STRIP &&
      mode != TINYGLTF_MODE_TRIANGLE_FAN) {
    warn("points and lines are not rendered (" + where + ")");
    return;
  }
  auto pos = prim.attributes.find("POSITION");
  if (pos == prim.attributes.end()) fail(where + ": no POSITION attribute");
  if (!prim.targets.empty()) warn("morph targets are not supported; using the base mesh");
  TriangleMesh mesh;
  const std::vector<float> p = read_floats(pos->second, 3, where + " POSITION");
  for (size_t i = 0; i + 2 < p.size(); i += 3)
    mesh.positions.emplace_back(p[i], p[i + 1], p[i + 2]);
  const size_t n = mesh.positions.size();
  if (n == 0) return;  // no vertices (an accessor without data): nothing to draw
  if (auto it = prim.attributes.find("NORMAL"); it != prim.attributes.end()) {
    const std::vector<float> v = read_floats(it->second, 3, where + " NORMAL");
    for (size_t i = 0; i + 2 < v.size(); i += 3)
      mesh.normals.emplace_back(v[i], v[i + 1], v[i + 2]);
    if (mesh.normals.size() != n) mesh.normals.clear();
  }
  if (auto it = prim.attributes.find("TEXCOORD_0"); it != prim.attributes.end()) {
    const std::vector<float> v = read_floats(it->second, 2, where + " TEXCOORD_0");
    for (size_t i = 0; i + 1 < v.size(); i += 2) mesh.uvs.emplace_back(v[i], v[i + 1]);
    if (mesh.uvs.size() != n) mesh.uvs.clear();
  }
  std::vector<uint32_t> idx;
  if (prim.indices >= 0) {
    idx = read_indices(prim.indices, where + " indices");
  } else {
    idx.resize(n);
    for (size_t i = 0; i < n; ++i) idx[i] = uint32_t(i);
  }
  for (uint32_t i : idx)
    if (i >= n)
      fail(where + ": vertex index " + std::to_string(i) + " out of range (" + std::to_string(n) +
           " vertices)");
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
  triangles_ += mesh.triangle_count();
  if (max_triangles_ > 0 && triangles_ > max_triangles_)
    fail("the scene has more than " + std::to_string(max_triangles_) +
         " triangles, the limit of this load");
  mesh.transform(to_world);
  for (const Vec3& q : mesh.positions) bounds_.extend(q);
  MaterialPtr m = material(prim.material);
  const std::optional<AreaEmission>& e = emission_[prim.material];
  try {
    builder_.add_mesh(std::move(mesh), m, e ? &*e : nullptr);
  } catch (const std::runtime_error& error) {
    fail(where + ": " + error.what());
  }
}

// Cameras and lights are checked whether or not a node uses them: a broken one is a broken
// file, and the camera a user asks for by index need not be the first.
void GltfConverter::check_cameras_and_lights() const {
  for (size_t i = 0; i < model_.cameras.size(); ++i) {
    const tinygltf::Camera& c = model_.cameras[i];
    const std::string name = index_path("cameras", i);
    if (c.type != "perspective") continue;  // warned about if used
    const double yfov = c.perspective.yfov;
    if (!(yfov > 0 && yfov < kPi))
      fail(name + ".perspective.yfov: expected an angle in radians in (0, pi), got " +
           format_number(yfov));
    // tinygltf reads an absent aspectRatio as 0.
    const double aspect = c.perspective.aspectRatio;
    if (aspect != 0 && !in_range(aspect, 0.01, 100))
      fail(name + ".perspective.aspectRatio: expected a ratio in [0.01, 100], got " +
           format_number(aspect));
  }
  for (size_t i = 0; i < model_.lights.size(); ++i) {
    const tinygltf::Light& l = model_.lights[i];
    const std::string name = "KHR_lights_punctual.lights[" + std::to_string(i) + "]";
    if (!in_range(l.intensity, 0, HUGE_VAL))
      fail(name + ".intensity: expected a finite number >= 0, got " + format_number(l.intensity));
    for (double c : l.color)
      if (!in_range(c, 0, HUGE_VAL))
        fail(name + ".color: expected finite numbers >= 0, got " + format_number(c));
    // The power of a point light (a spot emits less) must be a finite float too.
    const float per_intensity = point_light_power_per_intensity();
    for (double c : l.color)
      if (!std::isfinite(float(c) * float(l.intensity) * per_intensity))
        fail(name + ": color times intensity overflows to infinity");
    if (!std::isfinite(float(l.intensity) * per_intensity))
      fail(name + ": intensity overflows to infinity");
    if (l.type == "spot") {
      const double outer = l.spot.outerConeAngle, inner = l.spot.innerConeAngle;
      if (!in_range(outer, 0, kPi / 2) || outer <= 0)
        fail(name + ".spot.outerConeAngle: expected an angle in (0, pi/2], got " +
             format_number(outer));
      if (!in_range(inner, 0, outer) || inner >= outer)
        fail(name + ".spot.innerConeAngle: expected an angle in [0, outerConeAngle), got " +
             format_number(inner));
    }
  }
}

void GltfConverter::visit(int node_index, const Transform& parent, int depth) {
  if (node_index < 0 || size_t(node_index) >= model_.nodes.size())
    fail("node " + std::to_string(node_index) + " does not exist (" +
         std::to_string(model_.nodes.size()) + " nodes)");
  const std::string name = index_path("nodes", size_t(node_index));
  // glTF nodes form disjoint trees. A node reached twice (two parents, listed twice, or a
  // cycle) would be instanced again each time: a few bytes could ask for exponentially many.
  if (visited_[size_t(node_index)])
    fail(name + " is reached twice (glTF nodes form trees: one parent per node, no cycles)");
  visited_[size_t(node_index)] = true;
  if (depth > kMaxNodeDepth)
    fail(name + ": the node hierarchy is deeper than " + std::to_string(kMaxNodeDepth));
  const tinygltf::Node& node = model_.nodes[size_t(node_index)];
  const Mat4 local = node_matrix(node);
  if (!is_finite(local)) fail(name + ": the transform is not finite");
  const Transform to_world = parent * to_transform(local);
  if (!is_finite(to_world.matrix())) fail(name + ": the world transform overflows");
  if (node.skin >= 0) warn("skins are not supported; meshes are rendered in their bind pose");
  if (node.mesh >= 0) {
    if (size_t(node.mesh) >= model_.meshes.size())
      fail(name + ": mesh " + std::to_string(node.mesh) + " does not exist (" +
           std::to_string(model_.meshes.size()) + " meshes)");
    const tinygltf::Mesh& mesh = model_.meshes[size_t(node.mesh)];
    for (size_t i = 0; i < mesh.primitives.size(); ++i)
      add_primitive(mesh.primitives[i], to_world,
                    index_path("meshes", size_t(node.mesh)) + index_path(".primitives", i));
  }
  if (node.camera >= 0) {
    if (size_t(node.camera) >= model_.cameras.size())
      fail(name + ": camera " + std::to_string(node.camera) + " does not exist (" +
           std::to_string(model_.cameras.size()) + " cameras)");
    cameras_.push_back({node.camera, to_world});
  }
  if (const tinygltf::Value* v = extension(node.extensions, "KHR_lights_punctual")) {
    // Not GetNumberAsInt(): it casts any double, and int(1e300) is undefined behaviour.
    const tinygltf::Value light = v->Get("light");
    const int li = light.IsInt() ? light.Get<int>() : -1;
    if (li < 0 || size_t(li) >= model_.lights.size())
      fail(name + ": KHR_lights_punctual.light must be the index of one of the " +
           std::to_string(model_.lights.size()) + " lights");
    const tinygltf::Light& l = model_.lights[size_t(li)];
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
      warn("light type " + quote_excerpt(l.type) + " is not supported; skipped");
    }
  }
  for (int child : node.children) visit(child, to_world, depth + 1);
}

void GltfConverter::convert(int camera_index) {
  // Checked first: a wrong request should not wait for the geometry.
  if (camera_index < -1 || (camera_index >= 0 && size_t(camera_index) >= model_.cameras.size()))
    fail("camera index " + std::to_string(camera_index) + " is out of range: the file has " +
         (model_.cameras.empty() ? std::string("no cameras")
          : model_.cameras.size() == 1
              ? std::string("1 camera (index 0)")
              : std::to_string(model_.cameras.size()) + " cameras (indices 0 to " +
                    std::to_string(model_.cameras.size() - 1) + ")"));
  check_cameras_and_lights();
  if (!model_.animations.empty()) warn("animations are not supported; using the rest pose");
  visited_.assign(model_.nodes.size(), false);
  const int scene = model_.defaultScene >= 0 ? model_.defaultScene : 0;
  if (model_.scenes.empty()) {
    // No scene: every root node.
    std::vector<bool> is_child(model_.nodes.size(), false);
    for (const auto& n : model_.nodes)
      for (int c : n.children)
        if (c >= 0 && size_t(c) < is_child.size()) is_child[size_t(c)] = true;
    for (size_t i = 0; i < model_.nodes.size(); ++i)
      if (!is_child[i]) visit(int(i), Transform(), 0);
  } else {
    if (size_t(scene) >= model_.scenes.size())
      fail("scene " + std::to_string(scene) + " does not exist (" +
           std::to_string(model_.scenes.size()) + " scenes)");
    for (int n : model_.scenes[size_t(scene)].nodes) visit(n, Transform(), 0);
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
    const tinygltf::Camera& c = model_.cameras[size_t(chosen->camera)];
    float yfov = radians(45.f), aspect = 16.f / 9.f;
    if (c.type == "perspective") {
      yfov = float(c.perspective.yfov);  // checked in check_cameras_and_lights
      if (c.perspective.aspectRatio > 0) aspect = float(c.perspective.aspectRatio);
    } else {
      warn("camera type " + quote_excerpt(c.type) +
           " is not supported; using a perspective camera");
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
}

// Parses `bytes` (JSON, or GLB when it starts with "glTF") and converts it into `builder`.
// `base_dir`: where external URIs are looked up; nothing disables file access.
}  // namespace gltf_input

namespace {

using gltf_input::GltfConverter;
using namespace gltf_input;

void parse_gltf(const std::string& bytes, const std::string& name,
                const std::optional<std::string>& base_dir, SceneBuilder& builder,
                Warnings& warnings, int camera_index, size_t max_triangles) {
  auto fail = [&](const std::string& what) { throw SceneLoadError({name, 0, 0}, what); };
  // tinygltf takes the size as an unsigned int.
  if (bytes.size() > UINT_MAX) fail("the file is larger than 4 GiB");
  const bool binary = bytes.size() >= 4 && bytes.compare(0, 4, "glTF") == 0;
  const std::string_view json = binary ? check_glb(bytes, name) : std::string_view(bytes);
  if (json_depth(json, kMaxJsonDepth) > kMaxJsonDepth)
    fail("JSON nested deeper than " + std::to_string(kMaxJsonDepth) + " levels");

  tinygltf::Model model;
  tinygltf::TinyGLTF loader;
  TinygltfContext context;
  context.allow_files = base_dir.has_value();
  context.model = &model;
  loader.SetFsCallbacks({fs_file_exists, fs_expand_path, fs_read_file, fs_write_file, &context});
  loader.SetImageLoader(load_image_data, &context);
  std::string err, warning;
  const std::string dir = base_dir.value_or("");
  const bool ok =
      binary ? loader.LoadBinaryFromMemory(&model, &err, &warning,
                                           reinterpret_cast<const unsigned char*>(bytes.data()),
                                           unsigned(bytes.size()), dir)
             : loader.LoadASCIIFromString(&model, &err, &warning, bytes.data(),
                                          unsigned(bytes.size()), dir);
  if (!warning.empty()) warnings.warn({name, 0, 0}, sanitize_tinygltf_message(warning));
  if (!ok) fail(err.empty() ? "not a valid glTF file" : sanitize_tinygltf_message(err));
  try {
    GltfConverter(model, name, warnings, builder, max_triangles).convert(camera_index);
  } catch (const SceneLoadError&) {
    throw;
  } catch (const std::exception& e) {
    fail(e.what());
  }
}

}  // namespace

std::unique_ptr<Scene> load_gltf(const std::string& path, WarningSink warn, int camera_index) {
  std::string bytes;
  try {
    bytes = read_input_file(path);
  } catch (const std::runtime_error& e) {
    throw SceneLoadError({path, 0, 0}, std::string("cannot open the scene file: ") + e.what());
  }
  Warnings warnings(warn);
  SceneBuilder builder;
  parse_gltf(bytes, path, std::filesystem::path(path).parent_path().string(), builder, warnings,
             camera_index, 0);
  try {
    return builder.build(std::filesystem::path(path).stem().string());
  } catch (const std::runtime_error& e) {
    throw SceneLoadError({path, 0, 0}, e.what());
  }
}

void parse_gltf_memory(const std::string& bytes, const std::string& name, SceneBuilder& builder,
                       WarningSink warn, int camera_index, size_t max_triangles) {
  Warnings warnings(warn);
  parse_gltf(bytes, name, std::nullopt, builder, warnings, camera_index, max_triangles);
}

}  // namespace caustica
