#include "io/pbrt/tokenizer.h"

namespace caustica::pbrt {

std::string describe(const Token& token) {
  switch (token.kind) {
    case Token::Kind::End:
      return "end of file";
    case Token::Kind::OpenBracket:
      return "\"[\"";
    case Token::Kind::CloseBracket:
      return "\"]\"";
    case Token::Kind::String:
      return "string " + quote_excerpt(token.text);
    case Token::Kind::Word:
      break;
  }
  return quote_excerpt(token.text);
}

Tokenizer::Tokenizer(std::string text, std::string file)
    : text_(std::move(text)), file_(std::move(file)) {}

void Tokenizer::fail(int line, int column, const std::string& message) const {
  throw SceneLoadError({file_, line, column}, message);
}

const Token& Tokenizer::peek() {
  if (!has_peeked_) {
    peeked_ = scan();
    has_peeked_ = true;
  }
  return peeked_;
}

Token Tokenizer::next() {
  if (has_peeked_) {
    has_peeked_ = false;
    return std::move(peeked_);
  }
  return scan();
}

namespace {
bool is_space(char c) {
  return c == ' ' || c == '\t' || c == '\n' || c == '\r' || c == '\f' || c == '\v';
}
}  // namespace

Token Tokenizer::scan() {
  auto advance = [&]() {
    if (text_[pos_] == '\n') {
      ++line_;
      column_ = 1;
    } else {
      ++column_;
    }
    ++pos_;
  };
  for (;;) {
    while (pos_ < text_.size() && is_space(text_[pos_])) advance();
    if (pos_ < text_.size() && text_[pos_] == '#') {
      while (pos_ < text_.size() && text_[pos_] != '\n') advance();
      continue;
    }
    break;
  }
  Token t;
  t.line = line_;
  t.column = column_;
  if (pos_ >= text_.size()) return t;
  const char c = text_[pos_];
  if (c == '[' || c == ']') {
    t.kind = c == '[' ? Token::Kind::OpenBracket : Token::Kind::CloseBracket;
    t.text = std::string(1, c);
    advance();
    return t;
  }
  if (c == '"') {
    t.kind = Token::Kind::String;
    advance();
    for (;;) {
      if (pos_ >= text_.size() || text_[pos_] == '\n')
        fail(t.line, t.column,
             "unterminated string: missing closing '\"' before the end of the line");
      const char s = text_[pos_];
      if (s == '"') {
        advance();
        break;
      }
      if (s == '\\') {
        const int el = line_, ec = column_;
        advance();
        if (pos_ >= text_.size()) fail(el, ec, "unterminated string: missing closing '\"'");
        const char e = text_[pos_];
        switch (e) {
          case 'b':
            t.text += '\b';
            break;
          case 'f':
            t.text += '\f';
            break;
          case 'n':
            t.text += '\n';
            break;
          case 'r':
            t.text += '\r';
            break;
          case 't':
            t.text += '\t';
            break;
          case '\\':
            t.text += '\\';
            break;
          case '\'':
            t.text += '\'';
            break;
          case '"':
            t.text += '"';
            break;
          default:
            fail(el, ec,
                 std::string("unknown escape sequence '\\") +
                     (e == '\n' ? std::string("newline") : escape_text(std::string(1, e))) +
                     "' in string");
        }
        advance();
        continue;
      }
      t.text += s;
      advance();
    }
    return t;
  }
  t.kind = Token::Kind::Word;
  const size_t start = pos_;
  while (pos_ < text_.size() && !is_space(text_[pos_]) && text_[pos_] != '"' &&
         text_[pos_] != '[' && text_[pos_] != ']' && text_[pos_] != '#')
    advance();
  t.text = text_.substr(start, pos_ - start);
  return t;
}

}  // namespace caustica::pbrt
