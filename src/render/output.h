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

// Why writing `paths` would fail, found before a render spends its time: the folder is missing,
// is not a folder or cannot be written (probed by creating and removing a file there, which
// also catches read-only file systems and root-squashed mounts that permission bits do not
// show), or a target name is an existing directory. Empty when writing should succeed.
std::string output_problem(const OutputPaths& paths);

// The same for a folder that will be created if missing (with its parents): the nearest
// existing ancestor must be a writable folder, and `dir` itself a folder if it exists.
std::string output_dir_problem(const std::string& dir);

void write_render_outputs(const Image& image, const nlohmann::json& stats, const OutputPaths& paths,
                          float exposure_stops);

}  // namespace caustica
