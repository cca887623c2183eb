// The directive table and what is common to all directives: where each is allowed, errors
// located at the directive, and the end of the file (finish).
#include "io/pbrt/scene_converter.h"

#include <algorithm>
#include <stdexcept>

namespace caustica::pbrt {

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

const SceneConverter::DirectiveEntry* SceneConverter::find_directive(std::string_view name) {
  using S = SceneConverter;
  constexpr Scope any = Scope::Anywhere, options = Scope::Options, world = Scope::World;
  // Sorted by name (checked below) for the binary search. Include and Import never arrive:
  // the parser expands them.
  static constexpr DirectiveEntry kTable[] = {
      {"Accelerator", &S::accelerator, options},
      {"ActiveTransform", &S::active_transform, any},
      {"AreaLightSource", &S::area_light_source, world},
      {"Attribute", &S::attribute, any},
      {"AttributeBegin", &S::begin_block, any},
      {"AttributeEnd", &S::end_block, any},
      {"Camera", &S::camera, options},
      {"ColorSpace", &S::color_space, any},
      {"ConcatTransform", &S::transform_matrix, any},
      {"CoordSysTransform", &S::coord_sys_transform, any},
      {"CoordinateSystem", &S::coordinate_system, any},
      {"Film", &S::film, options},
      {"Identity", &S::identity, any},
      {"Integrator", &S::integrator, options},
      {"LightSource", &S::light_source, world},
      {"LookAt", &S::look_at, any},
      {"MakeNamedMaterial", &S::make_named_material, world},
      {"MakeNamedMedium", &S::make_named_medium, any},
      {"Material", &S::material_directive, world},
      {"MediumInterface", &S::medium_interface, any},
      {"NamedMaterial", &S::named_material_directive, world},
      {"ObjectBegin", &S::object_begin, world},
      {"ObjectEnd", &S::object_end, world},
      {"ObjectInstance", &S::object_instance, world},
      {"Option", &S::option, any},
      {"PixelFilter", &S::pixel_filter, options},
      {"ReverseOrientation", &S::reverse_orientation, any},
      {"Rotate", &S::rotate, any},
      {"Sampler", &S::sampler, options},
      {"Scale", &S::scale, any},
      {"Shape", &S::shape, world},
      {"Texture", &S::texture, world},
      {"Transform", &S::transform_matrix, any},
      {"TransformBegin", &S::begin_block, any},
      {"TransformEnd", &S::end_block, any},
      {"TransformTimes", &S::transform_times, any},
      {"Translate", &S::translate, any},
      {"WorldBegin", &S::world_begin, any},
      {"WorldEnd", &S::world_end, any},
  };
  constexpr auto by_name = [](const DirectiveEntry& a, const DirectiveEntry& b) {
    return a.name < b.name;
  };
  static_assert(std::is_sorted(std::begin(kTable), std::end(kTable), by_name));
  const auto it = std::lower_bound(std::begin(kTable), std::end(kTable),
                                   DirectiveEntry{name, nullptr, any}, by_name);
  return it != std::end(kTable) && it->name == name ? it : nullptr;
}

void SceneConverter::directive(const Directive& d) {
  try {
    const DirectiveEntry* entry = find_directive(d.name);
    if (!entry) {  // only a directive the parser knows and this table does not
      require_world(d, true);
      throw SceneLoadError(d.where, "directive " + d.name + " is not handled");
    }
    if (entry->scope != Scope::Anywhere) require_world(d, entry->scope == Scope::World);
    (this->*entry->handle)(d);
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

void SceneConverter::add_shape_record(ShapeRecord record) {
  const ShapeGeometry& g = *record.geometry;
  count_triangles(g.mesh ? g.mesh->triangle_count() : 1, record.where);
  shapes_.push_back(std::move(record));
}

// Instanced triangles count as often as they are placed: the limit bounds rendering work too.
void SceneConverter::count_triangles(size_t n, const SourceLocation& where) {
  triangle_count_ += n;
  if (ctx_.max_triangles > 0 && triangle_count_ > ctx_.max_triangles)
    throw SceneLoadError(where, "the scene has more than " + std::to_string(ctx_.max_triangles) +
                                    " triangles (the limit set for this load)");
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
  emit_instances();
  builder_.set_default_medium(medium_interface_of(camera_media_).outside);
  camera_.camera_to_world = camera_from_world_ ? camera_from_world_->inverse() : Transform();
  builder_.set_camera(camera_);
}

}  // namespace caustica::pbrt
