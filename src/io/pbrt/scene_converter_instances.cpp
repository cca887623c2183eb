// Hands the objects to the builder once the file is read: each object that ObjectInstance
// placed becomes one prototype (its triangle meshes, in the object's space) and each
// placement one instance of it, so memory grows with the objects, not with their copies.
#include <map>

#include "io/pbrt/scene_converter.h"
#include "io/pbrt/transforms.h"

namespace caustica::pbrt {

// Spheres stay exact only under a similarity of the whole transform, and a tessellated
// quadric's orientation depends on the whole transform's handedness: those are copied, as are
// shapes that bound media or have an alpha mask (the prototypes' meshes carry neither).
bool SceneConverter::instanced(const ShapeRecord& r) {
  return r.geometry->mesh && !r.geometry->sphere_radius && !r.geometry->quadric &&
         r.media.inside == r.media.outside && !r.alpha;
}

SceneConverter::PrototypeRef SceneConverter::emit_prototype(
    const std::vector<ShapeRecord>& shapes) {
  PrototypeRef proto{builder_.add_prototype(), {}};
  for (const ShapeRecord& r : shapes) {
    if (!instanced(r)) continue;
    MaterialPtr m = material(r.material);
    if (!m) continue;  // "interface" bounding no medium (else the shape is copied)
    const Transform& t = r.object_to_world;  // the shape's transform inside the definition
    if (!is_invertible(t)) {
      ctx_.warnings.warn(r.where, "shape with a singular transformation skipped", "singular shape");
      continue;
    }
    TriangleMesh mesh = *r.geometry->mesh;
    if (mesh.indices.empty()) continue;
    mesh.transform(t);
    if (r.reverse_orientation) mesh.flip_orientation();
    Bounds3 bounds;
    for (const Vec3& p : mesh.positions) bounds.extend(p);
    if (!is_finite(bounds.lo) || !is_finite(bounds.hi)) {
      ctx_.warnings.warn(r.where, "shape with non-finite coordinates skipped", "non-finite shape");
      continue;
    }
    proto.bounds.extend(bounds.lo);
    proto.bounds.extend(bounds.hi);
    try {
      builder_.add_prototype_mesh(proto.index, std::move(mesh), m);
    } catch (const std::exception& e) {
      throw SceneLoadError(r.where, std::string("Shape: ") + e.what());
    }
  }
  return proto;
}

void SceneConverter::emit_instances() {
  std::map<std::string, PrototypeRef> prototypes;  // each object's, made at its first use
  for (const InstanceRecord& inst : instances_) {
    auto it = prototypes.find(inst.object);
    if (it == prototypes.end())
      it = prototypes.emplace(inst.object, emit_prototype(objects_.at(inst.object))).first;
    const PrototypeRef& proto = it->second;
    if (proto.bounds.empty()) continue;
    const Bounds3 world = inst.object_to_world.bounds(proto.bounds);
    if (!is_finite(world.lo) || !is_finite(world.hi)) {
      ctx_.warnings.warn(inst.where, "object instance with non-finite coordinates skipped",
                         "non-finite shape");
      continue;
    }
    builder_.add_instance(proto.index, inst.object_to_world);
  }
}

}  // namespace caustica::pbrt
