#include "io/pbrt/context.h"

#include <filesystem>

namespace caustica::pbrt {

std::string LoaderContext::resolve(const std::string& name, const SourceLocation& where) const {
  if (!allow_files)
    throw SceneLoadError(where, "cannot read " + quote_excerpt(name, kPathExcerpt) +
                                    ": file access is disabled when parsing from memory");
  namespace fs = std::filesystem;
  const fs::path path(name);
  if (path.is_absolute()) return name;
  const fs::path local = fs::path(where.file).parent_path() / path;
  std::error_code ec;
  if (fs::exists(local, ec) || main_directory.empty()) return local.lexically_normal().string();
  const fs::path from_main = fs::path(main_directory) / path;
  if (fs::exists(from_main, ec)) return from_main.lexically_normal().string();
  return local.lexically_normal().string();
}

}  // namespace caustica::pbrt
