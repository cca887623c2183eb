// Errors in scene input, always located: "file:line:col: error: what was expected".
#pragma once

#include <stdexcept>
#include <string>

namespace caustica {

struct SourceLocation {
  std::string file;
  int line = 0, column = 0;
  std::string str() const {
    return line > 0 ? file + ":" + std::to_string(line) + ":" + std::to_string(column) : file;
  }
};

class SceneLoadError : public std::runtime_error {
 public:
  SceneLoadError(const SourceLocation& where, const std::string& message)
      : std::runtime_error(where.str() + ": error: " + message), where_(where), message_(message) {}
  const SourceLocation& where() const { return where_; }
  const std::string& message() const { return message_; }

 private:
  SourceLocation where_;
  std::string message_;
};

// Receives "file:line:col: warning: ..." lines for unsupported-but-valid input. A loader
// reports each distinct construct once.
using WarningSink = void (*)(const std::string& message);

}  // namespace caustica
