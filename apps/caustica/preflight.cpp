#include "preflight.h"

#include <sys/resource.h>
#include <unistd.h>

#include <algorithm>
#include <cstdio>
#include <exception>
#include <filesystem>

#include "image/image_io.h"
#include "io/builtin_scenes.h"
#include "options.h"

namespace caustica::cli {

namespace {

namespace fs = std::filesystem;

std::string gib(double bytes) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.1f GiB", bytes / double(uint64_t(1) << 30));
  return buf;
}

bool is_builtin(const std::string& name) {
  for (const auto& s : builtin_scenes())
    if (s.name == name) return true;
  return false;
}

// "" when `path` is missing or a regular file (following links), else what it is instead.
std::string not_a_regular_file(const std::string& path) {
  std::error_code ec;
  const fs::file_status st = fs::status(path, ec);
  if (st.type() == fs::file_type::not_found || fs::is_regular_file(st)) return "";
  if (fs::is_directory(st)) return "is a directory";
  if (ec) return "cannot be accessed (" + ec.message() + ")";
  return "is not a regular file";
}

}  // namespace

uint64_t memory_cap_bytes() {
  const long pages = ::sysconf(_SC_PHYS_PAGES), page_size = ::sysconf(_SC_PAGE_SIZE);
  uint64_t cap = pages > 0 && page_size > 0 ? uint64_t(pages) * uint64_t(page_size) : 0;
  struct rlimit limit {};
  if (::getrlimit(RLIMIT_AS, &limit) == 0 && limit.rlim_cur != RLIM_INFINITY)
    cap = cap == 0 ? uint64_t(limit.rlim_cur) : std::min(cap, uint64_t(limit.rlim_cur));
  return cap;
}

std::string film_memory_problem(int width, int height, uint64_t light_paths) {
  const uint64_t pixels = uint64_t(width) * uint64_t(height);  // each side < 2^31: no overflow
  const uint64_t paths = light_paths > 0 ? light_paths : pixels;
  // In double: with 2^64 light paths the byte count overflows an integer; the precision lost
  // does not matter against a cap of whole GiB.
  const double need =
      double(pixels) * double(kFilmBytesPerPixel) + double(paths) * double(kBytesPerLightPath);
  const uint64_t cap = memory_cap_bytes();
  const std::string film = "a " + std::to_string(width) + "x" + std::to_string(height) + " film";
  if (cap > 0 && need > double(cap))
    return film +
           (light_paths > 0 ? " with " + std::to_string(paths) + " light paths"
                            : " (one light path per pixel)") +
           " needs at least " + gib(need) + " of memory, more than the " + gib(double(cap)) +
           " available (physical memory or ulimit -v); lower --resolution or --light-paths";
  if (pixels > kMaxPixels)
    return film + " has " + std::to_string(pixels) + " pixels, more than the " +
           std::to_string(kMaxPixels) + " that 32-bit pixel indices reach; lower --resolution";
  return "";
}

std::string scene_path_problem(const std::string& scene) {
  if (is_builtin(scene))
    return "";  // a folder that happens to share a built-in's name is not meant
  if (std::string what = not_a_regular_file(scene); !what.empty())
    return "scene " + excerpt(scene) + " " + what +
           "; give a .pbrt, .gltf or .glb file or a built-in scene name";
  return "";
}

std::string reference_problem(const std::string& path, Image* image) {
  std::error_code ec;
  if (!fs::exists(path, ec)) return "--reference " + excerpt(path) + " does not exist";
  if (std::string what = not_a_regular_file(path); !what.empty())
    return "--reference " + excerpt(path) + " " + what;
  try {
    *image = read_image(path, false);
  } catch (const std::exception& e) {
    return "--reference " + excerpt(path) + " is not a readable image: " + e.what();
  }
  if (image->empty()) return "--reference " + excerpt(path) + " is an empty image";
  return "";
}

}  // namespace caustica::cli
