// Splits pbrt-v4 scene text into tokens, each with its line and column (1-based), so every
// later error can say exactly where it is. Tokens: quoted strings (with \n \t \\ \" escapes),
// "[" and "]", and bare words (directive names, numbers, true/false). "#" starts a comment
// that runs to the end of the line.
#pragma once

#include <memory>
#include <string>

#include "io/load_error.h"

namespace caustica::pbrt {

struct Token {
  enum class Kind { Word, String, OpenBracket, CloseBracket, End };
  Kind kind = Kind::End;
  std::string text;  // strings: the unescaped contents, without quotes
  int line = 0, column = 0;
};

// Short description of a token for error messages: "[" or "\"abc\"" or "end of file".
std::string describe(const Token& token);

class Tokenizer {
 public:
  // `file` is the name used in locations; the tokenizer keeps its own copy of the text.
  Tokenizer(std::string text, std::string file);

  // Next token, or a token of Kind::End at the end. Throws SceneLoadError on an unterminated
  // string or a bad escape.
  Token next();
  // The token that next() will return, without consuming it.
  const Token& peek();

  const std::string& file() const { return file_; }
  SourceLocation location(const Token& t) const { return {file_, t.line, t.column}; }

 private:
  Token scan();
  [[noreturn]] void fail(int line, int column, const std::string& message) const;

  std::string text_;
  std::string file_;
  size_t pos_ = 0;
  int line_ = 1, column_ = 1;
  bool has_peeked_ = false;
  Token peeked_;
};

}  // namespace caustica::pbrt
