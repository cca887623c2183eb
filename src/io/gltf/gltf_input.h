// What the glTF loader lets tinygltf read, and the checks on a file before tinygltf parses it:
// file access through read_input_file (no directories, devices or FIFOs; none at all when
// parsing from memory), image headers checked against their data before decoding, JSON nesting
// and GLB chunk lengths bounded, tinygltf's messages escaped and cut to one line.
#pragma once

#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

namespace tinygltf {
struct Image;
class Model;
}  // namespace tinygltf

namespace caustica::gltf_input {

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

// "array[index]", the JSON path errors name.
std::string index_path(const char* array, size_t index);
// tinygltf's messages quote the input (URIs, whole data: URIs) and may span lines: one line,
// escaped and bounded.
std::string sanitize_tinygltf_message(const std::string& text);

// What tinygltf's callbacks need: whether files may be read, and the model being parsed (its
// buffers and bufferViews are parsed before its images).
struct TinygltfContext {
  bool allow_files = false;
  const tinygltf::Model* model = nullptr;
};
// tinygltf's FsCallbacks and image loader; `user` is a TinygltfContext.
bool fs_file_exists(const std::string& path, void* user);
std::string fs_expand_path(const std::string& path, void* user);
bool fs_read_file(std::vector<unsigned char>* out, std::string* err, const std::string& path,
                  void* user);
bool fs_write_file(std::string* err, const std::string& path,
                   const std::vector<unsigned char>& data, void* user);
bool load_image_data(tinygltf::Image* image, const int index, std::string* err, std::string* warn,
                     int req_width, int req_height, const unsigned char* bytes, int size,
                     void* user);

// The deepest nesting of arrays and objects in JSON text (strings skipped), stopping as soon as
// it exceeds `limit`.
int json_depth(std::string_view text, int limit);
// Checks a GLB container's header and chunk lengths (throws SceneLoadError naming `name`);
// returns the JSON chunk.
std::string_view check_glb(const std::string& bytes, const std::string& name);

}  // namespace caustica::gltf_input
