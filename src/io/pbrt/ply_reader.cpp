#include "io/pbrt/ply_reader.h"

#include <bit>
#include <cctype>
#include <charconv>
#include <cmath>
#include <cstring>
#include <fstream>
#include <sstream>
#include <stdexcept>

#include "io/input_file.h"
#include "io/load_error.h"

namespace caustica::pbrt {

namespace {

enum class Scalar { Int8, UInt8, Int16, UInt16, Int32, UInt32, Float32, Float64 };

bool parse_scalar(const std::string& s, Scalar* out) {
  static const struct {
    const char* name;
    Scalar type;
  } names[] = {
      {"char", Scalar::Int8},      {"int8", Scalar::Int8},       {"uchar", Scalar::UInt8},
      {"uint8", Scalar::UInt8},    {"short", Scalar::Int16},     {"int16", Scalar::Int16},
      {"ushort", Scalar::UInt16},  {"uint16", Scalar::UInt16},   {"int", Scalar::Int32},
      {"int32", Scalar::Int32},    {"uint", Scalar::UInt32},     {"uint32", Scalar::UInt32},
      {"float", Scalar::Float32},  {"float32", Scalar::Float32}, {"double", Scalar::Float64},
      {"float64", Scalar::Float64}};
  for (const auto& n : names)
    if (s == n.name) {
      *out = n.type;
      return true;
    }
  return false;
}

size_t scalar_size(Scalar s) {
  switch (s) {
    case Scalar::Int8:
    case Scalar::UInt8:
      return 1;
    case Scalar::Int16:
    case Scalar::UInt16:
      return 2;
    case Scalar::Int32:
    case Scalar::UInt32:
    case Scalar::Float32:
      return 4;
    case Scalar::Float64:
      return 8;
  }
  return 1;
}

struct Property {
  std::string name;
  Scalar type = Scalar::Float32;
  bool is_list = false;
  Scalar count_type = Scalar::UInt8;
};

struct Element {
  std::string name;
  size_t count = 0;
  std::vector<Property> properties;
};

enum class Format { Ascii, BinaryLittle, BinaryBig };

[[noreturn]] void fail(const std::string& message) { throw std::runtime_error(message); }

// Sequential reader of element data in any of the three formats.
class DataReader {
 public:
  DataReader(const std::string& data, size_t pos, Format format)
      : data_(data), pos_(pos), format_(format) {}

  double read(Scalar type, const char* what) {
    if (format_ == Format::Ascii) return read_ascii(what);
    const size_t n = scalar_size(type);
    if (pos_ + n > data_.size()) fail(std::string("unexpected end of file while reading ") + what);
    unsigned char b[8];
    std::memcpy(b, data_.data() + pos_, n);
    pos_ += n;
    const bool swap =
        (format_ == Format::BinaryBig) == (std::endian::native == std::endian::little);
    if (swap)
      for (size_t i = 0; i < n / 2; ++i) std::swap(b[i], b[n - 1 - i]);
    switch (type) {
      case Scalar::Int8: {
        int8_t v;
        std::memcpy(&v, b, 1);
        return v;
      }
      case Scalar::UInt8:
        return b[0];
      case Scalar::Int16: {
        int16_t v;
        std::memcpy(&v, b, 2);
        return v;
      }
      case Scalar::UInt16: {
        uint16_t v;
        std::memcpy(&v, b, 2);
        return v;
      }
      case Scalar::Int32: {
        int32_t v;
        std::memcpy(&v, b, 4);
        return v;
      }
      case Scalar::UInt32: {
        uint32_t v;
        std::memcpy(&v, b, 4);
        return v;
      }
      case Scalar::Float32: {
        float v;
        std::memcpy(&v, b, 4);
        return v;
      }
      case Scalar::Float64: {
        double v;
        std::memcpy(&v, b, 8);
        return v;
      }
    }
    return 0;
  }

  size_t remaining() const { return data_.size() - pos_; }

 private:
  double read_ascii(const char* what) {
    while (pos_ < data_.size() && std::isspace(static_cast<unsigned char>(data_[pos_]))) ++pos_;
    if (pos_ >= data_.size()) fail(std::string("unexpected end of file while reading ") + what);
    size_t end = pos_;
    while (end < data_.size() && !std::isspace(static_cast<unsigned char>(data_[end]))) ++end;
    const char* first = data_.data() + pos_;
    const char* last = data_.data() + end;
    if (*first == '+') ++first;
    double v = 0;
    const auto [ptr, ec] = std::from_chars(first, last, v);
    if (ec != std::errc() || ptr != last)
      fail(std::string("expected a number in ") + what + ", got " +
           quote_excerpt(std::string_view(data_).substr(pos_, end - pos_)));
    pos_ = end;
    return v;
  }

  const std::string& data_;
  size_t pos_;
  Format format_;
};

// A list's length: a non-negative integer that the remaining data could hold (every item
// takes at least one byte or one character), so a corrupt count cannot make us loop long.
size_t list_length(DataReader& reader, Scalar count_type, const char* what) {
  const double n = reader.read(count_type, what);
  if (!(n >= 0) || n != std::floor(n) || n > double(reader.remaining()))
    fail(std::string("invalid list length ") + std::to_string(n) + " in " + what);
  return size_t(n);
}

}  // namespace

PlyMesh parse_ply(const std::string& data) {
  // Header: lines up to "end_header".
  size_t pos = 0;
  auto next_line = [&](std::string* line) {
    if (pos >= data.size()) return false;
    size_t end = data.find('\n', pos);
    if (end == std::string::npos) end = data.size();
    *line = data.substr(pos, end - pos);
    if (!line->empty() && line->back() == '\r') line->pop_back();
    pos = end + 1;
    return true;
  };
  std::string line;
  if (!next_line(&line) || line != "ply") fail("not a PLY file (the first line is not \"ply\")");
  Format format = Format::Ascii;
  bool have_format = false, ended = false;
  std::vector<Element> elements;
  int line_number = 1;
  while (next_line(&line)) {
    ++line_number;
    std::istringstream in(line);
    std::string keyword;
    in >> keyword;
    const std::string at = "header line " + std::to_string(line_number);
    if (keyword.empty() || keyword == "comment" || keyword == "obj_info") continue;
    if (keyword == "end_header") {
      ended = true;
      break;
    }
    if (keyword == "format") {
      std::string f, version;
      in >> f >> version;
      if (f == "ascii")
        format = Format::Ascii;
      else if (f == "binary_little_endian")
        format = Format::BinaryLittle;
      else if (f == "binary_big_endian")
        format = Format::BinaryBig;
      else
        fail(at + ": unknown format " + quote_excerpt(f));
      have_format = true;
    } else if (keyword == "element") {
      Element e;
      long long count = -1;
      in >> e.name >> count;
      if (e.name.empty() || !in || count < 0) fail(at + ": expected \"element <name> <count>\"");
      e.count = size_t(count);
      elements.push_back(std::move(e));
    } else if (keyword == "property") {
      if (elements.empty()) fail(at + ": property before any element");
      Property p;
      std::string type;
      in >> type;
      if (type == "list") {
        std::string count_type, item_type;
        in >> count_type >> item_type >> p.name;
        p.is_list = true;
        if (!parse_scalar(count_type, &p.count_type) || !parse_scalar(item_type, &p.type) ||
            p.count_type == Scalar::Float32 || p.count_type == Scalar::Float64)
          fail(at + ": bad list property " + quote_excerpt(line));
      } else {
        in >> p.name;
        if (!parse_scalar(type, &p.type))
          fail(at + ": unknown property type " + quote_excerpt(type));
      }
      if (p.name.empty()) fail(at + ": property without a name");
      elements.back().properties.push_back(std::move(p));
    } else {
      fail(at + ": unexpected " + quote_excerpt(keyword));
    }
  }
  if (!have_format) fail("the header has no \"format\" line");
  if (!ended) fail("the header has no \"end_header\" line");

  PlyMesh mesh;
  DataReader reader(data, pos, format);
  bool have_vertices = false;
  for (const Element& e : elements) {
    if (e.name == "vertex") {
      have_vertices = true;
      int ix = -1, iy = -1, iz = -1, inx = -1, iny = -1, inz = -1, iu = -1, iv = -1;
      for (int i = 0; i < int(e.properties.size()); ++i) {
        const std::string& n = e.properties[i].name;
        if (e.properties[i].is_list) continue;
        if (n == "x")
          ix = i;
        else if (n == "y")
          iy = i;
        else if (n == "z")
          iz = i;
        else if (n == "nx")
          inx = i;
        else if (n == "ny")
          iny = i;
        else if (n == "nz")
          inz = i;
        else if (n == "u" || n == "s" || n == "texture_u" || n == "texture_s")
          iu = i;
        else if (n == "v" || n == "t" || n == "texture_v" || n == "texture_t")
          iv = i;
      }
      if (ix < 0 || iy < 0 || iz < 0) fail("the vertex element has no x, y and z properties");
      const bool normals = inx >= 0 && iny >= 0 && inz >= 0, uvs = iu >= 0 && iv >= 0;
      // Never trust a count for allocation beyond what the data can hold.
      const size_t cap = std::min(e.count, reader.remaining() + 1);
      mesh.positions.reserve(cap);
      if (normals) mesh.normals.reserve(cap);
      if (uvs) mesh.uvs.reserve(cap);
      std::vector<double> values(e.properties.size());
      for (size_t v = 0; v < e.count; ++v) {
        for (size_t i = 0; i < e.properties.size(); ++i) {
          const Property& p = e.properties[i];
          if (p.is_list) {
            const size_t n = list_length(reader, p.count_type, "vertex data");
            for (size_t k = 0; k < n; ++k) reader.read(p.type, "vertex data");
            continue;
          }
          values[i] = reader.read(p.type, "vertex data");
        }
        mesh.positions.emplace_back(float(values[ix]), float(values[iy]), float(values[iz]));
        if (normals)
          mesh.normals.emplace_back(float(values[inx]), float(values[iny]), float(values[inz]));
        if (uvs) mesh.uvs.emplace_back(float(values[iu]), float(values[iv]));
      }
    } else if (e.name == "face") {
      int index_property = -1;
      for (int i = 0; i < int(e.properties.size()); ++i)
        if (e.properties[i].is_list &&
            (e.properties[i].name == "vertex_indices" || e.properties[i].name == "vertex_index"))
          index_property = i;
      if (index_property < 0) fail("the face element has no vertex_indices list");
      mesh.indices.reserve(std::min(e.count, reader.remaining() + 1) * 3);
      uint32_t face[4];
      for (size_t f = 0; f < e.count; ++f) {
        for (int i = 0; i < int(e.properties.size()); ++i) {
          const Property& p = e.properties[i];
          if (!p.is_list) {
            reader.read(p.type, "face data");
            continue;
          }
          const size_t count = list_length(reader, p.count_type, "face data");
          for (size_t k = 0; k < count; ++k) {
            const double idx = reader.read(p.type, "face data");
            if (i != index_property) continue;
            if (!(idx >= 0 && idx < 4294967295.0) || idx != std::floor(idx))
              fail("face " + std::to_string(f) + " has an invalid vertex index " +
                   std::to_string(idx));
            if (k < 4) face[k] = uint32_t(idx);
          }
          if (i != index_property) continue;
          if (count == 3) {
            mesh.indices.insert(mesh.indices.end(), {face[0], face[1], face[2]});
          } else if (count == 4) {
            mesh.indices.insert(mesh.indices.end(),
                                {face[0], face[1], face[2], face[0], face[2], face[3]});
          } else {
            ++mesh.skipped_faces;
          }
        }
      }
    } else {
      // Skip any other element property by property.
      if (e.properties.empty()) continue;
      for (size_t k = 0; k < e.count; ++k)
        for (const Property& p : e.properties) {
          if (p.is_list) {
            const size_t n = list_length(reader, p.count_type, "element data");
            for (size_t j = 0; j < n; ++j) reader.read(p.type, "element data");
          } else {
            reader.read(p.type, "element data");
          }
        }
    }
  }
  if (!have_vertices) fail("the file has no vertex element");
  for (uint32_t i : mesh.indices)
    if (i >= mesh.positions.size())
      fail("vertex index " + std::to_string(i) + " is out of range (" +
           std::to_string(mesh.positions.size()) + " vertices)");
  return mesh;
}

PlyMesh read_ply(const std::string& path) {
  std::string data;
  try {
    data = read_input_file(path);
  } catch (const std::runtime_error& e) {
    throw std::runtime_error("cannot read " + quote_excerpt(path, kPathExcerpt) + ": " + e.what());
  }
  try {
    return parse_ply(data);
  } catch (const std::runtime_error& e) {
    throw std::runtime_error(quote_excerpt(path, kPathExcerpt) + ": " + e.what());
  }
}

}  // namespace caustica::pbrt
