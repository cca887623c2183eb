// Writes a finished render: linear EXR (the truth), tone-mapped sRGB PNG, JSON statistics.
// Each file goes through a temporary file and a rename.
#pragma once

#include <nlohmann/json.hpp>
#include <string>

#include "image/image.h"

namespace caustica {

struct OutputPaths {
  std::string exr, png, json;
};

// From `--outfile`: "out.exr", "out.png" or "out" all give out.exr, out.png and out.json.
OutputPaths output_paths_for(const std::string& outfile);

void write_render_outputs(const Image& image, const nlohmann::json& stats, const OutputPaths& paths,
                          float exposure_stops);

}  // namespace caustica
