#include "io/pbrt/parameters.h"

#include <charconv>
#include <cmath>
#include <limits>

namespace caustica::pbrt {

namespace {

struct TypeInfo {
  const char* name;
  ParamType type;
};
constexpr TypeInfo kTypes[] = {
    {"integer", ParamType::Integer},
    {"float", ParamType::Float},
    {"point2", ParamType::Point2},
    {"vector2", ParamType::Vector2},
    {"point3", ParamType::Point3},
    {"vector3", ParamType::Vector3},
    {"normal3", ParamType::Normal3},
    {"rgb", ParamType::Rgb},
    {"spectrum", ParamType::Spectrum},
    {"blackbody", ParamType::Blackbody},
    {"bool", ParamType::Bool},
    {"string", ParamType::String},
    {"texture", ParamType::Texture},
    // Aliases accepted by pbrt-v4 (and pbrt-v3 files).
    {"point", ParamType::Point3},
    {"vector", ParamType::Vector3},
    {"normal", ParamType::Normal3},
    {"color", ParamType::Rgb},
};

// How many numbers make one element of a numeric type (0: not numeric).
int tuple_size(ParamType t) {
  switch (t) {
    case ParamType::Integer:
    case ParamType::Float:
    case ParamType::Blackbody:
      return 1;
    case ParamType::Point2:
    case ParamType::Vector2:
      return 2;
    case ParamType::Point3:
    case ParamType::Vector3:
    case ParamType::Normal3:
    case ParamType::Rgb:
      return 3;
    default:
      return 0;
  }
}

enum class NumberParse { Ok, NotANumber, OutOfRange };

// Every value ends up as a float (or an int), so a number that is finite as a double but
// not as a float (1e39) would turn into infinity later, far from where it was written.
// "inf" and "nan" parse as doubles and are rejected here too.
NumberParse parse_number(const std::string& text, double* out) {
  const char* first = text.data();
  const char* last = text.data() + text.size();
  if (first != last && *first == '+') ++first;
  if (first == last) return NumberParse::NotANumber;
  const auto [ptr, ec] = std::from_chars(first, last, *out);
  if (ptr != last) return NumberParse::NotANumber;
  if (ec == std::errc::result_out_of_range) return NumberParse::OutOfRange;
  if (ec != std::errc()) return NumberParse::NotANumber;
  if (!std::isfinite(*out) || std::abs(*out) > std::numeric_limits<float>::max())
    return NumberParse::OutOfRange;
  return NumberParse::Ok;
}

}  // namespace

const char* type_name(ParamType type) {
  for (const TypeInfo& t : kTypes)
    if (t.type == type) return t.name;
  return "?";
}

std::optional<ParamType> parse_type_name(std::string_view name) {
  for (const TypeInfo& t : kTypes)
    if (name == t.name) return t.type;
  return std::nullopt;
}

void param_error(const Param& p, const std::string& message) {
  throw SceneLoadError(p.where, p.declaration() + ": " + message);
}

ParamList ParamList::parse(Tokenizer& tokens) {
  ParamList list;
  while (tokens.peek().kind == Token::Kind::String) {
    const Token decl = tokens.next();
    Param p;
    p.where = tokens.location(decl);
    // "type name": exactly two words separated by blanks.
    std::vector<std::string> words;
    std::string word;
    for (char c : decl.text + " ") {
      if (c == ' ' || c == '\t' || c == '\n' || c == '\r') {
        if (!word.empty()) words.push_back(std::move(word));
        word.clear();
      } else {
        word += c;
      }
    }
    if (words.size() != 2)
      throw SceneLoadError(
          p.where, "expected a parameter declaration \"type name\" (such as \"float fov\"), got " +
                       quote_excerpt(decl.text));
    const auto type = parse_type_name(words[0]);
    if (!type)
      throw SceneLoadError(p.where, "unknown parameter type " + quote_excerpt(words[0]) + " in " +
                                        quote_excerpt(decl.text));
    p.type = *type;
    p.name = words[1];
    for (const Param& q : list.params_)
      if (q.name == p.name)
        throw SceneLoadError(p.where, "parameter " + quote_excerpt(p.name) +
                                          " given twice (first at " + q.where.str() + ")");

    // Values: one bare value or a bracketed list.
    std::vector<Token> values;
    const Token first = tokens.next();
    if (first.kind == Token::Kind::OpenBracket) {
      for (;;) {
        Token v = tokens.next();
        if (v.kind == Token::Kind::CloseBracket) break;
        if (v.kind == Token::Kind::End)
          throw SceneLoadError(tokens.location(first),
                               "missing \"]\" to close the \"[\" of " + p.declaration());
        if (v.kind == Token::Kind::OpenBracket)
          throw SceneLoadError(tokens.location(v),
                               p.declaration() + ": unexpected \"[\" inside a value list");
        values.push_back(std::move(v));
      }
    } else if (first.kind == Token::Kind::Word || first.kind == Token::Kind::String) {
      values.push_back(first);
    } else {
      throw SceneLoadError(tokens.location(first),
                           p.declaration() + ": expected a value or \"[\", got " + describe(first));
    }

    const int tuple = tuple_size(p.type);
    auto expect_number = [&](const Token& v) {
      double d = 0;
      const NumberParse r =
          v.kind == Token::Kind::Word ? parse_number(v.text, &d) : NumberParse::NotANumber;
      if (r == NumberParse::NotANumber)
        throw SceneLoadError(tokens.location(v),
                             p.declaration() + ": expected a number, got " + describe(v));
      if (r == NumberParse::OutOfRange)
        throw SceneLoadError(tokens.location(v),
                             p.declaration() + ": " + describe(v) +
                                 " is not a finite number in the range of a 32-bit float");
      return d;
    };
    if (tuple > 0) {
      for (const Token& v : values) {
        const double d = expect_number(v);
        if (p.type == ParamType::Integer &&
            (d != std::floor(d) || d < std::numeric_limits<int>::min() ||
             d > std::numeric_limits<int>::max()))
          throw SceneLoadError(tokens.location(v),
                               p.declaration() + ": expected an integer, got " + describe(v));
        p.numbers.push_back(d);
      }
      if (values.empty() || values.size() % tuple != 0) {
        std::string what = tuple == 1 ? "at least one value"
                                      : "a multiple of " + std::to_string(tuple) + " values";
        if (p.type == ParamType::Rgb || p.type == ParamType::Blackbody)
          what = p.type == ParamType::Rgb ? "exactly 3 values"
                                          : "exactly 1 value (a temperature in kelvin)";
        throw SceneLoadError(p.where, p.declaration() + ": expected " + what + ", got " +
                                          std::to_string(values.size()));
      }
      if ((p.type == ParamType::Rgb && values.size() != 3) ||
          (p.type == ParamType::Blackbody && values.size() != 1))
        throw SceneLoadError(p.where,
                             p.declaration() + ": expected " +
                                 std::string(p.type == ParamType::Rgb
                                                 ? "exactly 3 values"
                                                 : "exactly 1 value (a temperature in kelvin)") +
                                 ", got " + std::to_string(values.size()));
    } else if (p.type == ParamType::Bool) {
      for (const Token& v : values) {
        if (v.text == "true")
          p.bools.push_back(true);
        else if (v.text == "false")
          p.bools.push_back(false);
        else
          throw SceneLoadError(tokens.location(v),
                               p.declaration() + ": expected true or false, got " + describe(v));
      }
      if (p.bools.empty())
        throw SceneLoadError(p.where, p.declaration() + ": expected at least one value, got 0");
    } else if (p.type == ParamType::String || p.type == ParamType::Texture) {
      for (const Token& v : values) {
        if (v.kind != Token::Kind::String)
          throw SceneLoadError(tokens.location(v),
                               p.declaration() + ": expected a quoted string, got " + describe(v));
        p.strings.push_back(v.text);
      }
      if (p.strings.empty())
        throw SceneLoadError(p.where, p.declaration() + ": expected at least one value, got 0");
    } else {  // spectrum: (lambda, value) pairs, or one string (a named spectrum or a file)
      if (!values.empty() && values[0].kind == Token::Kind::String) {
        if (values.size() != 1)
          throw SceneLoadError(
              tokens.location(values[1]),
              p.declaration() + ": expected one spectrum name, got " + describe(values[1]));
        p.strings.push_back(values[0].text);
      } else {
        for (const Token& v : values) p.numbers.push_back(expect_number(v));
        if (p.numbers.size() < 2 || p.numbers.size() % 2 != 0)
          throw SceneLoadError(p.where, p.declaration() +
                                            ": expected (wavelength, value) pairs, got " +
                                            std::to_string(p.numbers.size()) + " numbers");
        for (size_t i = 2; i < p.numbers.size(); i += 2)
          if (p.numbers[i] <= p.numbers[i - 2])
            throw SceneLoadError(p.where, p.declaration() + ": wavelengths must increase");
      }
    }
    list.params_.push_back(std::move(p));
  }
  return list;
}

const Param* ParamList::find(std::string_view name) const {
  for (const Param& p : params_)
    if (p.name == name) {
      p.used = true;
      return &p;
    }
  return nullptr;
}

const Param* ParamList::find(std::string_view name, std::initializer_list<ParamType> types) const {
  const Param* p = find(name);
  if (!p) return nullptr;
  for (ParamType t : types)
    if (p->type == t) return p;
  std::string expected;
  for (ParamType t : types) expected += std::string(expected.empty() ? "" : " or ") + type_name(t);
  param_error(*p, "expected type " + expected);
}

namespace {
const Param* single(const ParamList& list, std::string_view name,
                    std::initializer_list<ParamType> types, size_t count) {
  const Param* p = list.find(name, types);
  if (!p) return nullptr;
  const size_t n = p->numbers.size() + p->strings.size() + p->bools.size();
  if (n != count)
    param_error(*p, "expected one value, got " + std::to_string(n / std::max<size_t>(count, 1)));
  return p;
}
}  // namespace

float ParamList::get_float(std::string_view name, float def) const {
  const Param* p = single(*this, name, {ParamType::Float}, 1);
  return p ? float(p->numbers[0]) : def;
}
int ParamList::get_int(std::string_view name, int def) const {
  const Param* p = single(*this, name, {ParamType::Integer}, 1);
  return p ? int(p->numbers[0]) : def;
}
bool ParamList::get_bool(std::string_view name, bool def) const {
  const Param* p = single(*this, name, {ParamType::Bool}, 1);
  return p ? p->bools[0] : def;
}
std::string ParamList::get_string(std::string_view name, const std::string& def) const {
  const Param* p = single(*this, name, {ParamType::String}, 1);
  return p ? p->strings[0] : def;
}
Vec3 ParamList::get_point3(std::string_view name, Vec3 def) const {
  const Param* p = single(*this, name, {ParamType::Point3}, 3);
  return p ? Vec3(float(p->numbers[0]), float(p->numbers[1]), float(p->numbers[2])) : def;
}
Vec3 ParamList::get_vector3(std::string_view name, Vec3 def) const {
  const Param* p = single(*this, name, {ParamType::Vector3}, 3);
  return p ? Vec3(float(p->numbers[0]), float(p->numbers[1]), float(p->numbers[2])) : def;
}

std::vector<int> ParamList::get_ints(std::string_view name) const {
  std::vector<int> out;
  if (const Param* p = find(name, {ParamType::Integer}))
    for (double d : p->numbers) out.push_back(int(d));
  return out;
}
namespace {
std::vector<Vec3> triples(const Param* p) {
  std::vector<Vec3> out;
  if (p)
    for (size_t i = 0; i + 2 < p->numbers.size(); i += 3)
      out.emplace_back(float(p->numbers[i]), float(p->numbers[i + 1]), float(p->numbers[i + 2]));
  return out;
}
}  // namespace
std::vector<Vec3> ParamList::get_point3s(std::string_view name) const {
  return triples(find(name, {ParamType::Point3}));
}
std::vector<Vec3> ParamList::get_normals(std::string_view name) const {
  return triples(find(name, {ParamType::Normal3}));
}
std::vector<Vec2> ParamList::get_point2s(std::string_view name) const {
  std::vector<Vec2> out;
  if (const Param* p = find(name, {ParamType::Point2}))
    for (size_t i = 0; i + 1 < p->numbers.size(); i += 2)
      out.emplace_back(float(p->numbers[i]), float(p->numbers[i + 1]));
  return out;
}

void ParamList::mark_all_used() const {
  for (const Param& p : params_) p.used = true;
}

void ParamList::report_unused(Warnings& warnings, const std::string& context) const {
  for (const Param& p : params_)
    if (!p.used)
      warnings.warn(
          p.where,
          context + ": parameter " + p.declaration() + " is unknown or not supported; ignored",
          "unused " + context + " " + p.declaration());
}

}  // namespace caustica::pbrt
