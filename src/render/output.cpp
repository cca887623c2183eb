#include "render/output.h"

#include <unistd.h>

#include <cerrno>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <system_error>

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

namespace {

namespace fs = std::filesystem;

std::string quoted(const std::string& name) {
  std::string q(1, '\'');
  q += name;
  q += '\'';
  return q;
}

// "" when `folder` is an existing, writable folder, else why not.
std::string folder_problem(const fs::path& folder) {
  std::error_code ec;
  const fs::file_status st = fs::status(folder, ec);
  // status() reports "not found" (ENOENT, ENOTDIR) through both the type and ec.
  if (st.type() == fs::file_type::not_found)
    return "folder " + quoted(folder.string()) + " does not exist";
  if (ec) return "cannot access folder " + quoted(folder.string()) + " (" + ec.message() + ")";
  if (!fs::is_directory(st)) return quoted(folder.string()) + " is not a folder";
  // access(W_OK) would answer yes to root on a read-only mount; creating a file cannot lie.
  std::string probe = (folder / ".caustica-probe-XXXXXX").string();
  const int fd = ::mkstemp(probe.data());
  if (fd < 0)
    return "folder " + quoted(folder.string()) + " is not writable (" + std::strerror(errno) + ")";
  ::close(fd);
  ::unlink(probe.c_str());
  return "";
}

fs::path folder_of(const std::string& path) {
  const fs::path parent = fs::path(path).parent_path();
  return parent.empty() ? fs::path(".") : parent;
}

}  // namespace

std::string output_problem(const OutputPaths& paths) {
  // The three names share one folder (output_paths_for only swaps the extension).
  if (std::string problem = folder_problem(folder_of(paths.exr)); !problem.empty()) return problem;
  for (const std::string* name : {&paths.exr, &paths.png, &paths.json}) {
    std::error_code ec;
    if (fs::is_directory(*name, ec)) return quoted(*name) + " is a directory";
  }
  return "";
}

std::string output_dir_problem(const std::string& dir) {
  std::error_code ec;
  fs::path p = dir.empty() ? fs::path(".") : fs::path(dir);
  if (fs::exists(p, ec)) {
    if (!fs::is_directory(p, ec)) return quoted(dir) + " exists and is not a folder";
    return folder_problem(p);
  }
  // create_directories will make the missing part; what exists above it must take new entries.
  p = fs::absolute(p, ec);
  while (p.has_parent_path() && p != p.parent_path() && !fs::exists(p, ec)) p = p.parent_path();
  return folder_problem(p);
}

void write_render_outputs(const Image& image, const nlohmann::json& stats, const OutputPaths& paths,
                          float exposure_stops) {
  write_exr(image, paths.exr);
  write_png_srgb(tonemap_srgb(image, exposure_stops), paths.png);
  write_file_atomic(paths.json, stats.dump(2) + "\n");
}

}  // namespace caustica
