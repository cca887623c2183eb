// Entry points of the pbrt-v4 scene loader (src/io/pbrt/). The README lists what is
// supported; unsupported-but-valid input warns once per construct through `warn`, and
// malformed input throws SceneLoadError ("file:line:col: error: what was expected").
#pragma once

#include <memory>
#include <string>

#include "io/load_error.h"
#include "io/scene_builder.h"
#include "scene/scene.h"

namespace caustica {

// Loads a pbrt-v4 scene file and everything it includes (Include/Import, PLY meshes,
// image textures and environment maps, relative to the file that names them).
std::unique_ptr<Scene> load_pbrt(const std::string& path, WarningSink warn);

// Parses pbrt-v4 text held in memory into `builder` without building the scene and without
// touching the file system: Include, plymesh, imagemap and other file references are
// errors. `name` is the file name used in messages. A nonzero `max_triangles` bounds the
// geometry (for fuzzing). Throws SceneLoadError.
void parse_pbrt_string(const std::string& text, const std::string& name, SceneBuilder& builder,
                       WarningSink warn, size_t max_triangles = 0);

// parse_pbrt_string, then build (for tests).
std::unique_ptr<Scene> load_pbrt_string(const std::string& text, WarningSink warn,
                                        const std::string& name = "<string>");

}  // namespace caustica
