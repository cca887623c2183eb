// Image file formats. Every reader turns any failure (missing file, truncated or corrupt data,
// library exception) into std::runtime_error("<path>: <what>"); every writer encodes into
// memory and hands the bytes to write_file_atomic.
#include "image/image_io.h"

#include <ImfChannelList.h>
#include <ImfFrameBuffer.h>
#include <ImfHeader.h>
#include <ImfIO.h>
#include <ImfInputFile.h>
#include <ImfOutputFile.h>
#include <fcntl.h>
#include <stb_image.h>
#include <stb_image_write.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <bit>
#include <cctype>
#include <cerrno>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>
#include <memory>
#include <sstream>
#include <stdexcept>
#include <vector>

namespace caustica {
namespace {

// Refuse absurd sizes from corrupt headers before allocating (2^28 pixels = 3 GiB as Rgb).
constexpr int64_t kMaxPixels = int64_t(1) << 28;

[[noreturn]] void fail(const std::string& path, const std::string& what) {
  throw std::runtime_error(path + ": " + what);
}

std::string lower_extension(const std::string& path) {
  std::string ext = std::filesystem::path(path).extension().string();
  for (char& c : ext) c = char(std::tolower(static_cast<unsigned char>(c)));
  return ext;
}

std::string read_whole_file(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) fail(path, std::string("cannot open: ") + std::strerror(errno));
  std::ostringstream buffer;
  buffer << in.rdbuf();
  if (in.bad()) fail(path, "read error");
  return std::move(buffer).str();
}

// Empty if an image of this size is acceptable, else why not.
std::string size_problem(int64_t width, int64_t height) {
  if (width <= 0 || height <= 0 || width * height > kMaxPixels)
    return "invalid image size " + std::to_string(width) + "x" + std::to_string(height);
  return {};
}

void check_size(const std::string& path, int64_t width, int64_t height) {
  if (std::string problem = size_problem(width, height); !problem.empty()) fail(path, problem);
}

// ---------------------------------------------------------------------------------------------
// OpenEXR

// Collects the bytes OpenEXR writes (it seeks back to fill in the line offset table).
class MemoryOStream final : public Imf::OStream {
 public:
  MemoryOStream() : Imf::OStream("memory") {}
  void write(const char c[], int n) override {
    if (pos_ + size_t(n) > bytes_.size()) bytes_.resize(pos_ + size_t(n));
    std::memcpy(bytes_.data() + pos_, c, size_t(n));
    pos_ += size_t(n);
  }
  uint64_t tellp() override { return pos_; }
  void seekp(uint64_t pos) override { pos_ = size_t(pos); }
  std::string& bytes() { return bytes_; }

 private:
  std::string bytes_;
  size_t pos_ = 0;
};

// Throws plain messages; read_exr adds the path to them and to OpenEXR's own exceptions.
Image read_exr_unlabelled(const char* path) {
  Imf::InputFile file(path);
  const Imath::Box2i window = file.header().dataWindow();
  const int64_t width = int64_t(window.max.x) - window.min.x + 1;
  const int64_t height = int64_t(window.max.y) - window.min.y + 1;
  if (std::string problem = size_problem(width, height); !problem.empty())
    throw std::runtime_error(problem);
  const Imf::ChannelList& channels = file.header().channels();
  const bool has_rgb =
      channels.findChannel("R") || channels.findChannel("G") || channels.findChannel("B");
  if (!has_rgb && !channels.findChannel("Y")) throw std::runtime_error("no R, G, B or Y channel");

  Image image{int(width), int(height)};
  // The slices address pixel (x, y) of the data window; OpenEXR converts half to float and
  // fills absent channels with 0.
  char* base = reinterpret_cast<char*>(image.pixels().data()) -
               (int64_t(window.min.x) + int64_t(window.min.y) * width) * int64_t(sizeof(Rgb));
  const size_t xs = sizeof(Rgb), ys = sizeof(Rgb) * size_t(width);
  Imf::FrameBuffer frame;
  if (has_rgb) {
    frame.insert("R", Imf::Slice(Imf::FLOAT, base + offsetof(Rgb, r), xs, ys));
    frame.insert("G", Imf::Slice(Imf::FLOAT, base + offsetof(Rgb, g), xs, ys));
    frame.insert("B", Imf::Slice(Imf::FLOAT, base + offsetof(Rgb, b), xs, ys));
  } else {
    frame.insert("Y", Imf::Slice(Imf::FLOAT, base + offsetof(Rgb, r), xs, ys));
  }
  file.setFrameBuffer(frame);
  file.readPixels(window.min.y, window.max.y);
  if (!has_rgb)
    for (Rgb& p : image.pixels()) p.g = p.b = p.r;
  return image;
}

Image read_exr(const std::string& path) {
  try {
    return read_exr_unlabelled(path.c_str());
  } catch (const std::exception& e) {
    fail(path, e.what());
  }
}

// ---------------------------------------------------------------------------------------------
// PFM (http://www.pauldebevec.com/Research/HDR/PFM/): "PF" colour or "Pf" grey, then width,
// height and a scale whose sign gives the byte order (negative: little endian); rows are stored
// bottom to top.

Image read_pfm(const std::string& path) {
  const std::string bytes = read_whole_file(path);
  size_t pos = 0;
  auto next_token = [&]() {
    while (pos < bytes.size() && std::isspace(static_cast<unsigned char>(bytes[pos]))) ++pos;
    size_t start = pos;
    while (pos < bytes.size() && !std::isspace(static_cast<unsigned char>(bytes[pos]))) ++pos;
    if (start == pos) fail(path, "truncated PFM header");
    if (pos - start > 32) fail(path, "malformed PFM header");
    return bytes.substr(start, pos - start);
  };
  const std::string magic = next_token();
  int channels;
  if (magic == "PF")
    channels = 3;
  else if (magic == "Pf")
    channels = 1;
  else
    fail(path, "not a PFM file (bad magic)");
  int64_t width = 0, height = 0;
  double scale = 0;
  try {
    size_t used = 0;
    std::string w = next_token(), h = next_token(), s = next_token();
    width = std::stoll(w, &used);
    if (used != w.size()) throw std::invalid_argument(w);
    height = std::stoll(h, &used);
    if (used != h.size()) throw std::invalid_argument(h);
    scale = std::stod(s, &used);
    if (used != s.size()) throw std::invalid_argument(s);
  } catch (const std::logic_error&) {  // std::invalid_argument, std::out_of_range
    fail(path, "malformed PFM header");
  }
  check_size(path, width, height);
  if (scale == 0 || !std::isfinite(scale)) fail(path, "invalid PFM scale");
  // Exactly one whitespace character separates the header from the raster.
  if (pos >= bytes.size() || !std::isspace(static_cast<unsigned char>(bytes[pos])))
    fail(path, "truncated PFM header");
  ++pos;
  const size_t count = size_t(width) * size_t(height) * size_t(channels);
  if (bytes.size() - pos < count * sizeof(float))
    fail(path, "truncated PFM data (" + std::to_string(bytes.size() - pos) + " bytes, expected " +
                   std::to_string(count * sizeof(float)) + ")");

  const bool file_little_endian = scale < 0;
  const bool swap = file_little_endian != (std::endian::native == std::endian::little);
  // pbrt-v4 multiplies by |scale| as the format's definition intends.
  const float gain = float(std::abs(scale));
  auto value = [&](size_t index) {
    uint32_t word;
    std::memcpy(&word, bytes.data() + pos + index * sizeof(float), sizeof word);
    if (swap) word = __builtin_bswap32(word);
    float v = std::bit_cast<float>(word);
    return gain == 1.f ? v : v * gain;
  };
  Image image{int(width), int(height)};
  for (int64_t file_row = 0; file_row < height; ++file_row) {
    const int y = int(height - 1 - file_row);
    for (int64_t x = 0; x < width; ++x) {
      const size_t i = (size_t(file_row) * size_t(width) + size_t(x)) * size_t(channels);
      image.at(int(x), y) =
          channels == 3 ? Rgb(value(i), value(i + 1), value(i + 2)) : Rgb(value(i));
    }
  }
  return image;
}

// ---------------------------------------------------------------------------------------------
// stb_image: PNG, JPEG, TGA, BMP (8 or 16 bit per channel) and Radiance HDR (linear float).

struct StbFree {
  void operator()(void* p) const { stbi_image_free(p); }
};

std::string stb_reason() {
  const char* reason = stbi_failure_reason();
  return reason ? reason : "unknown error";
}

Image read_stb(const std::string& path, bool srgb) {
  const std::string bytes = read_whole_file(path);
  if (bytes.size() > size_t(std::numeric_limits<int>::max())) fail(path, "file too large");
  const auto* data = reinterpret_cast<const stbi_uc*>(bytes.data());
  const int len = int(bytes.size());
  int width = 0, height = 0, in_file_channels = 0;
  if (!stbi_info_from_memory(data, len, &width, &height, &in_file_channels))
    fail(path, "cannot decode image: " + stb_reason());
  check_size(path, width, height);

  // Grey and grey+alpha are expanded to RGB by stb; alpha is dropped.
  constexpr int kChannels = 3;
  Image image(width, height);
  auto store = [&](auto* pixels, auto to_linear) {
    if (!pixels) fail(path, "cannot decode image: " + stb_reason());
    for (size_t i = 0; i < image.pixel_count(); ++i)
      image[i] = Rgb(to_linear(pixels[kChannels * i]), to_linear(pixels[kChannels * i + 1]),
                     to_linear(pixels[kChannels * i + 2]));
  };
  int w, h, c;
  if (stbi_is_hdr_from_memory(data, len)) {
    std::unique_ptr<float, StbFree> pixels(
        stbi_loadf_from_memory(data, len, &w, &h, &c, kChannels));
    store(pixels.get(), [](float v) { return v; });
  } else if (stbi_is_16_bit_from_memory(data, len)) {
    std::unique_ptr<stbi_us, StbFree> pixels(
        stbi_load_16_from_memory(data, len, &w, &h, &c, kChannels));
    store(pixels.get(), [srgb](stbi_us v) {
      float x = float(v) / 65535.f;
      return srgb ? srgb_to_linear(x) : x;
    });
  } else {
    float table[256];
    for (int i = 0; i < 256; ++i) table[i] = srgb ? srgb_to_linear(i / 255.f) : i / 255.f;
    std::unique_ptr<stbi_uc, StbFree> pixels(
        stbi_load_from_memory(data, len, &w, &h, &c, kChannels));
    store(pixels.get(), [&table](stbi_uc v) { return table[v]; });
  }
  if (w != width || h != height) fail(path, "inconsistent image size");
  return image;
}

void append_bytes(void* context, void* data, int size) {
  static_cast<std::string*>(context)->append(static_cast<const char*>(data), size_t(size));
}

uint8_t quantize_8bit(float v) {
  if (!(v > 0.f)) return 0;  // Also catches NaN.
  if (v >= 1.f) return 255;
  return uint8_t(v * 255.f + 0.5f);
}

}  // namespace

Image read_image(const std::string& path, bool srgb) {
  const std::string ext = lower_extension(path);
  if (ext == ".exr") return read_exr(path);
  if (ext == ".pfm") return read_pfm(path);
  return read_stb(path, srgb);
}

void write_exr(const Image& image, const std::string& path) {
  if (image.empty()) fail(path, "cannot write an empty image");
  MemoryOStream stream;
  try {
    Imf::Header header(image.width(), image.height());
    header.channels().insert("R", Imf::Channel(Imf::FLOAT));
    header.channels().insert("G", Imf::Channel(Imf::FLOAT));
    header.channels().insert("B", Imf::Channel(Imf::FLOAT));
    header.compression() = Imf::ZIP_COMPRESSION;
    // OpenEXR only reads through the frame buffer; the const_cast does not lead to writes.
    char* base = reinterpret_cast<char*>(const_cast<Rgb*>(image.pixels().data()));
    const size_t xs = sizeof(Rgb), ys = sizeof(Rgb) * size_t(image.width());
    Imf::FrameBuffer frame;
    frame.insert("R", Imf::Slice(Imf::FLOAT, base + offsetof(Rgb, r), xs, ys));
    frame.insert("G", Imf::Slice(Imf::FLOAT, base + offsetof(Rgb, g), xs, ys));
    frame.insert("B", Imf::Slice(Imf::FLOAT, base + offsetof(Rgb, b), xs, ys));
    Imf::OutputFile file(stream, header);
    file.setFrameBuffer(frame);
    file.writePixels(image.height());
  } catch (const std::exception& e) {
    fail(path, std::string("cannot encode EXR: ") + e.what());
  }
  write_file_atomic(path, stream.bytes());
}

void write_pfm(const Image& image, const std::string& path) {
  if (image.empty()) fail(path, "cannot write an empty image");
  // Negative scale: little endian, which we write on every host.
  std::string bytes =
      "PF\n" + std::to_string(image.width()) + " " + std::to_string(image.height()) + "\n-1\n";
  const size_t header = bytes.size();
  bytes.resize(header + image.pixel_count() * 3 * sizeof(float));
  char* out = bytes.data() + header;
  for (int y = image.height() - 1; y >= 0; --y) {  // Bottom row first.
    for (int x = 0; x < image.width(); ++x) {
      for (int c = 0; c < 3; ++c) {
        uint32_t word = std::bit_cast<uint32_t>(image.at(x, y)[c]);
        if constexpr (std::endian::native == std::endian::big) word = __builtin_bswap32(word);
        std::memcpy(out, &word, sizeof word);
        out += sizeof word;
      }
    }
  }
  write_file_atomic(path, bytes);
}

void write_png_srgb(const Image& display_image, const std::string& path) {
  if (display_image.empty()) fail(path, "cannot write an empty image");
  std::vector<uint8_t> rgb8(display_image.pixel_count() * 3);
  for (size_t i = 0; i < display_image.pixel_count(); ++i)
    for (int c = 0; c < 3; ++c) rgb8[3 * i + c] = quantize_8bit(display_image[i][c]);
  std::string bytes;
  if (!stbi_write_png_to_func(append_bytes, &bytes, display_image.width(), display_image.height(),
                              3, rgb8.data(), display_image.width() * 3))
    fail(path, "cannot encode PNG");
  write_file_atomic(path, bytes);
}

void write_file_atomic(const std::string& path, const std::string& contents) {
  // The temporary lives in the target's directory (rename is only atomic within a file
  // system); pid and a counter keep concurrent writers, in or across processes, apart.
  static std::atomic<unsigned> counter{0};
  const std::filesystem::path target(path);
  std::string temp;
  int fd = -1;
  // O_EXCL never reuses a name; a stale temporary left by a killed process with our pid only
  // costs another attempt.
  for (int attempt = 0; attempt < 100; ++attempt) {
    std::string temp_name = ".";
    temp_name += target.filename().string();
    temp_name += ".tmp-" + std::to_string(::getpid()) + "-" + std::to_string(counter++);
    temp = (target.parent_path() / temp_name).string();
    fd = ::open(temp.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_CLOEXEC, 0644);
    if (fd >= 0 || errno != EEXIST) break;
  }
  if (fd < 0) fail(path, std::string("cannot create temporary file: ") + std::strerror(errno));

  auto abandon = [&](const char* what) {
    const int err = errno;
    ::close(fd);
    ::unlink(temp.c_str());
    fail(path, std::string(what) + ": " + std::strerror(err));
  };
  const char* data = contents.data();
  size_t left = contents.size();
  while (left > 0) {
    const ssize_t n = ::write(fd, data, left);
    if (n < 0) {
      if (errno == EINTR) continue;
      abandon("write failed");
    }
    data += n;
    left -= size_t(n);
  }
  // Flush before the rename so a crash cannot leave the new name pointing at missing data.
  if (::fsync(fd) != 0) abandon("fsync failed");
  if (::close(fd) != 0) {
    const int err = errno;
    ::unlink(temp.c_str());
    fail(path, std::string("close failed: ") + std::strerror(err));
  }
  if (::rename(temp.c_str(), path.c_str()) != 0) {
    const int err = errno;
    ::unlink(temp.c_str());
    fail(path, std::string("rename failed: ") + std::strerror(err));
  }
}

}  // namespace caustica
