#include "render/output.h"

#include <filesystem>

#include "image/image_io.h"
#include "image/tonemap.h"

namespace caustica {

OutputPaths output_paths_for(const std::string& outfile) {
  std::filesystem::path p(outfile);
  const std::string ext = p.extension().string();
  if (ext == ".exr" || ext == ".png" || ext == ".json") p.replace_extension();
  const std::string stem = p.string();
  return {stem + ".exr", stem + ".png", stem + ".json"};
}

void write_render_outputs(const Image& image, const nlohmann::json& stats, const OutputPaths& paths,
                          float exposure_stops) {
  write_exr(image, paths.exr);
  write_png_srgb(tonemap_srgb(image, exposure_stops), paths.png);
  write_file_atomic(paths.json, stats.dump(2) + "\n");
}

}  // namespace caustica
