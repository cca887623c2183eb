#include "io/pbrt/scene_converter.h"

#include <cmath>
#include <limits>
#include <stdexcept>

#include "lights/light_power.h"
#include "materials/materials.h"

namespace caustica::pbrt {

namespace {

// pbrt keeps singular matrices (Scale 0 0 0 hides things); their inverse is NaN.
Transform make_transform(const Mat4& m) {
  Mat4 inv;
  if (m.inverse(&inv)) return Transform(m, inv);
  for (auto& row : inv.m) row.fill(std::numeric_limits<float>::quiet_NaN());
  return Transform(m, inv);
}

bool is_invertible(const Transform& t) {
  for (const auto& row : t.inverse_matrix().m)
    for (float v : row)
      if (!std::isfinite(v)) return false;
  for (const auto& row : t.matrix().m)
    for (float v : row)
      if (!std::isfinite(v)) return false;
  return true;
}

// Uniform scale of a similarity transform (rotation, translation, uniform scale, mirror),
// or nothing if the transform shears, scales non-uniformly or is projective.
std::optional<float> similarity_scale(const Transform& t) {
  const Mat4& m = t.matrix();
  if (m(3, 0) != 0 || m(3, 1) != 0 || m(3, 2) != 0 || m(3, 3) != 1) return std::nullopt;
  Vec3 c[3];
  for (int j = 0; j < 3; ++j) c[j] = Vec3(m(0, j), m(1, j), m(2, j));
  const float s = length(c[0]);
  if (!(s > 0) || !std::isfinite(s)) return std::nullopt;
  const float tol = 1e-4f;
  for (int j = 1; j < 3; ++j)
    if (std::abs(length(c[j]) - s) > tol * s) return std::nullopt;
  if (std::abs(dot(c[0], c[1])) > tol * s * s || std::abs(dot(c[0], c[2])) > tol * s * s ||
      std::abs(dot(c[1], c[2])) > tol * s * s)
    return std::nullopt;
  return s;
}

std::string integrator_name(const std::string& pbrt_name, const SourceLocation& where,
                            LoaderContext& ctx) {
  if (pbrt_name == "path" || pbrt_name == "volpath" || pbrt_name == "simplepath" ||
      pbrt_name == "simplevolpath" || pbrt_name == "randomwalk")
    return "pt";
  if (pbrt_name == "bdpt") return "bpt";
  if (pbrt_name == "lightpath") return "lt";
  if (pbrt_name == "sppm") return "ppm";
  if (pbrt_name == "mlt") {
    ctx.warnings.warn(where, "integrator \"mlt\" is not available; using \"bpt\"");
    return "bpt";
  }
  if (pbrt_name == "ambientocclusion" || pbrt_name == "aov") {
    ctx.warnings.warn(where,
                      "integrator " + quote_excerpt(pbrt_name) + " is not available; using \"pt\"");
    return "pt";
  }
  throw SceneLoadError(where, "unknown integrator " + quote_excerpt(pbrt_name));
}

}  // namespace

SceneConverter::SceneConverter(SceneBuilder& builder, LoaderContext& ctx)
    : builder_(builder), ctx_(ctx), factory_(ctx) {
  // pbrt-v4's default material.
  anonymous_materials_.push_back({"diffuse", ParamList{}, SourceLocation{}});
  anonymous_created_.emplace_back();
  camera_.width = 1280;
  camera_.height = 720;
  camera_.fov_degrees = 90;
  camera_.filter = PixelFilterParams::defaults(PixelFilterKind::Gaussian);  // pbrt-v4's default
}

void SceneConverter::directive(const Directive& d) {
  try {
    handle(d);
  } catch (const SceneLoadError&) {
    throw;
  } catch (const std::exception& e) {
    // Factories and transforms report invalid values with plain exceptions: locate them.
    throw SceneLoadError(d.where, d.name + ": " + e.what());
  }
}

void SceneConverter::require_world(const Directive& d, bool inside) const {
  if (inside && !world_)
    throw SceneLoadError(d.where, d.name + " is only allowed after WorldBegin");
  if (!inside && world_)
    throw SceneLoadError(
        d.where, d.name + " is only allowed before WorldBegin (it sets a rendering option)");
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

void SceneConverter::apply_transform(const Directive& d, const Transform& t, bool concatenate) {
  if (!transforms_active_) return;
  (void)d;
  state_.ctm = concatenate ? state_.ctm * t : t;
}

void SceneConverter::handle(const Directive& d) {
  const std::string& n = d.name;
  const std::vector<float>& v = d.numbers;

  // Transformations.
  if (n == "Identity") return apply_transform(d, Transform(), false);
  if (n == "Translate") return apply_transform(d, Transform::translate({v[0], v[1], v[2]}), true);
  if (n == "Scale") {
    Mat4 m = Mat4::identity();
    m.m[0][0] = v[0];
    m.m[1][1] = v[1];
    m.m[2][2] = v[2];
    return apply_transform(d, make_transform(m), true);
  }
  if (n == "Rotate") {
    const Vec3 axis(v[1], v[2], v[3]);
    if (!(length(axis) > 0) || !std::isfinite(length(axis)))
      throw SceneLoadError(d.where, "Rotate: the rotation axis is zero");
    return apply_transform(d, Transform::rotate(v[0], axis), true);
  }
  if (n == "LookAt") {
    const Vec3 eye(v[0], v[1], v[2]), look(v[3], v[4], v[5]), up(v[6], v[7], v[8]);
    const Vec3 dir = look - eye;
    if (!(length(dir) > 0) || !std::isfinite(length(dir)))
      throw SceneLoadError(d.where, "LookAt: the eye and the look-at point are the same");
    if (!(length(up) > 0) || !(length(cross(normalize(up), normalize(dir))) > 1e-6f))
      throw SceneLoadError(d.where,
                           "LookAt: the up vector is zero or parallel to the viewing direction");
    return apply_transform(d, Transform::look_at(eye, look, up), true);
  }
  if (n == "Transform" || n == "ConcatTransform")
    return apply_transform(d, make_transform(Mat4::from_column_major(v.data())),
                           n == "ConcatTransform");
  if (n == "CoordinateSystem") {
    coordinate_systems_[d.args[0]] = state_.ctm;
    return;
  }
  if (n == "CoordSysTransform") {
    auto it = coordinate_systems_.find(d.args[0]);
    if (it == coordinate_systems_.end())
      ctx_.warnings.warn(d.arg_where[0], "CoordSysTransform: no coordinate system named " +
                                             quote_excerpt(d.args[0]) + "; ignored");
    else if (transforms_active_)
      state_.ctm = it->second;
    return;
  }
  if (n == "ActiveTransform") {
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
    return;
  }
  if (n == "TransformTimes") {
    ctx_.warnings.warn(d.where, "motion blur is not supported: TransformTimes is ignored",
                       "motion blur");
    return;
  }
  if (n == "ReverseOrientation") {
    state_.reverse_orientation = !state_.reverse_orientation;
    return;
  }

  // Blocks.
  if (n == "AttributeBegin" || n == "TransformBegin") {
    blocks_.push_back({n == "AttributeBegin" ? 'a' : 't', d.where, state_});
    return;
  }
  if (n == "AttributeEnd" || n == "TransformEnd") {
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
      state_.ctm = b.saved.ctm;
    blocks_.pop_back();
    return;
  }
  if (n == "Attribute") {
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
    return;
  }

  // Options block.
  if (n == "Camera") {
    require_world(d, false);
    if (!is_invertible(state_.ctm))
      throw SceneLoadError(d.where, "Camera: the current transformation is singular");
    camera_from_world_ = state_.ctm;
    coordinate_systems_["camera"] = state_.ctm.inverse();
    if (d.args[0] != "perspective") {
      ctx_.warnings.warn(d.where, "camera " + quote_excerpt(d.args[0]) +
                                      " is not supported; using \"perspective\"");
      d.params.mark_all_used();
    }
    camera_.fov_degrees = d.params.get_float("fov", 90);
    if (!(camera_.fov_degrees > 0 && camera_.fov_degrees < 180))
      param_error(*d.params.find("fov"), "expected an angle between 0 and 180 degrees");
    camera_.lens_radius = d.params.get_float("lensradius", 0);
    camera_.focal_distance = d.params.get_float("focaldistance", 1e6f);
    if (camera_.lens_radius < 0) param_error(*d.params.find("lensradius"), "must not be negative");
    if (!(camera_.focal_distance > 0))
      param_error(*d.params.find("focaldistance"), "must be positive");
    if (const Param* sw = d.params.find("screenwindow", {ParamType::Float})) {
      if (sw->numbers.size() != 4)
        param_error(*sw, "expected 4 values (xmin xmax ymin ymax), got " +
                             std::to_string(sw->numbers.size()));
      for (int i = 0; i < 4; ++i) camera_.screen_window[i] = float(sw->numbers[i]);
      if (!(camera_.screen_window[0] < camera_.screen_window[1] &&
            camera_.screen_window[2] < camera_.screen_window[3]))
        param_error(*sw, "expected xmin < xmax and ymin < ymax");
    }
    d.params.report_unused(ctx_.warnings, "Camera " + quote_excerpt(d.args[0]));
    return;
  }
  if (n == "Film") {
    require_world(d, false);
    if (d.args[0] != "rgb" && d.args[0] != "gbuffer" && d.args[0] != "spectral")
      throw SceneLoadError(d.arg_where[0], "unknown film " + quote_excerpt(d.args[0]) +
                                               " (expected rgb, gbuffer or spectral)");
    camera_.width = d.params.get_int("xresolution", 1280);
    camera_.height = d.params.get_int("yresolution", 720);
    for (const char* r : {"xresolution", "yresolution"})
      if (const Param* p = d.params.find(r))
        if (!(p->numbers[0] >= 1 && p->numbers[0] <= 65536))
          param_error(*p, "expected a resolution between 1 and 65536");
    if (d.params.find("filename"))
      builder_.settings().output_name = d.params.get_string("filename", "");
    d.params.report_unused(ctx_.warnings, "Film " + quote_excerpt(d.args[0]));
    return;
  }
  if (n == "Sampler") {
    require_world(d, false);
    const int spp = d.params.get_int("pixelsamples", 16);
    if (spp < 1) param_error(*d.params.find("pixelsamples"), "must be at least 1");
    builder_.settings().spp = spp;
    d.params.mark_all_used();  // sampler-specific settings (seed, randomization) do not apply
    return;
  }
  if (n == "Integrator") {
    require_world(d, false);
    builder_.settings().integrator = integrator_name(d.args[0], d.arg_where[0], ctx_);
    const int depth = d.params.get_int("maxdepth", 5);
    if (depth < 0) param_error(*d.params.find("maxdepth"), "must not be negative");
    builder_.settings().max_depth = depth;
    d.params.report_unused(ctx_.warnings, "Integrator " + quote_excerpt(d.args[0]));
    return;
  }
  if (n == "PixelFilter") {
    require_world(d, false);
    const auto kind = pixel_filter_kind(d.args[0]);
    if (!kind)
      throw SceneLoadError(d.arg_where[0], "unknown pixel filter " + quote_excerpt(d.args[0]) +
                                               " (expected " + kPixelFilterNames + ")");
    PixelFilterParams& f = camera_.filter = PixelFilterParams::defaults(*kind);
    f.radius = {d.params.get_float("xradius", f.radius.x),
                d.params.get_float("yradius", f.radius.y)};
    for (const char* r : {"xradius", "yradius"})
      if (const Param* p = d.params.find(r))
        if (!(p->numbers[0] > 0 && p->numbers[0] <= 64))
          param_error(*p, "expected a radius greater than 0 and at most 64 pixels");
    if (*kind == PixelFilterKind::Gaussian) {
      f.sigma = d.params.get_float("sigma", f.sigma);
      if (!(f.sigma > 0)) param_error(*d.params.find("sigma"), "must be positive");
    } else if (*kind == PixelFilterKind::Mitchell) {
      f.b = d.params.get_float("B", f.b);
      f.c = d.params.get_float("C", f.c);
    } else if (*kind == PixelFilterKind::Lanczos) {
      f.tau = d.params.get_float("tau", f.tau);
      if (!(f.tau > 0)) param_error(*d.params.find("tau"), "must be positive");
    }
    d.params.report_unused(ctx_.warnings, "PixelFilter \"" + d.args[0] + "\"");
    return;
  }
  if (n == "Accelerator") {
    require_world(d, false);
    d.params.mark_all_used();  // Embree builds its own BVH
    return;
  }
  if (n == "ColorSpace") {
    if (d.args[0] != "srgb")
      ctx_.warnings.warn(d.where,
                         "ColorSpace " + quote_excerpt(d.args[0]) + " is not supported; using srgb",
                         "colorspace");
    return;
  }
  if (n == "Option") {
    const Param& p = d.params.all()[0];
    ctx_.warnings.warn(p.where, "Option " + p.declaration() + " is not supported; ignored",
                       "option " + p.name);
    return;
  }
  if (n == "WorldBegin") {
    if (world_) throw SceneLoadError(d.where, "WorldBegin appears twice");
    world_ = true;
    state_.ctm = Transform();
    transforms_active_ = true;
    coordinate_systems_["world"] = Transform();
    return;
  }
  if (n == "WorldEnd") {
    ctx_.warnings.warn(d.where, "WorldEnd is a pbrt-v3 directive; ignored");
    return;
  }

  // World block.
  require_world(d, true);
  if (n == "Material") {
    anonymous_materials_.push_back({d.args[0], with_attributes(d.params, "material"), d.where});
    anonymous_created_.emplace_back();
    state_.material = {int(anonymous_materials_.size() - 1), {}, d.where};
    return;
  }
  if (n == "MakeNamedMaterial") {
    const std::string& name = d.args[0];
    if (named_materials_.count(name))
      throw SceneLoadError(d.arg_where[0], "named material " + quote_excerpt(name) +
                                               " is defined twice (first at " +
                                               named_materials_[name].where.str() + ")");
    ParamList params = with_attributes(d.params, "material");
    if (!params.find("type", {ParamType::String}))
      throw SceneLoadError(
          d.where, "MakeNamedMaterial " + quote_excerpt(name) + ": \"string type\" is required");
    named_materials_[name] = {params.get_string("type", ""), std::move(params), d.where};
    return;
  }
  if (n == "NamedMaterial") {
    state_.material = {0, d.args[0], d.arg_where[0]};
    return;
  }
  if (n == "Texture") {
    factory_.define_texture(d.args[0], d.args[1], d.args[2], with_attributes(d.params, "texture"),
                            d.where, d.arg_where[0]);
    return;
  }
  if (n == "LightSource") {
    if (current_object_) {
      ctx_.warnings.warn(d.where, "lights inside ObjectBegin/ObjectEnd are not supported; ignored",
                         "object light");
      return;
    }
    add_light_source(d.args[0], with_attributes(d.params, "light"), d.where, state_.ctm, factory_,
                     builder_, ctx_);
    return;
  }
  if (n == "AreaLightSource") {
    state_.area_light =
        make_area_light(d.args[0], with_attributes(d.params, "light"), d.where, ctx_);
    return;
  }
  if (n == "Shape") {
    ParamList params = with_attributes(d.params, "shape");
    if (const Param* alpha = params.find("alpha", {ParamType::Float, ParamType::Texture})) {
      if (alpha->type == ParamType::Float && alpha->numbers.size() == 1 && alpha->numbers[0] == 0) {
        params.mark_all_used();
        return;  // fully transparent: pbrt-v4 drops such shapes too
      }
      ctx_.warnings.warn(alpha->where, "alpha masks are not supported; shapes are opaque", "alpha");
    }
    for (const char* ignored : {"emissionfilename"}) params.find(ignored);
    std::optional<ShapeGeometry> g = make_shape(d.args[0], params, d.where, ctx_);
    params.report_unused(ctx_.warnings, "Shape " + quote_excerpt(d.args[0]));
    if (!g) return;
    ShapeRecord r;
    r.geometry = std::make_shared<const ShapeGeometry>(std::move(*g));
    r.object_to_world = state_.ctm;
    r.reverse_orientation = state_.reverse_orientation;
    r.material = state_.material;
    r.where = d.where;
    if (state_.area_light) {
      if (current_object_)
        ctx_.warnings.warn(
            d.where,
            "area lights inside ObjectBegin/ObjectEnd are not supported; the shape does not emit",
            "object area light");
      else
        r.emission = state_.area_light;
    }
    if (current_object_)
      objects_[*current_object_].push_back(std::move(r));
    else
      add_shape_record(std::move(r));
    return;
  }
  if (n == "ObjectBegin") {
    if (current_object_)
      throw SceneLoadError(d.where, "ObjectBegin inside the definition of object " +
                                        quote_excerpt(*current_object_));
    if (objects_.count(d.args[0]))
      throw SceneLoadError(d.arg_where[0],
                           "object " + quote_excerpt(d.args[0]) + " is defined twice");
    blocks_.push_back({'o', d.where, state_});
    current_object_ = d.args[0];
    objects_[d.args[0]];
    return;
  }
  if (n == "ObjectEnd") {
    if (!current_object_ || blocks_.empty() || blocks_.back().kind != 'o')
      throw SceneLoadError(d.where, current_object_
                                        ? "ObjectEnd does not match the innermost open block at " +
                                              blocks_.back().where.str()
                                        : "ObjectEnd without a matching ObjectBegin");
    state_ = blocks_.back().saved;
    blocks_.pop_back();
    current_object_.reset();
    return;
  }
  if (n == "ObjectInstance") {
    if (current_object_)
      throw SceneLoadError(d.where, "ObjectInstance inside the definition of object " +
                                        quote_excerpt(*current_object_));
    auto it = objects_.find(d.args[0]);
    if (it == objects_.end())
      throw SceneLoadError(d.arg_where[0],
                           "ObjectInstance: no object named " + quote_excerpt(d.args[0]));
    // Flattened: each shape is copied into world space (world-from-instance times the
    // shape's transform inside the definition), as pbrt-v4 composes them.
    for (const ShapeRecord& s : it->second) {
      ShapeRecord copy = s;
      copy.object_to_world = state_.ctm * s.object_to_world;
      add_shape_record(std::move(copy));
    }
    return;
  }
  if (n == "MakeNamedMedium" || n == "MediumInterface") {
    ctx_.warnings.warn(d.where, "participating media are not supported; " + n + " is ignored",
                       "media " + n);
    d.params.mark_all_used();
    return;
  }
  throw SceneLoadError(d.where, "directive " + n + " is not handled");  // the parser knows no other
}

void SceneConverter::add_shape_record(ShapeRecord record) {
  const ShapeGeometry& g = *record.geometry;
  triangle_count_ += g.mesh ? g.mesh->triangle_count() : 1;
  if (ctx_.max_triangles > 0 && triangle_count_ > ctx_.max_triangles)
    throw SceneLoadError(record.where, "the scene has more than " +
                                           std::to_string(ctx_.max_triangles) +
                                           " triangles (the limit set for this load)");
  shapes_.push_back(std::move(record));
}

MaterialPtr SceneConverter::named_material(const std::string& name, const SourceLocation& where) {
  auto done = named_created_.find(name);
  if (done != named_created_.end()) return done->second;
  auto it = named_materials_.find(name);
  if (it == named_materials_.end())
    throw SceneLoadError(where, "no material named " + quote_excerpt(name));
  for (const std::string& c : creating_)
    if (c == name)
      throw SceneLoadError(
          where, "material " + quote_excerpt(name) + " contains itself (through \"mix\")");
  if (creating_.size() >= 64)
    throw SceneLoadError(where, "materials nested more than 64 deep (through \"mix\")");
  creating_.push_back(name);
  const MaterialDef& def = it->second;
  MaterialPtr m = factory_.make_material(
      def.type, def.params, def.where,
      [this](const std::string& n, const SourceLocation& w) { return named_material(n, w); });
  creating_.pop_back();
  named_created_[name] = m;
  return m;
}

MaterialPtr SceneConverter::material(const MaterialRef& ref) {
  if (!ref.name.empty()) return named_material(ref.name, ref.where);
  std::optional<MaterialPtr>& slot = anonymous_created_[ref.index];
  if (!slot) {
    const MaterialDef& def = anonymous_materials_[ref.index];
    slot = factory_.make_material(
        def.type, def.params, def.where,
        [this](const std::string& n, const SourceLocation& w) { return named_material(n, w); });
  }
  return *slot;
}

namespace {
// "power" spread over a tiny area can overflow; the light's power (and the light selection
// distribution) would then be infinite or NaN at render time.
void check_area_emission(Rgb radiance, const AreaLightDesc& light) {
  if (!radiance.is_finite())
    throw SceneLoadError(light.where,
                         "\"power\" over the area of a shape makes its radiance overflow to "
                         "infinity");
}
}  // namespace

void SceneConverter::emit_shape(const ShapeRecord& r) {
  MaterialPtr m = material(r.material);
  if (!m) return;  // "interface": only bounds media, which are not supported
  const ShapeGeometry& g = *r.geometry;
  const Transform& t = r.object_to_world;
  if (!is_invertible(t)) {
    ctx_.warnings.warn(r.where, "shape with a singular transformation skipped", "singular shape");
    return;
  }
  const bool swaps = t.swaps_handedness();
  std::optional<TriangleMesh> mesh;
  bool quadric = g.quadric;
  if (g.sphere_radius) {
    if (std::optional<float> s = similarity_scale(t)) {
      Sphere sphere;
      sphere.center = t.point({0, 0, 0});
      sphere.radius = *g.sphere_radius * *s;
      // pbrt-v4 flips a quadric's normal when its transform swaps handedness.
      sphere.reverse_orientation = r.reverse_orientation != swaps;
      if (!is_finite(sphere.center) || !std::isfinite(sphere.radius)) {
        ctx_.warnings.warn(r.where, "shape with non-finite coordinates skipped",
                           "non-finite shape");
        return;
      }
      AreaEmission e;
      if (r.emission) {
        e.radiance = r.emission->radiance;
        e.two_sided = r.emission->two_sided;
        if (r.emission->power > 0) {
          const float area = 4 * kPi * sqr(sphere.radius);
          e.radiance = e.radiance * (r.emission->power /
                                     diffuse_area_light_power_per_radiance(area, e.two_sided));
        }
        check_area_emission(e.radiance, *r.emission);
      }
      builder_.add_sphere(sphere, m, r.emission ? &e : nullptr);
      return;
    }
    ctx_.warnings.warn(r.where,
                       "sphere under a non-uniform scale or shear is tessellated into triangles",
                       "tessellated sphere");
    mesh = tessellate_sphere(*g.sphere_radius, -*g.sphere_radius, *g.sphere_radius, 360);
    quadric = true;
  } else {
    mesh = *g.mesh;
  }
  if (mesh->indices.empty()) return;
  mesh->transform(t);
  if (r.reverse_orientation) mesh->flip_orientation();
  if (quadric && swaps) mesh->flip_orientation();
  for (const Vec3& p : mesh->positions)
    if (!is_finite(p)) {
      ctx_.warnings.warn(r.where, "shape with non-finite coordinates skipped", "non-finite shape");
      return;
    }
  if (!r.emission) {
    builder_.add_mesh(std::move(*mesh), m, nullptr);
    return;
  }
  AreaEmission e{r.emission->radiance, r.emission->two_sided};
  if (r.emission->power <= 0) {
    builder_.add_mesh(std::move(*mesh), m, &e);
    return;
  }
  // pbrt-v4 gives "power" to each shape, and each triangle is a shape: one mesh per triangle.
  for (size_t i = 0; i < mesh->triangle_count(); ++i) {
    TriangleMesh tri;
    for (int k = 0; k < 3; ++k) {
      const uint32_t v = mesh->indices[3 * i + k];
      tri.positions.push_back(mesh->positions[v]);
      if (!mesh->normals.empty()) tri.normals.push_back(mesh->normals[v]);
      if (!mesh->uvs.empty()) tri.uvs.push_back(mesh->uvs[v]);
      tri.indices.push_back(uint32_t(k));
    }
    tri.reverse_orientation = mesh->reverse_orientation;
    const float area = tri.area(0);
    AreaEmission ei = e;
    ei.radiance = area > 0 ? e.radiance * (r.emission->power /
                                           diffuse_area_light_power_per_radiance(area, e.two_sided))
                           : Rgb(0.f);
    check_area_emission(ei.radiance, *r.emission);
    builder_.add_mesh(std::move(tri), m, &ei);
  }
}

void SceneConverter::finish() {
  if (!blocks_.empty()) {
    const Block& b = blocks_.back();
    const char* open = b.kind == 'a'   ? "AttributeBegin"
                       : b.kind == 't' ? "TransformBegin"
                                       : "ObjectBegin";
    const char* close = b.kind == 'a'   ? "AttributeEnd"
                        : b.kind == 't' ? "TransformEnd"
                                        : "ObjectEnd";
    throw SceneLoadError(
        b.where, std::string(open) + " has no matching " + close + " before the end of the file");
  }
  // Every named material is created (as pbrt-v4 does), so mistakes in unused ones show.
  for (const auto& [name, def] : named_materials_) named_material(name, def.where);
  for (const ShapeRecord& r : shapes_) {
    try {
      emit_shape(r);
    } catch (const SceneLoadError&) {
      throw;
    } catch (const std::exception& e) {
      throw SceneLoadError(r.where, std::string("Shape: ") + e.what());
    }
  }
  camera_.camera_to_world = camera_from_world_ ? camera_from_world_->inverse() : Transform();
  builder_.set_camera(camera_);
}

}  // namespace caustica::pbrt
