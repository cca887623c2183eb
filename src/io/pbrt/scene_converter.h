// Gives meaning to pbrt-v4 directives: the graphics state (current transformation, its
// AttributeBegin/End and TransformBegin/End stack, ReverseOrientation, current material and
// area light, named coordinate systems, Attribute defaults), the options block (Camera,
// Film, Sampler, Integrator) and the world (shapes, materials, textures, lights, objects).
//
// Materials are created after the whole file is read, as in pbrt-v4, so NamedMaterial may
// refer to a material defined later. An object (ObjectBegin/End) is stored once: its triangle
// meshes become a prototype that each ObjectInstance places as an Embree instance; its spheres
// and tessellated quadrics, whose exactness and orientation depend on the whole transform,
// are copied into world space per instance.
//
// Each directive has one handler; a table (scene_converter.cpp) maps directive names to them and
// says where each is allowed. The handlers live by meaning in scene_converter_state.cpp
// (transformations, blocks, attributes), _options.cpp (Camera, Film, Sampler, ...), _world.cpp
// (materials, textures, lights, shapes, objects); _shapes.cpp hands the shapes to the builder,
// _instances.cpp the objects' prototypes and instances.
#pragma once

#include <map>
#include <memory>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "io/pbrt/context.h"
#include "io/pbrt/light_factory.h"
#include "io/pbrt/material_factory.h"
#include "io/pbrt/parser.h"
#include "io/pbrt/shape_factory.h"
#include "io/scene_builder.h"

namespace caustica::pbrt {

class SceneConverter final : public DirectiveHandler {
 public:
  SceneConverter(SceneBuilder& builder, LoaderContext& ctx);
  void directive(const Directive& d) override;
  // After the last directive: checks that blocks are closed, creates materials, hands the
  // shapes and the camera to the builder. Throws SceneLoadError.
  void finish();

 private:
  struct MaterialRef {
    int index = 0;     // into anonymous_materials_, when name is empty
    std::string name;  // a NamedMaterial
    SourceLocation where;
  };
  struct MaterialDef {
    std::string type;
    ParamList params;
    SourceLocation where;
  };
  // MediumInterface's names ("" is no medium), resolved once the whole file is read, since
  // pbrt-v4 lets a medium be named before MakeNamedMedium defines it.
  struct MediumNames {
    std::string inside, outside;
    SourceLocation where;
  };
  struct GraphicsState {
    Transform ctm;
    MediumNames media;
    bool reverse_orientation = false;
    MaterialRef material;
    std::optional<AreaLightDesc> area_light;
    std::map<std::string, ParamList> attributes;  // Attribute "shape"/"light"/... defaults
  };
  struct Block {
    char kind;  // 'a' AttributeBegin, 't' TransformBegin, 'o' ObjectBegin
    SourceLocation where;
    GraphicsState saved;
  };
  struct ShapeRecord {
    std::shared_ptr<const ShapeGeometry> geometry;  // object space
    Transform object_to_world;
    bool reverse_orientation = false;
    MaterialRef material;
    std::optional<AreaLightDesc> emission;
    SourceLocation where;
    MediumNames media;
    TexturePtr alpha;  // pbrt-v4's alpha mask; null: opaque
  };
  struct InstanceRecord {  // one ObjectInstance of an object's triangle meshes
    std::string object;
    Transform object_to_world;
    SourceLocation where;
  };

  using Handler = void (SceneConverter::*)(const Directive&);
  enum class Scope { Anywhere, Options, World };  // Options: before WorldBegin; World: after
  struct DirectiveEntry {
    std::string_view name;
    Handler handle;
    Scope scope;
  };
  static const DirectiveEntry* find_directive(std::string_view name);

  // Graphics state (scene_converter_state.cpp).
  void identity(const Directive& d);
  void translate(const Directive& d);
  void scale(const Directive& d);
  void rotate(const Directive& d);
  void look_at(const Directive& d);
  void transform_matrix(const Directive& d);  // Transform and ConcatTransform
  void coordinate_system(const Directive& d);
  void coord_sys_transform(const Directive& d);
  void active_transform(const Directive& d);
  void transform_times(const Directive& d);
  void reverse_orientation(const Directive& d);
  void begin_block(const Directive& d);  // AttributeBegin and TransformBegin
  void end_block(const Directive& d);    // AttributeEnd and TransformEnd
  void attribute(const Directive& d);
  void apply_transform(const Transform& t, bool concatenate);

  // Options block (scene_converter_options.cpp).
  void camera(const Directive& d);
  void film(const Directive& d);
  void sampler(const Directive& d);
  void integrator(const Directive& d);
  void pixel_filter(const Directive& d);
  void accelerator(const Directive& d);
  void color_space(const Directive& d);
  void option(const Directive& d);
  void world_begin(const Directive& d);
  void world_end(const Directive& d);

  // World block (scene_converter_world.cpp).
  void material_directive(const Directive& d);
  void make_named_material(const Directive& d);
  void named_material_directive(const Directive& d);
  void texture(const Directive& d);
  void light_source(const Directive& d);
  void area_light_source(const Directive& d);
  void shape(const Directive& d);
  void object_begin(const Directive& d);
  void object_end(const Directive& d);
  void object_instance(const Directive& d);

  // Media (scene_converter_media.cpp).
  void make_named_medium(const Directive& d);
  void medium_interface(const Directive& d);
  int16_t medium_index(const std::string& name, const SourceLocation& where) const;
  MediumInterface medium_interface_of(const MediumNames& names) const;
  MaterialPtr material(const MaterialRef& ref);
  MaterialPtr named_material(const std::string& name, const SourceLocation& where);

  void require_world(const Directive& d, bool inside) const;
  ParamList with_attributes(const ParamList& params, const std::string& target) const;
  void add_shape_record(ShapeRecord record);
  void count_triangles(size_t n, const SourceLocation& where);  // the max_triangles guard

  // Handing shapes to the builder (scene_converter_shapes.cpp).
  void emit_shape(const ShapeRecord& record);
  void emit_sphere(const ShapeRecord& record, const Sphere& sphere, const MaterialPtr& m,
                   MediumInterface media);
  void emit_mesh(const ShapeRecord& record, TriangleMesh mesh, bool quadric, const MaterialPtr& m,
                 MediumInterface media);

  // Objects' prototypes and instances (scene_converter_instances.cpp).
  static bool instanced(const ShapeRecord& record);  // placed by instances, not copied
  struct PrototypeRef {
    uint32_t index = 0;
    Bounds3 bounds;  // object space
  };
  PrototypeRef emit_prototype(const std::vector<ShapeRecord>& shapes);
  void emit_instances();

  SceneBuilder& builder_;
  LoaderContext& ctx_;
  MaterialFactory factory_;

  GraphicsState state_;
  std::vector<Block> blocks_;
  std::map<std::string, Transform> coordinate_systems_;
  bool world_ = false;
  bool transforms_active_ = true;  // false after ActiveTransform EndTime (motion blur unsupported)

  // Options block.
  std::optional<Transform> camera_from_world_;
  CameraParams camera_;

  std::vector<MaterialDef> anonymous_materials_;
  std::vector<std::optional<MaterialPtr>> anonymous_created_;
  std::map<std::string, MaterialDef> named_materials_;
  std::map<std::string, MaterialPtr> named_created_;
  std::vector<std::string> creating_;  // named materials being created (cycle check for mix)

  std::map<std::string, std::optional<int16_t>> media_;  // nullopt: a kind not supported
  MediumNames camera_media_;

  std::vector<ShapeRecord> shapes_;
  std::map<std::string, std::vector<ShapeRecord>> objects_;
  std::optional<std::string> current_object_;
  std::vector<InstanceRecord> instances_;
  size_t triangle_count_ = 0;
};

}  // namespace caustica::pbrt
