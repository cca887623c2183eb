// Gives meaning to pbrt-v4 directives: the graphics state (current transformation, its
// AttributeBegin/End and TransformBegin/End stack, ReverseOrientation, current material and
// area light, named coordinate systems, Attribute defaults), the options block (Camera,
// Film, Sampler, Integrator) and the world (shapes, materials, textures, lights, objects).
//
// Materials are created after the whole file is read, as in pbrt-v4, so NamedMaterial may
// refer to a material defined later. Object instances (ObjectBegin/End/ObjectInstance) are
// flattened into world-space copies for now rather than Embree instances.
#pragma once

#include <map>
#include <memory>
#include <optional>
#include <string>
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
  struct GraphicsState {
    Transform ctm;
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
  };

  void handle(const Directive& d);
  void apply_transform(const Directive& d, const Transform& t, bool concatenate);
  void require_world(const Directive& d, bool inside) const;
  ParamList with_attributes(const ParamList& params, const std::string& target) const;
  void add_shape_record(ShapeRecord record);
  MaterialPtr material(const MaterialRef& ref);
  MaterialPtr named_material(const std::string& name, const SourceLocation& where);
  void emit_shape(const ShapeRecord& record);

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

  std::vector<ShapeRecord> shapes_;
  std::map<std::string, std::vector<ShapeRecord>> objects_;
  std::optional<std::string> current_object_;
  size_t triangle_count_ = 0;
};

}  // namespace caustica::pbrt
