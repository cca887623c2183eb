// What every part of the pbrt loader shares: warnings, and how file names in the scene are
// found (or that file access is off, for in-memory parsing).
#pragma once

#include <string>

#include "io/load_error.h"
#include "io/pbrt/warnings.h"

namespace caustica::pbrt {

struct LoaderContext {
  explicit LoaderContext(WarningSink sink) : warnings(sink) {}

  Warnings warnings;
  bool allow_files = true;
  std::string main_directory;  // directory of the top-level scene file
  size_t max_triangles = 0;    // 0: unlimited (a guard for fuzzing)

  // A data file named in a directive at `where`: relative names are looked up next to the
  // file that holds the directive, then (as pbrt-v4 does) next to the main scene file.
  // Throws SceneLoadError at `where` if file access is disabled.
  std::string resolve(const std::string& name, const SourceLocation& where) const;
};

}  // namespace caustica::pbrt
