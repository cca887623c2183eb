#include "scene/scene.h"

#include <embree3/rtcore.h>
#include <tbb/enumerable_thread_specific.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

#include "lights/light.h"
#include "lights/light_sampler.h"

namespace caustica {

namespace {

// gamma(n) of Higham / pbrt: bound on the relative error of n float operations.
constexpr float gamma_bound(int n) {
  constexpr float eps = 0x1p-24f;
  return (n * eps) / (1 - n * eps);
}

// Embree user geometry for exact spheres: ray-sphere in double precision, as pbrt-v4 does
// to keep the roots accurate for glass (rays leaving the surface from inside).
struct SphereGeometry {
  const std::vector<SceneData::SphereEntry>* spheres;
};

void sphere_bounds(const RTCBoundsFunctionArguments* args) {
  const auto* g = static_cast<const SphereGeometry*>(args->geometryUserPtr);
  const Sphere& s = (*g->spheres)[args->primID].sphere;
  RTCBounds* b = args->bounds_o;
  const float r = s.radius * (1 + 1e-5f);
  b->lower_x = s.center.x - r;
  b->lower_y = s.center.y - r;
  b->lower_z = s.center.z - r;
  b->upper_x = s.center.x + r;
  b->upper_y = s.center.y + r;
  b->upper_z = s.center.z + r;
}

// Returns the nearest root in (tnear, tfar), or -1.
double sphere_hit(const Sphere& s, const float o[3], const float d[3], double tnear, double tfar) {
  const double ox = double(o[0]) - s.center.x, oy = double(o[1]) - s.center.y,
               oz = double(o[2]) - s.center.z;
  const double dx = d[0], dy = d[1], dz = d[2];
  const double a = dx * dx + dy * dy + dz * dz;
  const double b = 2 * (dx * ox + dy * oy + dz * oz);
  const double r2 = double(s.radius) * s.radius;
  // Discriminant via the perpendicular distance of the centre (pbrt-v4, Hearn & Baker):
  // stable when the ray passes far from the centre.
  const double f = b / (2 * a);
  const double vx = ox - f * dx, vy = oy - f * dy, vz = oz - f * dz;
  const double disc = 4 * a * (r2 - (vx * vx + vy * vy + vz * vz));
  if (disc < 0) return -1;
  const double root = std::sqrt(disc);
  const double c = ox * ox + oy * oy + oz * oz - r2;
  const double q = (b < 0) ? -0.5 * (b - root) : -0.5 * (b + root);
  double t0 = q / a, t1 = c / q;
  if (t0 > t1) std::swap(t0, t1);
  if (t0 > tnear && t0 < tfar) return t0;
  if (t1 > tnear && t1 < tfar) return t1;
  return -1;
}

void sphere_intersect(const RTCIntersectFunctionNArguments* args) {
  if (!args->valid[0]) return;
  const auto* g = static_cast<const SphereGeometry*>(args->geometryUserPtr);
  const Sphere& s = (*g->spheres)[args->primID].sphere;
  auto* rh = reinterpret_cast<RTCRayHit*>(args->rayhit);
  const float o[3] = {rh->ray.org_x, rh->ray.org_y, rh->ray.org_z};
  const float d[3] = {rh->ray.dir_x, rh->ray.dir_y, rh->ray.dir_z};
  const double t = sphere_hit(s, o, d, rh->ray.tnear, rh->ray.tfar);
  if (t < 0) return;
  rh->ray.tfar = float(t);
  rh->hit.u = rh->hit.v = 0;
  rh->hit.Ng_x = rh->hit.Ng_y = rh->hit.Ng_z = 0;
  rh->hit.primID = args->primID;
  rh->hit.geomID = args->geomID;
  rh->hit.instID[0] = args->context->instID[0];
}

void sphere_occluded(const RTCOccludedFunctionNArguments* args) {
  if (!args->valid[0]) return;
  const auto* g = static_cast<const SphereGeometry*>(args->geometryUserPtr);
  const Sphere& s = (*g->spheres)[args->primID].sphere;
  auto* ray = reinterpret_cast<RTCRay*>(args->ray);
  const float o[3] = {ray->org_x, ray->org_y, ray->org_z};
  const float d[3] = {ray->dir_x, ray->dir_y, ray->dir_z};
  if (sphere_hit(s, o, d, ray->tnear, ray->tfar) >= 0) ray->tfar = -kInfinity;
}

// Embree calls this from C code: never throw here; the constructor checks the device after.
void embree_error(void* user, RTCError, const char* str) {
  auto* message = static_cast<std::string*>(user);
  if (message->empty()) *message = str ? str : "unknown error";
}

}  // namespace

struct Scene::Impl {
  RTCDevice device = nullptr;
  RTCScene scene = nullptr;
  unsigned sphere_geom_id = RTC_INVALID_GEOMETRY_ID;
  std::vector<int> mesh_of_geom;          // Embree geometry id -> mesh index (-1: spheres)
  std::vector<uint32_t> first_primitive;  // Embree geometry id -> its first dense primitive index
  SphereGeometry sphere_geometry{};
  struct RayCounts {
    uint64_t all = 0, occlusion = 0;
  };
  mutable tbb::enumerable_thread_specific<RayCounts> rays;
  std::string error;

  ~Impl() {
    if (scene) rtcReleaseScene(scene);
    if (device) rtcReleaseDevice(device);
  }
};

Scene::Scene(SceneData data)
    : impl_(std::make_unique<Impl>()),
      meshes_(std::move(data.meshes)),
      spheres_(std::move(data.spheres)),
      lights_(std::move(data.lights)),
      camera_params_(data.camera),
      camera_(data.camera),
      settings_(std::move(data.settings)),
      name_(std::move(data.name)) {
  Impl& im = *impl_;
  // No "threads=N" here: Embree's TBB backend implements it with a process-wide
  // tbb::global_control, which would cap the renderer's own parallelism too.
  im.device = rtcNewDevice(nullptr);
  if (!im.device) throw std::runtime_error("could not create the Embree device");
  rtcSetDeviceErrorFunction(im.device, embree_error, &im.error);
  im.scene = rtcNewScene(im.device);
  rtcSetSceneFlags(im.scene, RTC_SCENE_FLAG_ROBUST);
  rtcSetSceneBuildQuality(im.scene, RTC_BUILD_QUALITY_HIGH);

  for (size_t mi = 0; mi < meshes_.size(); ++mi) {
    const TriangleMesh& m = meshes_[mi].mesh;
    if (m.triangle_count() == 0) continue;
    RTCGeometry g = rtcNewGeometry(im.device, RTC_GEOMETRY_TYPE_TRIANGLE);
    auto* vb = static_cast<float*>(rtcSetNewGeometryBuffer(
        g, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3, 3 * sizeof(float), m.positions.size()));
    for (size_t i = 0; i < m.positions.size(); ++i) {
      vb[3 * i] = m.positions[i].x;
      vb[3 * i + 1] = m.positions[i].y;
      vb[3 * i + 2] = m.positions[i].z;
      bounds_.extend(m.positions[i]);
    }
    auto* ib = static_cast<uint32_t*>(rtcSetNewGeometryBuffer(
        g, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3, 3 * sizeof(uint32_t), m.triangle_count()));
    std::copy(m.indices.begin(), m.indices.end(), ib);
    rtcCommitGeometry(g);
    const unsigned id = rtcAttachGeometry(im.scene, g);
    rtcReleaseGeometry(g);
    if (im.mesh_of_geom.size() <= id) im.mesh_of_geom.resize(id + 1, -1);
    im.mesh_of_geom[id] = int(mi);
  }
  if (!spheres_.empty()) {
    im.sphere_geometry.spheres = &spheres_;
    RTCGeometry g = rtcNewGeometry(im.device, RTC_GEOMETRY_TYPE_USER);
    rtcSetGeometryUserPrimitiveCount(g, unsigned(spheres_.size()));
    rtcSetGeometryUserData(g, &im.sphere_geometry);
    rtcSetGeometryBoundsFunction(g, sphere_bounds, nullptr);
    rtcSetGeometryIntersectFunction(g, sphere_intersect);
    rtcSetGeometryOccludedFunction(g, sphere_occluded);
    rtcCommitGeometry(g);
    im.sphere_geom_id = rtcAttachGeometry(im.scene, g);
    rtcReleaseGeometry(g);
    if (im.mesh_of_geom.size() <= im.sphere_geom_id)
      im.mesh_of_geom.resize(im.sphere_geom_id + 1, -1);
    for (const auto& s : spheres_) {
      bounds_.extend(s.sphere.center - Vec3(s.sphere.radius, s.sphere.radius, s.sphere.radius));
      bounds_.extend(s.sphere.center + Vec3(s.sphere.radius, s.sphere.radius, s.sphere.radius));
    }
  }
  // Build the BVH on one thread: its layout, and so the choice between equally close hits
  // (shared edges), is then the same for any thread count, keeping images bit-identical.
  tbb::task_arena single_threaded(1);
  single_threaded.execute([&] { rtcCommitScene(im.scene); });
  // Dense primitive indices in geometry-id order (ids are assigned consecutively from 0).
  im.first_primitive.assign(im.mesh_of_geom.size(), 0);
  for (size_t g = 0, next = 0; g < im.mesh_of_geom.size(); ++g) {
    im.first_primitive[g] = uint32_t(next);
    if (g == im.sphere_geom_id)
      next += spheres_.size();
    else if (im.mesh_of_geom[g] >= 0)
      next += meshes_[im.mesh_of_geom[g]].mesh.triangle_count();
  }
  if (!im.error.empty()) throw std::runtime_error("Embree: " + im.error);

  if (bounds_.empty()) bounds_.extend(Vec3(0, 0, 0));
  Vec3 center;
  float radius;
  bounds_.bounding_sphere(&center, &radius);
  radius = std::max(radius, 1e-3f);
  for (uint32_t i = 0; i < lights_.size(); ++i) {
    lights_[i]->index = i;
    lights_[i]->preprocess(center, radius);
    light_ptrs_.push_back(lights_[i].get());
    if (lights_[i]->is_infinite()) infinite_lights_.push_back(lights_[i].get());
  }
  light_sampler_ = std::make_unique<LightSampler>(light_ptrs_);
}

Scene::~Scene() = default;

void Scene::override_resolution(int width, int height) {
  if (width <= 0 || height <= 0) throw std::invalid_argument("resolution must be positive");
  camera_params_.width = width;
  camera_params_.height = height;
  camera_ = Camera(camera_params_);
}

size_t Scene::triangle_count() const {
  size_t n = 0;
  for (const auto& m : meshes_) n += m.mesh.triangle_count();
  return n;
}

uint64_t Scene::rays_traced() const {
  uint64_t n = 0;
  for (const Impl::RayCounts& c : impl_->rays) n += c.all;
  return n;
}

uint64_t Scene::occlusion_rays_traced() const {
  uint64_t n = 0;
  for (const Impl::RayCounts& c : impl_->rays) n += c.occlusion;
  return n;
}

static void fill_ray(const Ray& r, RTCRay* out) {
  out->org_x = r.o.x;
  out->org_y = r.o.y;
  out->org_z = r.o.z;
  out->dir_x = r.d.x;
  out->dir_y = r.d.y;
  out->dir_z = r.d.z;
  out->tnear = 0.f;
  out->tfar = r.tmax;
  out->time = 0.f;
  out->mask = 0xffffffffu;
  out->id = 0;
  out->flags = 0;
}

bool Scene::occluded(const Ray& ray) const {
  Impl::RayCounts& counts = impl_->rays.local();
  ++counts.all;
  ++counts.occlusion;
  RTCIntersectContext ctx;
  rtcInitIntersectContext(&ctx);
  RTCRay r;
  fill_ray(ray, &r);
  rtcOccluded1(impl_->scene, &ctx, &r);
  return r.tfar < 0;
}

bool Scene::intersect(const Ray& ray, SurfaceInteraction* si) const {
  ++impl_->rays.local().all;
  RTCIntersectContext ctx;
  rtcInitIntersectContext(&ctx);
  RTCRayHit rh;
  fill_ray(ray, &rh.ray);
  rh.hit.geomID = RTC_INVALID_GEOMETRY_ID;
  rh.hit.instID[0] = RTC_INVALID_GEOMETRY_ID;
  rtcIntersect1(impl_->scene, &ctx, &rh);
  if (rh.hit.geomID == RTC_INVALID_GEOMETRY_ID) return false;

  si->t = rh.ray.tfar;
  si->wo = -normalize(ray.d);
  Vec3 p_sphere;
  if (rh.hit.geomID == impl_->sphere_geom_id) p_sphere = ray.o + ray.d * si->t;
  complete_hit(rh.hit.geomID, rh.hit.primID, rh.hit.u, rh.hit.v, p_sphere, si);
  return true;
}

uint64_t Scene::intersect_raw(const Ray* rays, size_t n, float* t_hit) const {
  RTCIntersectContext ctx;
  rtcInitIntersectContext(&ctx);
  uint64_t hits = 0;
  for (size_t i = 0; i < n; ++i) {
    RTCRayHit rh;
    fill_ray(rays[i], &rh.ray);
    rh.hit.geomID = RTC_INVALID_GEOMETRY_ID;
    rh.hit.instID[0] = RTC_INVALID_GEOMETRY_ID;
    rtcIntersect1(impl_->scene, &ctx, &rh);
    const bool hit = rh.hit.geomID != RTC_INVALID_GEOMETRY_ID;
    hits += hit;
    t_hit[i] = hit ? rh.ray.tfar : kInfinity;
  }
  return hits;
}

uint64_t Scene::occluded_raw(const Ray* rays, size_t n) const {
  RTCIntersectContext ctx;
  rtcInitIntersectContext(&ctx);
  uint64_t occluded = 0;
  for (size_t i = 0; i < n; ++i) {
    RTCRay r;
    fill_ray(rays[i], &r);
    rtcOccluded1(impl_->scene, &ctx, &r);
    occluded += r.tfar < 0;
  }
  return occluded;
}

void Scene::complete_hit(uint32_t geom_id, uint32_t prim_id, float b1, float b2, Vec3 p_sphere,
                         SurfaceInteraction* si) const {
  si->geom_id = geom_id;
  si->prim_id = prim_id;
  if (geom_id == impl_->sphere_geom_id) {
    const auto& e = spheres_[prim_id];
    const Sphere& s = e.sphere;
    Vec3 p = p_sphere;
    Vec3 local = p - s.center;
    const float len = length(local);
    local = len > 0 ? local * (s.radius / len) : Vec3(0, 0, s.radius);
    p = s.center + local;  // re-projected onto the surface (pbrt-v4)
    si->p = p;
    si->p_error = abs(p) * (8 * gamma_bound(5)) + abs(local) * (8 * gamma_bound(5));
    Vec3 n = local / s.radius;
    float phi = std::atan2(local.y, local.x);
    if (phi < 0) phi += 2 * kPi;
    const float theta = safe_acos(local.z / s.radius);
    si->uv = {phi * kInv2Pi, 1.f - theta * kInvPi};
    const Vec3 dpdu(-2 * kPi * local.y, 2 * kPi * local.x, 0);
    if (s.reverse_orientation) n = -n;
    si->ng = n;
    si->shading = Frame::from_normal_tangent(n, dpdu);
    si->material = e.material.get();
    si->area_light = e.light != UINT32_MAX ? lights_[e.light].get() : nullptr;
    return;
  }

  const auto& e = meshes_[impl_->mesh_of_geom[geom_id]];
  const TriangleMesh& m = e.mesh;
  const uint32_t i0 = m.indices[3 * prim_id], i1 = m.indices[3 * prim_id + 1],
                 i2 = m.indices[3 * prim_id + 2];
  const Vec3 p0 = m.positions[i0], p1 = m.positions[i1], p2 = m.positions[i2];
  const float b0 = 1.f - b1 - b2;
  si->p = p0 * b0 + p1 * b1 + p2 * b2;
  si->p_error = (abs(p0 * b0) + abs(p1 * b1) + abs(p2 * b2)) * (8 * gamma_bound(7));
  Vec3 ng = normalize(cross(p1 - p0, p2 - p0));
  Vec2 uv0(0, 0), uv1(1, 0), uv2(1, 1);
  if (!m.uvs.empty()) {
    uv0 = m.uvs[i0];
    uv1 = m.uvs[i1];
    uv2 = m.uvs[i2];
  }
  si->uv = uv0 * b0 + uv1 * b1 + uv2 * b2;
  // dp/du from the uv parameterisation, for the tangent of anisotropic BSDFs.
  const Vec2 duv02 = uv0 - uv2, duv12 = uv1 - uv2;
  const Vec3 dp02 = p0 - p2, dp12 = p1 - p2;
  const float det = duv02.x * duv12.y - duv02.y * duv12.x;
  Vec3 dpdu = std::abs(det) > 1e-12f ? (dp02 * duv12.y - dp12 * duv02.y) / det : p1 - p0;
  Vec3 ns = ng;
  if (!m.normals.empty()) {
    ns = m.normals[i0] * b0 + m.normals[i1] * b1 + m.normals[i2] * b2;
    const float len = length(ns);
    ns = len > 0 ? ns / len : ng;
    ng = face_forward(ng, ns);
  } else if (m.reverse_orientation) {
    ng = -ng;
    ns = ng;
  }
  si->ng = ng;
  si->shading = Frame::from_normal_tangent(ns, dpdu);
  si->material = e.material.get();
  si->area_light = e.first_light != UINT32_MAX ? lights_[e.first_light + prim_id].get() : nullptr;
}

uint32_t Scene::primitive_index(const SurfaceInteraction& si) const {
  return impl_->first_primitive[si.geom_id] + si.prim_id;
}

Scene::PrimitiveRange Scene::shape_primitives(const SurfaceInteraction& si) const {
  const uint32_t first = impl_->first_primitive[si.geom_id];
  if (si.geom_id == impl_->sphere_geom_id) return {first + si.prim_id, first + si.prim_id + 1};
  return {first, first + uint32_t(meshes_[impl_->mesh_of_geom[si.geom_id]].mesh.triangle_count())};
}

SurfaceInteraction Scene::interaction_at(uint32_t primitive_index, Vec3 p, Vec3 wo) const {
  const auto& first = impl_->first_primitive;
  // The geometry whose range [first[g], first[g + 1]) holds the index.
  const uint32_t geom_id =
      uint32_t(std::upper_bound(first.begin(), first.end(), primitive_index) - first.begin()) - 1;
  const uint32_t prim_id = primitive_index - first[geom_id];
  SurfaceInteraction si;
  si.wo = wo;
  float b1 = 0, b2 = 0;
  if (geom_id != impl_->sphere_geom_id) {
    // Barycentrics of p's projection onto the triangle's plane.
    const TriangleMesh& m = meshes_[impl_->mesh_of_geom[geom_id]].mesh;
    const Vec3 p0 = m.positions[m.indices[3 * prim_id]],
               p1 = m.positions[m.indices[3 * prim_id + 1]],
               p2 = m.positions[m.indices[3 * prim_id + 2]];
    const Vec3 e1 = p1 - p0, e2 = p2 - p0, d = p - p0;
    const float d11 = dot(e1, e1), d12 = dot(e1, e2), d22 = dot(e2, e2), d1 = dot(d, e1),
                d2 = dot(d, e2);
    const float det = d11 * d22 - d12 * d12;
    if (det > 0) {
      b1 = clamp((d22 * d1 - d12 * d2) / det, 0.f, 1.f);
      b2 = clamp((d11 * d2 - d12 * d1) / det, 0.f, 1.f - b1);
    }
  }
  complete_hit(geom_id, prim_id, b1, b2, p, &si);
  return si;
}

}  // namespace caustica
