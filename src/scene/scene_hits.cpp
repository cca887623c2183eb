// Hit records: an Embree hit (or a stored primitive index) turned into a SurfaceInteraction in
// world space. An instanced triangle's vertices are transformed per hit, so that its record
// is the one a flattened world-space copy of the triangle would give.
#include <algorithm>
#include <cmath>

#include "lights/light.h"
#include "scene/scene.h"
#include "scene/scene_impl.h"

namespace caustica {

namespace {

void complete_sphere(const Sphere& s, Vec3 p_hit, SurfaceInteraction* si) {
  Vec3 local = p_hit - s.center;
  const float len = length(local);
  local = len > 0 ? local * (s.radius / len) : Vec3(0, 0, s.radius);
  const Vec3 p = s.center + local;  // re-projected onto the surface (pbrt-v4)
  si->p = p;
  si->p_error = abs(p) * (8 * gamma_bound(5)) + abs(local) * (8 * gamma_bound(5));
  Vec3 n = local / s.radius;
  float phi = std::atan2(local.y, local.x);
  if (phi < 0) phi += 2 * kPi;
  const float theta = safe_acos(local.z / s.radius);
  si->uv = {phi * kInv2Pi, 1.f - theta * kInvPi};
  const Vec3 dpdu(-2 * kPi * local.y, 2 * kPi * local.x, 0);
  // pbrt-v4's dp/dv for v = 1 - theta / pi (theta from pi at z = -r to 0 at z = r).
  const float z_radius = std::sqrt(local.x * local.x + local.y * local.y);
  const float cos_phi = z_radius > 0 ? local.x / z_radius : 1.f,
              sin_phi = z_radius > 0 ? local.y / z_radius : 0.f;
  const float sin_theta = std::sqrt(std::max(0.f, 1.f - sqr(local.z / s.radius)));
  si->dpdu = dpdu;
  si->dpdv = Vec3(local.z * cos_phi, local.z * sin_phi, -s.radius * sin_theta) * -kPi;
  if (s.reverse_orientation) n = -n;
  si->ng = n;
  si->shading = Frame::from_normal_tangent(n, dpdu);
}

// Barycentrics (b1, b2) of p's projection onto the triangle's plane, clamped into it.
void project_onto_triangle(const Vec3 v[3], Vec3 p, float* b1, float* b2) {
  const Vec3 e1 = v[1] - v[0], e2 = v[2] - v[0], d = p - v[0];
  const float d11 = dot(e1, e1), d12 = dot(e1, e2), d22 = dot(e2, e2), d1 = dot(d, e1),
              d2 = dot(d, e2);
  const float det = d11 * d22 - d12 * d12;
  if (det > 0) {
    *b1 = clamp((d22 * d1 - d12 * d2) / det, 0.f, 1.f);
    *b2 = clamp((d11 * d2 - d12 * d1) / det, 0.f, 1.f - *b1);
  }
}

}  // namespace

uint32_t GeometryTable::geometry_of(uint32_t primitive_index) const {
  return uint32_t(
             std::upper_bound(first_primitive.begin(), first_primitive.end(), primitive_index) -
             first_primitive.begin()) -
         1;
}

const SceneData::MeshEntry& Scene::mesh_entry(uint32_t inst_id, uint32_t geom_id) const {
  const Impl& im = *impl_;
  if (inst_id == SurfaceInteraction::kNoInstance) return meshes_[im.top.mesh_of_geom[geom_id]];
  const uint32_t proto = instances_[im.instance_of_geom[inst_id]].prototype;
  return prototypes_[proto].meshes[im.prototypes[proto].mesh_of_geom[geom_id]];
}

TriangleVertices Scene::triangle_vertices(uint32_t inst_id, uint32_t geom_id,
                                          uint32_t prim_id) const {
  const TriangleMesh& m = mesh_entry(inst_id, geom_id).mesh;
  TriangleVertices v;
  const uint32_t* idx = &m.indices[3 * size_t(prim_id)];
  for (int k = 0; k < 3; ++k) v.p[k] = m.positions[idx[k]];
  v.has_normals = !m.normals.empty();
  if (v.has_normals)
    for (int k = 0; k < 3; ++k) v.n[k] = m.normals[idx[k]];
  if (!m.uvs.empty())
    for (int k = 0; k < 3; ++k) v.uv[k] = m.uvs[idx[k]];
  v.reverse_orientation = m.reverse_orientation;
  if (inst_id == SurfaceInteraction::kNoInstance) return v;
  // As TriangleMesh::transform does for a flattened copy.
  const uint32_t instance = impl_->instance_of_geom[inst_id];
  const Transform& t = instances_[instance].object_to_world;
  for (int k = 0; k < 3; ++k) {
    v.p[k] = t.point(v.p[k]);
    if (!v.has_normals) continue;
    v.n[k] = t.normal(v.n[k]);
    const float len = length(v.n[k]);
    if (len > 0) v.n[k] = v.n[k] / len;
  }
  if (impl_->instance_swaps_handedness[instance]) v.reverse_orientation = !v.reverse_orientation;
  return v;
}

// Embree intersects an instanced triangle in object space: the world vertices and the ray
// origin Embree maps back each carry one transform's rounding (gamma(3) per coordinate, as
// pbrt-v4 bounds a transformed point), which the offset of spawned rays must clear.
static Vec3 instance_rounding(const Transform& t, Vec3 p_world) {
  const Mat4& inv = t.inverse_matrix();
  const Mat4& m = t.matrix();
  Vec3 p_object, bound;
  for (int r = 0; r < 3; ++r)
    p_object[r] = std::abs(inv(r, 0) * p_world.x) + std::abs(inv(r, 1) * p_world.y) +
                  std::abs(inv(r, 2) * p_world.z) + std::abs(inv(r, 3));
  for (int r = 0; r < 3; ++r)
    bound[r] = std::abs(m(r, 0)) * p_object.x + std::abs(m(r, 1)) * p_object.y +
               std::abs(m(r, 2)) * p_object.z + std::abs(m(r, 3));
  return bound * (4 * gamma_bound(3));
}

static void complete_triangle(const TriangleVertices& v, float b1, float b2,
                              SurfaceInteraction* si) {
  const Vec3 p0 = v.p[0], p1 = v.p[1], p2 = v.p[2];
  const float b0 = 1.f - b1 - b2;
  si->p = p0 * b0 + p1 * b1 + p2 * b2;
  si->p_error = (abs(p0 * b0) + abs(p1 * b1) + abs(p2 * b2)) * (8 * gamma_bound(7));
  Vec3 ng = normalize(cross(p1 - p0, p2 - p0));
  const Vec2 uv0 = v.uv[0], uv1 = v.uv[1], uv2 = v.uv[2];
  si->uv = uv0 * b0 + uv1 * b1 + uv2 * b2;
  // dp/du from the uv parameterisation, for the tangent of anisotropic BSDFs.
  const Vec2 duv02 = uv0 - uv2, duv12 = uv1 - uv2;
  const Vec3 dp02 = p0 - p2, dp12 = p1 - p2;
  const float det = duv02.x * duv12.y - duv02.y * duv12.x;
  const bool uv_ok = std::abs(det) > 1e-12f;
  Vec3 dpdu = uv_ok ? (dp02 * duv12.y - dp12 * duv02.y) / det : p1 - p0;
  const Vec3 dpdv = uv_ok ? (dp12 * duv02.x - dp02 * duv12.x) / det : p2 - p0;
  Vec3 ns = ng;
  si->dpdu = dpdu;
  si->dpdv = dpdv;
  if (v.has_normals) {
    ns = v.n[0] * b0 + v.n[1] * b1 + v.n[2] * b2;
    const float len = length(ns);
    ns = len > 0 ? ns / len : ng;
    ng = face_forward(ng, ns);
    // pbrt-v4's shading tangents: dp/du made perpendicular to ns, and cross(ns, it).
    const Vec3 ts = cross(ns, dpdu);
    if (length_squared(ts) > 0) {
      si->dpdu = cross(ts, ns);
      si->dpdv = ts;
    } else {
      const Frame f = Frame::from_normal(ns);
      si->dpdu = f.s;
      si->dpdv = f.t;
    }
  } else if (v.reverse_orientation) {
    ng = -ng;
    ns = ng;
  }
  si->ng = ng;
  si->shading = Frame::from_normal_tangent(ns, dpdu);
}

void Scene::complete_hit(uint32_t inst_id, uint32_t geom_id, uint32_t prim_id, float b1, float b2,
                         Vec3 p_sphere, SurfaceInteraction* si) const {
  si->inst_id = inst_id;
  si->geom_id = geom_id;
  si->prim_id = prim_id;
  if (inst_id == SurfaceInteraction::kNoInstance && geom_id == impl_->sphere_geom_id) {
    const auto& e = spheres_[prim_id];
    complete_sphere(e.sphere, p_sphere, si);
    si->material = e.material.get();
    si->area_light = e.light != UINT32_MAX ? lights_[e.light].get() : nullptr;
    si->media = e.media;
    return;
  }
  const SceneData::MeshEntry& e = mesh_entry(inst_id, geom_id);
  complete_triangle(triangle_vertices(inst_id, geom_id, prim_id), b1, b2, si);
  if (inst_id != SurfaceInteraction::kNoInstance)
    si->p_error +=
        instance_rounding(instances_[impl_->instance_of_geom[inst_id]].object_to_world, si->p);
  si->material = e.material.get();
  si->area_light = e.first_light != UINT32_MAX ? lights_[e.first_light + prim_id].get() : nullptr;
  si->media = e.media;
}

uint32_t Scene::primitive_index(const SurfaceInteraction& si) const {
  const Impl& im = *impl_;
  if (si.inst_id == SurfaceInteraction::kNoInstance)
    return im.top.first_primitive[si.geom_id] + si.prim_id;
  const GeometryTable& proto = im.prototypes[instances_[im.instance_of_geom[si.inst_id]].prototype];
  return im.top.first_primitive[si.inst_id] + proto.first_primitive[si.geom_id] + si.prim_id;
}

Scene::PrimitiveRange Scene::shape_primitives(const SurfaceInteraction& si) const {
  const Impl& im = *impl_;
  uint32_t first = im.top.first_primitive[si.geom_id];
  if (si.inst_id != SurfaceInteraction::kNoInstance) {
    const uint32_t proto = instances_[im.instance_of_geom[si.inst_id]].prototype;
    first = im.top.first_primitive[si.inst_id] + im.prototypes[proto].first_primitive[si.geom_id];
  } else if (si.geom_id == im.sphere_geom_id) {
    return {first + si.prim_id, first + si.prim_id + 1};
  }
  return {first, first + uint32_t(mesh_entry(si.inst_id, si.geom_id).mesh.triangle_count())};
}

SurfaceInteraction Scene::interaction_at(uint32_t primitive_index, Vec3 p, Vec3 wo) const {
  const Impl& im = *impl_;
  uint32_t geom_id = im.top.geometry_of(primitive_index);
  uint32_t prim_id = primitive_index - im.top.first_primitive[geom_id];
  uint32_t inst_id = SurfaceInteraction::kNoInstance;
  if (geom_id < im.instance_of_geom.size() && im.instance_of_geom[geom_id] != UINT32_MAX) {
    inst_id = geom_id;
    const GeometryTable& proto = im.prototypes[instances_[im.instance_of_geom[inst_id]].prototype];
    geom_id = proto.geometry_of(prim_id);
    prim_id -= proto.first_primitive[geom_id];
  }
  SurfaceInteraction si;
  si.wo = wo;
  float b1 = 0, b2 = 0;
  if (inst_id != SurfaceInteraction::kNoInstance || geom_id != im.sphere_geom_id)
    project_onto_triangle(triangle_vertices(inst_id, geom_id, prim_id).p, p, &b1, &b2);
  complete_hit(inst_id, geom_id, prim_id, b1, b2, p, &si);
  return si;
}

}  // namespace caustica
