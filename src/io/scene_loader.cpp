#include "io/scene_loader.h"

#include <cstdio>
#include <filesystem>

#include "io/builtin_scenes.h"

#if __has_include("io/pbrt/pbrt_loader.h")
#include "io/pbrt/pbrt_loader.h"
#define CAUSTICA_HAS_PBRT 1
#endif
#if __has_include("io/gltf/gltf_loader.h")
#include "io/gltf/gltf_loader.h"
#define CAUSTICA_HAS_GLTF 1
#endif

namespace caustica {

namespace {
void warn_to_stderr(const std::string& message) { std::fprintf(stderr, "%s\n", message.c_str()); }

bool ends_with(const std::string& s, const std::string& suffix) {
  return s.size() >= suffix.size() &&
         s.compare(s.size() - suffix.size(), suffix.size(), suffix) == 0;
}
}  // namespace

std::unique_ptr<Scene> load_scene(const std::string& name_or_path, const LoadOptions& options) {
  if (auto scene = make_builtin_scene(name_or_path)) return scene;
  const WarningSink warn = options.warn ? options.warn : warn_to_stderr;
  const bool looks_like_file =
      name_or_path.find('.') != std::string::npos || name_or_path.find('/') != std::string::npos;
  if (looks_like_file && !std::filesystem::exists(name_or_path))
    throw SceneLoadError(SourceLocation{name_or_path, 0, 0}, "no such file");
  // Checked before the extension: "scenes/" or "x.gltf/" would otherwise be reported as an
  // unsupported format or an empty scene.
  std::error_code ec;
  if (std::filesystem::is_directory(name_or_path, ec))
    throw SceneLoadError(SourceLocation{name_or_path, 0, 0},
                         "is a directory, not a scene file (.pbrt, .gltf or .glb)");
  if (ends_with(name_or_path, ".pbrt")) {
#ifdef CAUSTICA_HAS_PBRT
    return load_pbrt(name_or_path, warn);
#endif
  }
  if (ends_with(name_or_path, ".gltf") || ends_with(name_or_path, ".glb")) {
#ifdef CAUSTICA_HAS_GLTF
    return load_gltf(name_or_path, warn, options.camera_index);
#endif
  }
  if (looks_like_file)
    throw SceneLoadError(SourceLocation{name_or_path, 0, 0},
                         "unsupported scene format (expected .pbrt, .gltf or .glb)");
  std::string names;
  for (const auto& s : builtin_scenes()) names += (names.empty() ? "" : ", ") + s.name;
  throw UnknownSceneError("unknown scene '" + name_or_path + "'; built-in scenes: " + names +
                          "; or give a .pbrt/.gltf/.glb file");
}

}  // namespace caustica
