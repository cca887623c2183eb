#include "io/input_file.h"

#include <cerrno>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <stdexcept>

namespace caustica {

std::string read_input_file(const std::string& path) {
  namespace fs = std::filesystem;
  std::error_code ec;
  const fs::file_status status = fs::status(path, ec);
  if (ec || !fs::exists(status))
    throw std::runtime_error(ec ? ec.message() : std::string("No such file or directory"));
  if (fs::is_directory(status)) throw std::runtime_error("is a directory");
  if (!fs::is_regular_file(status)) throw std::runtime_error("is not a regular file");
  std::ifstream in(path, std::ios::binary);
  if (!in) throw std::runtime_error(std::strerror(errno));
  std::string data((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  if (in.bad()) throw std::runtime_error("read error");
  return data;
}

}  // namespace caustica
