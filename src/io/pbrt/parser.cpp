#include "io/pbrt/parser.h"

#include <charconv>
#include <cmath>
#include <filesystem>

namespace caustica::pbrt {

namespace {

// Argument shapes of the directives (pbrt-v4's parser.cpp grammar).
enum class Form {
  Bare,           // AttributeBegin
  Word,           // ActiveTransform StartTime
  Name,           // NamedMaterial "name"
  NameParams,     // Shape "type" params
  Texture,        // Texture "name" "type" "class" params
  Numbers,        // Translate 1 2 3
  Matrix,         // Transform [ 16 numbers ]
  OneOrTwoNames,  // MediumInterface "a" ["b"]
  Params,         // Option "bool x" true
  Include,        // Include "file"
};

struct Grammar {
  const char* name;
  Form form;
  int count = 0;  // numbers for Form::Numbers
};

constexpr Grammar kGrammar[] = {
    {"Accelerator", Form::NameParams},
    {"ActiveTransform", Form::Word},
    {"AreaLightSource", Form::NameParams},
    {"Attribute", Form::NameParams},
    {"AttributeBegin", Form::Bare},
    {"AttributeEnd", Form::Bare},
    {"Camera", Form::NameParams},
    {"ColorSpace", Form::Name},
    {"ConcatTransform", Form::Matrix},
    {"CoordinateSystem", Form::Name},
    {"CoordSysTransform", Form::Name},
    {"Film", Form::NameParams},
    {"Identity", Form::Bare},
    {"Import", Form::Include},
    {"Include", Form::Include},
    {"Integrator", Form::NameParams},
    {"LightSource", Form::NameParams},
    {"LookAt", Form::Numbers, 9},
    {"MakeNamedMaterial", Form::NameParams},
    {"MakeNamedMedium", Form::NameParams},
    {"Material", Form::NameParams},
    {"MediumInterface", Form::OneOrTwoNames},
    {"NamedMaterial", Form::Name},
    {"ObjectBegin", Form::Name},
    {"ObjectEnd", Form::Bare},
    {"ObjectInstance", Form::Name},
    {"Option", Form::Params},
    {"PixelFilter", Form::NameParams},
    {"ReverseOrientation", Form::Bare},
    {"Rotate", Form::Numbers, 4},
    {"Sampler", Form::NameParams},
    {"Scale", Form::Numbers, 3},
    {"Shape", Form::NameParams},
    {"Texture", Form::Texture},
    {"Transform", Form::Matrix},
    {"TransformBegin", Form::Bare},
    {"TransformEnd", Form::Bare},
    {"TransformTimes", Form::Numbers, 2},
    {"Translate", Form::Numbers, 3},
    {"WorldBegin", Form::Bare},
    {"WorldEnd", Form::Bare},  // pbrt-v3; accepted and ignored by the handler
};

const Grammar* find_grammar(const std::string& name) {
  for (const Grammar& g : kGrammar)
    if (name == g.name) return &g;
  return nullptr;
}

float parse_float(Tokenizer& tokens, const Token& t, const Directive& d, int expected) {
  if (t.kind == Token::Kind::Word) {
    const char* first = t.text.data();
    const char* last = first + t.text.size();
    if (first != last && *first == '+') ++first;
    double v = 0;
    const auto [ptr, ec] = std::from_chars(first, last, v);
    if (first != last && ec == std::errc() && ptr == last && std::isfinite(float(v)))
      return float(v);
  }
  throw SceneLoadError(tokens.location(t), d.name + ": expected " + std::to_string(expected) +
                                               " numbers, got " + describe(t));
}

Token expect_string(Tokenizer& tokens, const Directive& d, const char* what) {
  Token t = tokens.next();
  if (t.kind != Token::Kind::String)
    throw SceneLoadError(tokens.location(t),
                         d.name + ": expected " + what + " as a quoted string, got " + describe(t));
  return t;
}

constexpr int kMaxIncludeDepth = 32;

void parse_impl(Tokenizer& tokens, DirectiveHandler& handler, const ParseOptions& options,
                int depth) {
  for (;;) {
    Token t = tokens.next();
    if (t.kind == Token::Kind::End) return;
    if (t.kind != Token::Kind::Word)
      throw SceneLoadError(
          tokens.location(t),
          "expected a directive (such as Shape or AttributeBegin), got " + describe(t));
    const Grammar* g = find_grammar(t.text);
    if (!g) throw SceneLoadError(tokens.location(t), "unknown directive " + describe(t));
    Directive d;
    d.name = t.text;
    d.where = tokens.location(t);
    auto add_arg = [&](const Token& a) {
      d.args.push_back(a.text);
      d.arg_where.push_back(tokens.location(a));
    };
    switch (g->form) {
      case Form::Bare:
        break;
      case Form::Word: {
        Token w = tokens.next();
        if (w.kind != Token::Kind::Word)
          throw SceneLoadError(tokens.location(w),
                               d.name + ": expected StartTime, EndTime or All, got " + describe(w));
        add_arg(w);
        break;
      }
      case Form::Name:
        add_arg(expect_string(tokens, d, "a name"));
        break;
      case Form::NameParams:
        add_arg(expect_string(tokens, d, "a type name"));
        d.params = ParamList::parse(tokens);
        break;
      case Form::Texture:
        add_arg(expect_string(tokens, d, "the texture name"));
        add_arg(expect_string(tokens, d, "the texture type (\"float\" or \"spectrum\")"));
        add_arg(expect_string(tokens, d, "the texture class (such as \"imagemap\")"));
        d.params = ParamList::parse(tokens);
        break;
      case Form::Numbers:
        for (int i = 0; i < g->count; ++i)
          d.numbers.push_back(parse_float(tokens, tokens.next(), d, g->count));
        break;
      case Form::Matrix: {
        const Token open = tokens.next();
        if (open.kind != Token::Kind::OpenBracket)
          throw SceneLoadError(
              tokens.location(open),
              d.name + ": expected \"[\" followed by 16 numbers, got " + describe(open));
        for (int i = 0; i < 16; ++i) {
          const Token v = tokens.next();
          if (v.kind == Token::Kind::CloseBracket)
            throw SceneLoadError(tokens.location(v),
                                 d.name + ": expected 16 numbers, got " + std::to_string(i));
          d.numbers.push_back(parse_float(tokens, v, d, 16));
        }
        const Token close = tokens.next();
        if (close.kind != Token::Kind::CloseBracket)
          throw SceneLoadError(
              tokens.location(close),
              d.name + ": expected \"]\" after 16 numbers, got " + describe(close));
        break;
      }
      case Form::OneOrTwoNames:
        add_arg(expect_string(tokens, d, "a medium name"));
        if (tokens.peek().kind == Token::Kind::String) add_arg(tokens.next());
        break;
      case Form::Params:
        d.params = ParamList::parse(tokens);
        if (d.params.all().size() != 1)
          throw SceneLoadError(
              d.where,
              d.name + ": expected one parameter such as \"bool disablepixeljitter\" true");
        break;
      case Form::Include: {
        const Token file = expect_string(tokens, d, "a file name");
        if (!options.read_file)
          throw SceneLoadError(tokens.location(file),
                               d.name + ": file access is disabled when parsing from memory");
        if (depth + 1 >= kMaxIncludeDepth)
          throw SceneLoadError(tokens.location(file), d.name + ": files nested more than " +
                                                          std::to_string(kMaxIncludeDepth) +
                                                          " deep (does a file include itself?)");
        namespace fs = std::filesystem;
        fs::path path(file.text);
        if (path.is_relative()) path = fs::path(tokens.file()).parent_path() / path;
        const std::string resolved = path.lexically_normal().string();
        std::string text;
        try {
          text = options.read_file(resolved);
        } catch (const SceneLoadError&) {
          throw;
        } catch (const std::runtime_error& e) {
          throw SceneLoadError(
              tokens.location(file),
              d.name + ": cannot read " + quote_excerpt(resolved, kPathExcerpt) + ": " + e.what());
        }
        Tokenizer included(std::move(text), resolved);
        parse_impl(included, handler, options, depth + 1);
        continue;
      }
    }
    handler.directive(d);
  }
}

}  // namespace

void parse_directives(Tokenizer& tokens, DirectiveHandler& handler, const ParseOptions& options) {
  parse_impl(tokens, handler, options, 0);
}

}  // namespace caustica::pbrt
