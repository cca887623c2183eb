// Helpers for the pbrt loader tests: captured warnings, temporary files, in-memory loads.
#pragma once

#include <gtest/gtest.h>

#include <cstring>
#include <filesystem>
#include <fstream>
#include <initializer_list>
#include <memory>
#include <string>
#include <vector>

#include "io/load_error.h"
#include "io/pbrt/pbrt_loader.h"

namespace caustica::test {

inline std::vector<std::string>& captured_warnings() {
  static std::vector<std::string> w;
  return w;
}
inline void capture_warning(const std::string& message) { captured_warnings().push_back(message); }

inline int count_containing(const std::vector<std::string>& lines, const std::string& needle) {
  int n = 0;
  for (const std::string& l : lines) n += l.find(needle) != std::string::npos;
  return n;
}

// A minimal valid options block, so world-block snippets can be tested on their own.
inline std::string with_camera(const std::string& world) {
  return "Film \"rgb\" \"integer xresolution\" [ 64 ] \"integer yresolution\" [ 64 ]\n"
         "Camera \"perspective\"\nWorldBegin\n" +
         world;
}

inline std::unique_ptr<Scene> load_text(const std::string& text) {
  captured_warnings().clear();
  return load_pbrt_string(text, capture_warning, "test.pbrt");
}

// The "file:line:col: error: message" of loading `text`, or "" if it loads.
inline std::string load_error(const std::string& text) {
  try {
    load_text(text);
  } catch (const SceneLoadError& e) {
    return e.what();
  }
  return "";
}

// A fresh directory under the system temp dir, removed at destruction.
class TempDir {
 public:
  TempDir() {
    path_ = std::filesystem::temp_directory_path() /
            ("caustica_pbrt_" + std::to_string(::testing::UnitTest::GetInstance()->random_seed()) +
             "_" + std::to_string(counter()++) + "_" +
             std::to_string(reinterpret_cast<uintptr_t>(this)));
    std::filesystem::create_directories(path_);
  }
  ~TempDir() {
    std::error_code ec;
    std::filesystem::remove_all(path_, ec);
  }
  std::string file(const std::string& name) const { return (path_ / name).string(); }
  std::string write(const std::string& name, const std::string& contents) const {
    std::filesystem::create_directories((path_ / name).parent_path());
    std::ofstream(path_ / name, std::ios::binary) << contents;
    return file(name);
  }

 private:
  static int& counter() {
    static int c = 0;
    return c;
  }
  std::filesystem::path path_;
};

// Writes a single-row, single-channel PFM of these values (little-endian) into dir; its path.
inline std::string write_row_pfm(const TempDir& dir, const std::string& name,
                                 std::initializer_list<float> values) {
  std::string bytes = "Pf\n" + std::to_string(values.size()) + " 1\n-1.0\n";
  for (float v : values) {
    char b[4];
    std::memcpy(b, &v, 4);
    bytes.append(b, 4);
  }
  return dir.write(name, bytes);
}

// Loads `text` as the file `name` in dir (so it can refer to files there); warnings captured.
inline std::unique_ptr<Scene> load_file_text(const TempDir& dir, const std::string& name,
                                             const std::string& text) {
  captured_warnings().clear();
  return load_pbrt(dir.write(name, text), capture_warning);
}

}  // namespace caustica::test
