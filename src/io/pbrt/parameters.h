// pbrt-v4's typed parameter lists: `"float fov" [ 45 ]`, `"rgb L" [ 1 2 3 ]`,
// `"spectrum eta" "metal-Cu-eta"`, `"texture reflectance" "checks"`, `"bool twosided" true`.
// Values are type-checked and counted when parsed (so errors point at the offending value);
// lookups mark parameters as used, and report_unused() warns once about the rest.
#pragma once

#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "core/vec.h"
#include "io/load_error.h"
#include "io/pbrt/tokenizer.h"
#include "io/pbrt/warnings.h"

namespace caustica::pbrt {

// The pbrt-v4 parameter types. Aliases are folded when parsed: point -> point3,
// vector -> vector3, normal -> normal3, color -> rgb.
enum class ParamType {
  Integer,
  Float,
  Point2,
  Vector2,
  Point3,
  Vector3,
  Normal3,
  Rgb,
  Spectrum,
  Blackbody,
  Bool,
  String,
  Texture
};

const char* type_name(ParamType type);
std::optional<ParamType> parse_type_name(std::string_view name);

struct Param {
  ParamType type = ParamType::Float;
  std::string name;
  SourceLocation where;         // of the "type name" string
  std::vector<double> numbers;  // integer, float, point*, vector*, normal, rgb, blackbody, spectrum
                                // (lambda, value pairs)
  std::vector<std::string> strings;  // string, texture, spectrum (a named spectrum or file)
  std::vector<bool> bools;
  mutable bool used = false;

  std::string declaration() const {
    return quote_excerpt(std::string(type_name(type)) + " " + name);
  }
};

class ParamList {
 public:
  // Parses `"type name" value-or-[values]` pairs until the next token is not a string.
  static ParamList parse(Tokenizer& tokens);

  void add(Param p) { params_.push_back(std::move(p)); }
  const std::vector<Param>& all() const { return params_; }
  bool empty() const { return params_.empty(); }

  // The parameter called `name`, whatever its type (marks it used), or null.
  const Param* find(std::string_view name) const;
  // Like find(), but the type must be one of `types`; otherwise throws a SceneLoadError at
  // the parameter ("\"integer fov\": expected type float").
  const Param* find(std::string_view name, std::initializer_list<ParamType> types) const;

  // Single values with defaults. A present parameter must have exactly one value.
  float get_float(std::string_view name, float def) const;
  int get_int(std::string_view name, int def) const;
  bool get_bool(std::string_view name, bool def) const;
  std::string get_string(std::string_view name, const std::string& def) const;
  Vec3 get_point3(std::string_view name, Vec3 def) const;
  Vec3 get_vector3(std::string_view name, Vec3 def) const;

  // Arrays (empty if absent).
  std::vector<int> get_ints(std::string_view name) const;
  std::vector<Vec3> get_point3s(std::string_view name) const;
  std::vector<Vec3> get_normals(std::string_view name) const;
  std::vector<Vec2> get_point2s(std::string_view name) const;

  // Marks every parameter used: for a construct that is skipped or ignored as a whole, which
  // warns once itself rather than once per parameter.
  void mark_all_used() const;
  // Warns once per unused parameter name and `context` (for example "Shape \"sphere\"").
  void report_unused(Warnings& warnings, const std::string& context) const;

 private:
  std::vector<Param> params_;
};

// Throws SceneLoadError at p: "<declaration>: <message>".
[[noreturn]] void param_error(const Param& p, const std::string& message);

}  // namespace caustica::pbrt
