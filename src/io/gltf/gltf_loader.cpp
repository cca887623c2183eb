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
#include "io/input_file.h"
#include "io/pbrt/warnings.h"
#include "io/scene_builder.h"
#include "lights/light_power.h"
#include "lights/lights.h"
#include "materials/materials.h"

namespace caustica {

namespace {

using pbrt::Warnings;

// Limits on what a file may claim, checked before anything is allocated for it.
// tinygltf's JSON values are converted recursively: deep nesting would exhaust the stack.
constexpr int kMaxJsonDepth = 256;
// glTF nodes form trees; deeper than this is a mistake (and recursion).
constexpr int kMaxNodeDepth = 256;
// Images are decoded (by stb_image, inside tinygltf) as soon as they are parsed, at the size
// their header claims. No format stb_image reads packs more than about 2,700 pixels into a
// byte (GIF's LZW; deflate's limit is about 1,032:1, JPEG's about 512:1), so a header that
// claims more than 4,096 pixels per byte of image data is a lie; 16384^2 bounds the rest.
constexpr uint64_t kMaxPixelsPerByte = 4096;
constexpr uint64_t kMaxImagePixels = uint64_t(16384) * 16384;

std::string index_path(const char* array, size_t index) {
  return std::string(array) + "[" + std::to_string(index) + "]";
}

// tinygltf's messages quote the input (URIs, whole data: URIs) and may span lines: one
// line, escaped and bounded, keeps them readable and safe to print.
std::string sanitize_tinygltf_message(const std::string& text) {
  std::string joined;
  for (char c : text) {
    if (c == '\n') {
      if (!joined.empty() && joined.back() != ' ') joined += "; ";
    } else {
      joined += c;
    }
  }
  while (!joined.empty() && (joined.back() == ' ' || joined.back() == ';')) joined.pop_back();
  constexpr size_t kMaxBytes = 300;
  const bool cut = joined.size() > kMaxBytes;
  return escape_text(cut ? joined.substr(0, kMaxBytes) : joined) + (cut ? "..." : "");
}

// What tinygltf's callbacks need: whether files may be read, and the model being parsed
// (its buffers and bufferViews are parsed before its images).
struct TinygltfContext {
  bool allow_files = false;
  const tinygltf::Model* model = nullptr;
};

bool fs_file_exists(const std::string& path, void* user) {
  // Without file access, "exists" lets fs_read_file say why the file is not read.
  if (!static_cast<const TinygltfContext*>(user)->allow_files) return true;
  std::error_code ec;
  return std::filesystem::exists(path, ec);
}

// tinygltf's own expansion once used wordexp(); a URI is a path, nothing more.
std::string fs_expand_path(const std::string& path, void*) { return path; }

bool fs_read_file(std::vector<unsigned char>* out, std::string* err, const std::string& path,
                  void* user) {
  if (!static_cast<const TinygltfContext*>(user)->allow_files) {
    if (err) *err += "file access is disabled when parsing from memory";
    return false;
  }
  try {
    // read_input_file refuses directories, devices and FIFOs; tinygltf's reader would take
    // a directory's lseek() size as its length.
    const std::string data = read_input_file(path);
    out->assign(data.begin(), data.end());
    return true;
  } catch (const std::exception& e) {
    if (err) *err += e.what();
    return false;
  }
}

bool fs_write_file(std::string* err, const std::string&, const std::vector<unsigned char>&, void*) {
  if (err) *err += "the loader does not write files";
  return false;
}

bool load_image_data(tinygltf::Image* image, const int index, std::string* err, std::string* warn,
                     int req_width, int req_height, const unsigned char* bytes, int size,
                     void* user) {
  const auto& ctx = *static_cast<const TinygltfContext*>(user);
  auto reject = [&](const std::string& why) {
    if (err) *err += index_path("images", size_t(index)) + ": " + why + "\n";
    return false;
  };
  if (image->bufferView >= 0) {
    // tinygltf checks the bufferView and buffer indices, but hands over
    // &buffer.data[byteOffset] and byteLength without checking them against the buffer.
    const tinygltf::BufferView& view = ctx.model->bufferViews[size_t(image->bufferView)];
    const size_t buffer_size = ctx.model->buffers[size_t(view.buffer)].data.size();
    if (view.byteOffset > buffer_size || view.byteLength > buffer_size - view.byteOffset ||
        view.byteLength > size_t(INT_MAX))
      return reject(index_path("bufferViews", size_t(image->bufferView)) +
                    " lies outside its buffer (" + std::to_string(buffer_size) + " bytes)");
  }
  if (size <= 0) return reject("no image data");
  int width = 0, height = 0, components = 0;
  if (!stbi_info_from_memory(bytes, size, &width, &height, &components))
    return reject("not an image format that can be decoded (PNG, JPEG, ...)");
  const uint64_t pixels = uint64_t(width) * uint64_t(height);
  if (pixels > kMaxImagePixels || pixels > kMaxPixelsPerByte * uint64_t(size))
    return reject("its header claims " + std::to_string(width) + "x" + std::to_string(height) +
                  " pixels, more than its " + std::to_string(size) + " bytes can hold");
  return tinygltf::LoadImageData(image, index, err, warn, req_width, req_height, bytes, size,
                                 nullptr);
}

// The deepest nesting of arrays and objects in JSON text (strings skipped), stopping as soon
// as it exceeds `limit`.
int json_depth(std::string_view text, int limit) {
  int depth = 0, deepest = 0;
  bool in_string = false;
  for (size_t i = 0; i < text.size() && deepest <= limit; ++i) {
    const char c = text[i];
    if (in_string) {
      if (c == '\\')
        ++i;
      else if (c == '"')
        in_string = false;
    } else if (c == '"') {
      in_string = true;
    } else if (c == '[' || c == '{') {
      deepest = std::max(deepest, ++depth);
    } else if (c == ']' || c == '}') {
      --depth;
    }
  }
  return deepest;
}

uint32_t read_u32(const std::string& bytes, size_t offset) {
  uint32_t v;
  std::memcpy(&v, bytes.data() + offset, 4);
  return v;  // GLB is little-endian, like every machine this runs on
}

// tinygltf 2.7 checks the BIN chunk's length against the file without its 8-byte chunk
// header, so a chunk may claim 8 bytes past the end. Returns the JSON chunk.
std::string_view check_glb(const std::string& bytes, const std::string& name) {
  auto fail = [&](const std::string& what) { throw SceneLoadError({name, 0, 0}, "GLB: " + what); };
  if (bytes.size() < 20) fail("the file is shorter than the 20-byte header");
  const uint64_t length = read_u32(bytes, 8), json_length = read_u32(bytes, 12);
  if (length > bytes.size())
    fail("the header's length " + std::to_string(length) + " exceeds the file's " +
         std::to_string(bytes.size()) + " bytes");
  if (20 + json_length > length)
    fail("the JSON chunk (" + std::to_string(json_length) + " bytes) runs past the end");
  const uint64_t bin = 20 + json_length;
  if (bin < length) {
    if (bin + 8 > length) fail("the BIN chunk header runs past the end");
    const uint64_t bin_length = read_u32(bytes, size_t(bin));
    if (bin + 8 + bin_length > length)
      fail("the BIN chunk (" + std::to_string(bin_length) + " bytes) runs past the end");
  }
  return std::string_view(bytes).substr(20, size_t(json_length));
}

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
bool in_range(double v, double lo, double hi) {
  return std::isfinite(float(v)) && v >= lo && v <= hi;
}

GltfConverter::AccessorSpan GltfConverter::accessor_span(int index, int components,
                                                         const std::string& what) const {
  if (index < 0 || size_t(index) >= model_.accessors.size())
    fail(what + ": accessor " + std::to_string(index) + " does not exist (" +
         std::to_string(model_.accessors.size()) + " accessors)");
  const std::string name = index_path("accessors", size_t(index));
  const tinygltf::Accessor& a = model_.accessors[size_t(index)];
  if (a.sparse.isSparse) fail(name + ": sparse accessors are not supported");
  if (tinygltf::GetNumComponentsInType(uint32_t(a.type)) != components)
    fail(name + ": " + what + " needs " + std::to_string(components) +
         " components per element, the accessor's type has " +
         std::to_string(tinygltf::GetNumComponentsInType(uint32_t(a.type))));
  const int component_size = tinygltf::GetComponentSizeInBytes(uint32_t(a.componentType));
  if (component_size <= 0)
    fail(name + ": unknown componentType " + std::to_string(a.componentType));
  AccessorSpan span;
  span.count = a.count;
  if (a.bufferView < 0) return span;
  if (size_t(a.bufferView) >= model_.bufferViews.size())
    fail(name + ": bufferView " + std::to_string(a.bufferView) + " does not exist (" +
         std::to_string(model_.bufferViews.size()) + " bufferViews)");
  const std::string view_name = index_path("bufferViews", size_t(a.bufferView));
  const tinygltf::BufferView& view = model_.bufferViews[size_t(a.bufferView)];
  if (view.buffer < 0 || size_t(view.buffer) >= model_.buffers.size())
    fail(view_name + ": buffer " + std::to_string(view.buffer) + " does not exist (" +
         std::to_string(model_.buffers.size()) + " buffers)");
  const size_t buffer_size = model_.buffers[size_t(view.buffer)].data.size();
  // Every comparison below is arranged so that nothing can overflow: sizes are subtracted
  // from what is known to be larger, never added or multiplied.
  if (view.byteOffset > buffer_size || view.byteLength > buffer_size - view.byteOffset)
    fail(view_name + ": byteOffset " + std::to_string(view.byteOffset) + " + byteLength " +
         std::to_string(view.byteLength) + " exceeds the " + std::to_string(buffer_size) +
         " bytes of " + index_path("buffers", size_t(view.buffer)));
  const size_t element = size_t(component_size) * size_t(components);
  span.stride = view.byteStride ? view.byteStride : element;
  if (a.count > 0) {
    const size_t available = view.byteLength;
    // byteOffset + (count - 1) * stride + element <= byteLength
    if (a.byteOffset > available || element > available - a.byteOffset ||
        a.count - 1 > (available - a.byteOffset - element) / span.stride)
      fail(name + ": count " + std::to_string(a.count) + " (elements of " +
           std::to_string(element) + " bytes, stride " + std::to_string(span.stride) +
           ", byteOffset " + std::to_string(a.byteOffset) + ") needs more than the " +
           std::to_string(available) + " bytes of " + view_name);
  }
  span.first = model_.buffers[size_t(view.buffer)].data.data() + view.byteOffset + a.byteOffset;
  return span;
}

std::vector<float> GltfConverter::read_floats(int index, int components, const std::string& what) {
  const AccessorSpan span = accessor_span(index, components, what);
  const tinygltf::Accessor& a = model_.accessors[size_t(index)];
  if (!span.first) {
    // All zeros by the spec, meant for sparse accessors (not supported): nothing to read,
    // and nothing is allocated for a count no data backs.
    warn(index_path("accessors", size_t(index)) + " has no bufferView; " + what + " ignored");
    return {};
  }
  // Safe to allocate now: count elements were checked to lie inside the buffer.
  std::vector<float> out(span.count * size_t(components));
  for (size_t i = 0; i < span.count; ++i)
    for (int c = 0; c < components; ++c) {
      const unsigned char* p =
          span.first + i * span.stride +
          size_t(c) * size_t(tinygltf::GetComponentSizeInBytes(uint32_t(a.componentType)));
      float v = 0;
      switch (a.componentType) {
        case TINYGLTF_COMPONENT_TYPE_FLOAT:
          std::memcpy(&v, p, 4);
          if (!std::isfinite(v))
            fail(index_path("accessors", size_t(index)) + ": " + what + " element " +
                 std::to_string(i) + " is not a finite number");
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
          fail(index_path("accessors", size_t(index)) + ": unsupported componentType " +
               std::to_string(a.componentType));
      }
      out[i * size_t(components) + size_t(c)] = v;
    }
  return out;
}

std::vector<uint32_t> GltfConverter::read_indices(int index, const std::string& what) {
  const AccessorSpan span = accessor_span(index, 1, what);
  const tinygltf::Accessor& a = model_.accessors[size_t(index)];
  const int type = a.componentType;
  if (type != TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE &&
      type != TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT &&
      type != TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT)
    fail(index_path("accessors", size_t(index)) + ": " + what +
         " must be unsigned integers (componentType 5121, 5123 or 5125), got " +
         std::to_string(type));
  if (!span.first) {
    warn(index_path("accessors", size_t(index)) + " has no bufferView; " + what + " ignored");
    return {};
  }
  std::vector<uint32_t> out(span.count);
  for (size_t i = 0; i < span.count; ++i) {
    const unsigned char* p = span.first + i * span.stride;
    if (type == TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE) {
      out[i] = p[0];
    } else if (type == TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT) {
      uint16_t u;
      std::memcpy(&u, p, 2);
      out[i] = u;
    } else {
      std::memcpy(&out[i], p, 4);  // exact (floats lose precision above 2^24)
    }
  }
  return out;
}

TexturePtr GltfConverter::base_color_texture(const tinygltf::Material& m,
                                             const std::string& where) {
  const auto& pbr = m.pbrMetallicRoughness;
  Rgb factor(1.f);
  if (pbr.baseColorFactor.size() >= 3)
    factor = Rgb(float(pbr.baseColorFactor[0]), float(pbr.baseColorFactor[1]),
                 float(pbr.baseColorFactor[2]));
  factor = clamp(factor, 0.f, 1.f);
  const int tex = pbr.baseColorTexture.index;
  if (tex < 0) return make_constant_texture(factor);
  if (size_t(tex) >= model_.textures.size())
    fail(where + ".pbrMetallicRoughness.baseColorTexture: texture " + std::to_string(tex) +
         " does not exist (" + std::to_string(model_.textures.size()) + " textures)");
  if (pbr.baseColorTexture.texCoord != 0)
    warn("texture coordinate sets other than TEXCOORD_0 are not supported");
  if (!pbr.baseColorTexture.extensions.empty())
    warn("texture extensions (KHR_texture_transform) are not supported; ignored");
  const int source = model_.textures[size_t(tex)].source;
  if (source < 0 || size_t(source) >= model_.images.size()) {
    warn("texture without a supported image source; using the base colour factor");
    return make_constant_texture(factor);
  }
  auto it = images_.find(source);
  if (it == images_.end()) {
    const tinygltf::Image& src = model_.images[size_t(source)];
    const std::string name = index_path("images", size_t(source));
    if (src.width <= 0 || src.height <= 0 || src.image.empty() ||
        (src.bits != 8 && src.bits != 16) || src.component < 1)
      fail(name + " (" + quote_excerpt(src.uri, kPathExcerpt) + ") could not be decoded");
    const size_t bytes = size_t(src.bits / 8), comps = size_t(src.component);
    if (src.image.size() / bytes / comps / size_t(src.width) < size_t(src.height))
      fail(name + " is truncated");
    auto image = std::make_shared<Image>(src.width, src.height);
    for (int y = 0; y < src.height; ++y)
      for (int x = 0; x < src.width; ++x) {
        const size_t base = (size_t(y) * size_t(src.width) + size_t(x)) * comps;
        Rgb c;
        for (size_t k = 0; k < 3; ++k) {
          const size_t ch = std::min(k, comps > 2 ? k : size_t(0));
          float v;
          if (bytes == 1) {
            v = src.image[base + ch] / 255.f;
          } else {
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
      fail("material " + std::to_string(index) + " does not exist (" +
           std::to_string(model_.materials.size()) + " materials)");
    const std::string where = index_path("materials", size_t(index));
    const tinygltf::Material& m = model_.materials[size_t(index)];
    const auto& pbr = m.pbrMetallicRoughness;
    const float metallic = clamp(float(pbr.metallicFactor), 0.f, 1.f);
    const float roughness = clamp(float(pbr.roughnessFactor), 0.f, 1.f);
    // glTF roughness is perceptual: GGX alpha = roughness^2.
    TexturePtr alpha = roughness > 0 ? make_constant_texture(Rgb(roughness * roughness)) : nullptr;
    TexturePtr base = base_color_texture(m, where);
    if (pbr.metallicRoughnessTexture.index >= 0)
      warn("metallicRoughnessTexture is not supported; using the factors");
    if (m.normalTexture.index >= 0) warn("normal textures are not supported; ignored");
    if (m.occlusionTexture.index >= 0) warn("occlusion textures are not supported; ignored");
    if (m.emissiveTexture.index >= 0)
      warn("emissive textures are not supported; using emissiveFactor");
    if (m.alphaMode != "OPAQUE")
      warn("alphaMode " + quote_excerpt(m.alphaMode) + " is not supported; surfaces are opaque");

    double ior = 1.5, transmission = 0, strength = 1;
    if (const tinygltf::Value* v = extension(m.extensions, "KHR_materials_ior"))
      if (v->Has("ior")) ior = v->Get("ior").GetNumberAsDouble();
    if (const tinygltf::Value* v = extension(m.extensions, "KHR_materials_transmission"))
      if (v->Has("transmissionFactor"))
        transmission = v->Get("transmissionFactor").GetNumberAsDouble();
    if (const tinygltf::Value* v = extension(m.extensions, "KHR_materials_emissive_strength"))
      if (v->Has("emissiveStrength")) strength = v->Get("emissiveStrength").GetNumberAsDouble();
    if (!in_range(ior, 0, HUGE_VAL))
      fail(where + ": KHR_materials_ior.ior: expected a finite number >= 1 (or 0), got " +
           format_number(ior));
    if (!in_range(transmission, 0, 1))
      fail(where +
           ": KHR_materials_transmission.transmissionFactor: expected a number in "
           "[0, 1], got " +
           format_number(transmission));
    if (!in_range(strength, 0, HUGE_VAL))
      fail(where +
           ": KHR_materials_emissive_strength.emissiveStrength: expected a finite "
           "number >= 0, got " +
           format_number(strength));
    for (const auto& [name, value] : m.extensions)
      if (name != "KHR_materials_ior" && name != "KHR_materials_transmission" &&
          name != "KHR_materials_emissive_strength")
        warn("material extension " + quote_excerpt(name) + " is not supported; ignored");
    if (!(ior >= 1)) ior = 1.5;  // ior 0 means "no refraction" in glTF; 1.5 is its default

    if (transmission > 0) {
      DielectricParams d;
      d.eta = float(ior);
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
        c.eta = float(ior);
        plastic = make_coated_diffuse(c);
      }
      result = !metal     ? plastic
               : !plastic ? metal
                          : make_mix(plastic, metal, make_constant_texture(Rgb(metallic)));
    }
    if (m.emissiveFactor.size() == 3) {
      for (double e : m.emissiveFactor)
        if (!in_range(e, 0, HUGE_VAL))
          fail(where + ".emissiveFactor: expected finite numbers >= 0, got " + format_number(e));
      const Rgb e =
          Rgb(float(m.emissiveFactor[0]), float(m.emissiveFactor[1]), float(m.emissiveFactor[2])) *
          float(strength);
      if (!e.is_finite())
        fail(where + ": emissiveFactor times emissiveStrength overflows to infinity");
      if (!e.is_black()) emission = AreaEmission{e, m.doubleSided};
    }
  }
  materials_[index] = result;
  emission_[index] = emission;
  return result;
}

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
