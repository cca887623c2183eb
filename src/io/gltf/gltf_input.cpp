// tinygltf is compiled once, in tinygltf_impl.cpp; this file sees only its declarations.
#define TINYGLTF_NO_STB_IMAGE_WRITE
#define TINYGLTF_NO_INCLUDE_STB_IMAGE_WRITE
#include "io/gltf/gltf_input.h"

#include <stb_image.h>
#include <tiny_gltf.h>

#include <climits>
#include <cstring>
#include <filesystem>

#include "io/input_file.h"
#include "io/load_error.h"

namespace caustica::gltf_input {

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

namespace {
uint32_t read_u32(const std::string& bytes, size_t offset) {
  uint32_t v;
  std::memcpy(&v, bytes.data() + offset, 4);
  return v;  // GLB is little-endian, like every machine this runs on
}
}  // namespace

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

}  // namespace caustica::gltf_input
