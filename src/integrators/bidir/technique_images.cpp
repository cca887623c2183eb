#include "integrators/bidir/technique_images.h"

#include <filesystem>

#include "image/image_io.h"

namespace caustica::bidir {

std::vector<std::string> TechniqueImages::write(const std::string& dir, uint32_t iterations) const {
  std::filesystem::create_directories(dir);
  std::vector<std::string> files;
  const float scale = iterations > 0 ? 1.f / float(iterations) : 0.f;
  for (uint32_t k = 0; k < slots_.size(); ++k) {
    if (!slots_[k]) continue;
    Image out = *slots_[k];
    for (Rgb& p : out.pixels()) p *= scale;
    const bool merge = k >= uint32_t(kMaxVertices * kMaxVertices);
    const uint32_t rest = k % (kMaxVertices * kMaxVertices);
    const std::string name = std::string(merge ? "merge_" : "connect_") + "s" +
                             std::to_string(rest / kMaxVertices) + "_t" +
                             std::to_string(rest % kMaxVertices) + ".exr";
    write_exr(out, (std::filesystem::path(dir) / name).string());
    files.push_back(name);
  }
  return files;
}

}  // namespace caustica::bidir
