// The graphics-state directives: transformations, named coordinate systems, the
// AttributeBegin/End and TransformBegin/End stack, ReverseOrientation and Attribute defaults.
#include <cmath>

#include "io/pbrt/scene_converter.h"
#include "io/pbrt/transforms.h"

namespace caustica::pbrt {

void SceneConverter::apply_transform(const Transform& t, bool concatenate) {
  if (!transforms_active_) return;
  state_.ctm = concatenate ? state_.ctm * t : t;
}

void SceneConverter::identity(const Directive&) { apply_transform(Transform(), false); }

void SceneConverter::translate(const Directive& d) {
  const std::vector<float>& v = d.numbers;
  apply_transform(Transform::translate({v[0], v[1], v[2]}), true);
}

void SceneConverter::scale(const Directive& d) {
  Mat4 m = Mat4::identity();
  m.m[0][0] = d.numbers[0];
  m.m[1][1] = d.numbers[1];
  m.m[2][2] = d.numbers[2];
  apply_transform(make_transform(m), true);
}

void SceneConverter::rotate(const Directive& d) {
  const std::vector<float>& v = d.numbers;
  const Vec3 axis(v[1], v[2], v[3]);
  if (!(length(axis) > 0) || !std::isfinite(length(axis)))
    throw SceneLoadError(d.where, "Rotate: the rotation axis is zero");
  apply_transform(Transform::rotate(v[0], axis), true);
}

void SceneConverter::look_at(const Directive& d) {
  const std::vector<float>& v = d.numbers;
  const Vec3 eye(v[0], v[1], v[2]), look(v[3], v[4], v[5]), up(v[6], v[7], v[8]);
  const Vec3 dir = look - eye;
  if (!(length(dir) > 0) || !std::isfinite(length(dir)))
    throw SceneLoadError(d.where, "LookAt: the eye and the look-at point are the same");
  if (!(length(up) > 0) || !(length(cross(normalize(up), normalize(dir))) > 1e-6f))
    throw SceneLoadError(d.where,
                         "LookAt: the up vector is zero or parallel to the viewing direction");
  apply_transform(Transform::look_at(eye, look, up), true);
}

void SceneConverter::transform_matrix(const Directive& d) {
  apply_transform(make_transform(Mat4::from_column_major(d.numbers.data())),
                  d.name == "ConcatTransform");
}

void SceneConverter::coordinate_system(const Directive& d) {
  coordinate_systems_[d.args[0]] = state_.ctm;
}

void SceneConverter::coord_sys_transform(const Directive& d) {
  auto it = coordinate_systems_.find(d.args[0]);
  if (it == coordinate_systems_.end())
    ctx_.warnings.warn(d.arg_where[0], "CoordSysTransform: no coordinate system named " +
                                           quote_excerpt(d.args[0]) + "; ignored");
  else if (transforms_active_)
    state_.ctm = it->second;
}

void SceneConverter::active_transform(const Directive& d) {
  const std::string& which = d.args[0];
  if (which == "StartTime" || which == "All") {
    transforms_active_ = true;
  } else if (which == "EndTime") {
    transforms_active_ = false;
    ctx_.warnings.warn(d.where,
                       "motion blur is not supported: transformations for EndTime are ignored",
                       "motion blur");
  } else {
    throw SceneLoadError(
        d.arg_where[0],
        "ActiveTransform: expected StartTime, EndTime or All, got " + quote_excerpt(which));
  }
}

void SceneConverter::transform_times(const Directive& d) {
  ctx_.warnings.warn(d.where, "motion blur is not supported: TransformTimes is ignored",
                     "motion blur");
}

void SceneConverter::reverse_orientation(const Directive&) {
  state_.reverse_orientation = !state_.reverse_orientation;
}

void SceneConverter::begin_block(const Directive& d) {
  blocks_.push_back({d.name == "AttributeBegin" ? 'a' : 't', d.where, state_});
}

void SceneConverter::end_block(const Directive& d) {
  const std::string& n = d.name;
  const char kind = n == "AttributeEnd" ? 'a' : 't';
  const char* open = kind == 'a' ? "AttributeBegin" : "TransformBegin";
  if (blocks_.empty()) throw SceneLoadError(d.where, n + " without a matching " + open);
  const Block& b = blocks_.back();
  if (b.kind != kind) {
    const char* other = b.kind == 'a'   ? "AttributeBegin"
                        : b.kind == 't' ? "TransformBegin"
                                        : "ObjectBegin";
    throw SceneLoadError(d.where, n + " does not match the " + other + " at " + b.where.str());
  }
  if (kind == 'a')
    state_ = b.saved;
  else
    state_.ctm = b.saved.ctm;  // TransformEnd restores only the transformation
  blocks_.pop_back();
}

// Attribute "shape" ... sets defaults that later directives of that kind read where they do
// not give the parameter themselves (with_attributes); a new value replaces an older one.
void SceneConverter::attribute(const Directive& d) {
  const std::string& target = d.args[0];
  if (target != "shape" && target != "light" && target != "material" && target != "medium" &&
      target != "texture")
    throw SceneLoadError(d.arg_where[0],
                         "Attribute: expected \"shape\", \"light\", \"material\", \"medium\" or "
                         "\"texture\", got " +
                             quote_excerpt(target));
  ParamList& list = state_.attributes[target];
  ParamList updated;
  for (const Param& p : d.params.all()) updated.add(p);
  for (const Param& p : list.all()) {
    bool replaced = false;
    for (const Param& q : d.params.all()) replaced |= q.name == p.name;
    if (!replaced) updated.add(p);
  }
  list = std::move(updated);
}

ParamList SceneConverter::with_attributes(const ParamList& params,
                                          const std::string& target) const {
  auto it = state_.attributes.find(target);
  if (it == state_.attributes.end()) return params;
  ParamList merged = params;
  for (const Param& p : it->second.all()) {
    bool present = false;
    for (const Param& q : params.all()) present |= q.name == p.name;
    if (!present) {
      Param copy = p;
      copy.used = false;
      merged.add(std::move(copy));
    }
  }
  return merged;
}

}  // namespace caustica::pbrt
