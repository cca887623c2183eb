// tinygltf is compiled once, in tinygltf_impl.cpp; this file sees only its declarations.
#define TINYGLTF_NO_STB_IMAGE_WRITE
#define TINYGLTF_NO_INCLUDE_STB_IMAGE_WRITE
#include <climits>
#include <cstring>

#include "io/gltf/gltf_converter.h"
#include "io/gltf/gltf_input.h"

namespace caustica::gltf_input {

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

}  // namespace caustica::gltf_input
