// The world block (after WorldBegin): materials and textures, lights, shapes and object
// instances. Materials are recorded here and created once the whole file is read (finish()),
// so that NamedMaterial may refer to one defined later, as in pbrt-v4.
#include "io/pbrt/scene_converter.h"
#include "io/pbrt/transforms.h"

namespace caustica::pbrt {

void SceneConverter::material_directive(const Directive& d) {
  anonymous_materials_.push_back({d.args[0], with_attributes(d.params, "material"), d.where});
  anonymous_created_.emplace_back();
  state_.material = {int(anonymous_materials_.size() - 1), {}, d.where};
}

void SceneConverter::make_named_material(const Directive& d) {
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
}

void SceneConverter::named_material_directive(const Directive& d) {
  state_.material = {0, d.args[0], d.arg_where[0]};
}

void SceneConverter::texture(const Directive& d) {
  factory_.define_texture(d.args[0], d.args[1], d.args[2], with_attributes(d.params, "texture"),
                          d.where, d.arg_where[0]);
}

void SceneConverter::light_source(const Directive& d) {
  if (current_object_) {
    ctx_.warnings.warn(d.where, "lights inside ObjectBegin/ObjectEnd are not supported; ignored",
                       "object light");
    return;
  }
  add_light_source(d.args[0], with_attributes(d.params, "light"), d.where, state_.ctm, factory_,
                   builder_, ctx_);
}

void SceneConverter::area_light_source(const Directive& d) {
  state_.area_light = make_area_light(d.args[0], with_attributes(d.params, "light"), d.where, ctx_);
}

void SceneConverter::shape(const Directive& d) {
  ParamList params = with_attributes(d.params, "shape");
  TexturePtr alpha;  // pbrt-v4's alpha mask (scene/scene.h, MeshEntry::alpha)
  if (const Param* ap = params.find("alpha", {ParamType::Float, ParamType::Texture})) {
    if (ap->type == ParamType::Float && ap->numbers.size() == 1 && ap->numbers[0] == 0) {
      params.mark_all_used();
      return;  // fully transparent: pbrt-v4 drops such shapes too
    }
    alpha = factory_.float_texture(params, "alpha", std::nullopt);
    if (alpha->is_constant() && alpha->eval_float({}) >= 1) alpha = nullptr;  // opaque
    if (alpha && state_.area_light)
      ctx_.warnings.warn(ap->where,
                         "an alpha mask on an area light masks the rays that reach it, not what "
                         "it emits",
                         "alpha area light");
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
  r.media = state_.media;
  r.alpha = std::move(alpha);
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
}

void SceneConverter::object_begin(const Directive& d) {
  if (current_object_)
    throw SceneLoadError(
        d.where, "ObjectBegin inside the definition of object " + quote_excerpt(*current_object_));
  if (objects_.count(d.args[0]))
    throw SceneLoadError(d.arg_where[0],
                         "object " + quote_excerpt(d.args[0]) + " is defined twice");
  blocks_.push_back({'o', d.where, state_});
  current_object_ = d.args[0];
  objects_[d.args[0]];
}

void SceneConverter::object_end(const Directive& d) {
  if (!current_object_ || blocks_.empty() || blocks_.back().kind != 'o')
    throw SceneLoadError(d.where, current_object_
                                      ? "ObjectEnd does not match the innermost open block at " +
                                            blocks_.back().where.str()
                                      : "ObjectEnd without a matching ObjectBegin");
  state_ = blocks_.back().saved;
  blocks_.pop_back();
  current_object_.reset();
}

void SceneConverter::object_instance(const Directive& d) {
  if (current_object_)
    throw SceneLoadError(d.where, "ObjectInstance inside the definition of object " +
                                      quote_excerpt(*current_object_));
  auto it = objects_.find(d.args[0]);
  if (it == objects_.end())
    throw SceneLoadError(d.arg_where[0],
                         "ObjectInstance: no object named " + quote_excerpt(d.args[0]));
  const Transform& world_from_instance = state_.ctm;
  const Mat4& m = world_from_instance.matrix();
  const bool affine = m(3, 0) == 0 && m(3, 1) == 0 && m(3, 2) == 0 && m(3, 3) == 1;
  if (affine && !is_invertible(world_from_instance)) {
    ctx_.warnings.warn(d.where, "ObjectInstance with a singular transformation skipped",
                       "singular instance");
    return;
  }
  // Copies are placed in world space as pbrt-v4 composes the transforms: world-from-instance
  // times the shape's transform inside the definition. A projective placement (which Embree
  // instances cannot express) copies every shape.
  bool any_instanced = false;
  for (const ShapeRecord& s : it->second) {
    if (affine && instanced(s)) {
      count_triangles(s.geometry->mesh->triangle_count(), d.where);
      any_instanced = true;
      continue;
    }
    ShapeRecord copy = s;
    copy.object_to_world = state_.ctm * s.object_to_world;
    add_shape_record(std::move(copy));
  }
  if (any_instanced) instances_.push_back({d.args[0], world_from_instance, d.where});
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

}  // namespace caustica::pbrt
