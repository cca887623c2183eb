// The pbrt-v4 directive grammar: which arguments each directive takes (quoted names,
// numbers, bracketed matrices) followed by a parameter list. The parser checks syntax only
// and hands each directive to a DirectiveHandler, which owns all meaning (graphics state,
// scene objects). Include and Import are expanded here, relative to the including file.
#pragma once

#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "io/pbrt/parameters.h"
#include "io/pbrt/tokenizer.h"

namespace caustica::pbrt {

struct Directive {
  std::string name;               // "Shape", "Translate", ...
  SourceLocation where;           // of the directive's name
  std::vector<std::string> args;  // quoted or bare-word arguments: Shape "sphere" -> {"sphere"}
  std::vector<SourceLocation> arg_where;
  std::vector<float>
      numbers;  // Translate/Scale/Rotate/LookAt/Transform/ConcatTransform/TransformTimes
  ParamList params;
};

class DirectiveHandler {
 public:
  virtual ~DirectiveHandler() = default;
  virtual void directive(const Directive& d) = 0;
};

struct ParseOptions {
  // Returns the contents of an Include/Import file, or throws std::runtime_error saying why
  // it cannot be read (the parser locates the message at the file name). When unset, Include
  // and Import are errors (in-memory parsing, fuzzing).
  std::function<std::string(const std::string& path)> read_file;
};

// Parses the whole token stream. Throws SceneLoadError at the first syntax error.
void parse_directives(Tokenizer& tokens, DirectiveHandler& handler, const ParseOptions& options);

}  // namespace caustica::pbrt
