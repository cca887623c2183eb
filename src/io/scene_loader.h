// One entry point for every scene source: a built-in name, a pbrt-v4 file or a glTF file.
#pragma once

#include <memory>
#include <string>

#include "io/load_error.h"
#include "scene/scene.h"

namespace caustica {

struct LoadOptions {
  WarningSink warn = nullptr;  // nullptr: warnings go to stderr
  int camera_index = -1;       // glTF: which camera (-1: the first)
};

// Throws SceneLoadError for malformed input, std::runtime_error for other failures, and
// UnknownSceneError when `name_or_path` is neither a built-in name nor an existing file.
std::unique_ptr<Scene> load_scene(const std::string& name_or_path, const LoadOptions& options = {});

class UnknownSceneError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

}  // namespace caustica
