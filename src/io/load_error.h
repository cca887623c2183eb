// Errors in scene input, always located: "file:line:col: error: what was expected".
#pragma once

#include <stdexcept>
#include <string>
#include <string_view>

namespace caustica {

// Text from a scene file that goes into a message, made safe to print: control bytes (C0, DEL,
// C1) and bytes that are not valid UTF-8 become \xNN, so a hostile file cannot move the cursor
// or recolour the terminal. escape_text keeps every byte; quote_excerpt also wraps the text in
// double quotes (escaping " and \) and cuts it after `max_bytes` input bytes with "...", so one
// megabyte-long token cannot flood the message.
std::string escape_text(std::string_view text);
std::string quote_excerpt(std::string_view text, size_t max_bytes = 40);
// A number from the input as "%g" prints it (1e+39, -0.5), for messages.
std::string format_number(double value);
// File names are quoted longer: cut at 40 bytes, a path no longer says which file it is.
inline constexpr size_t kPathExcerpt = 160;

struct SourceLocation {
  std::string file;
  int line = 0, column = 0;
  // The file name may come from the input (an Include), so it is escaped too.
  std::string str() const {
    const std::string f = escape_text(file);
    return line > 0 ? f + ":" + std::to_string(line) + ":" + std::to_string(column) : f;
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
