// Building the Embree scenes (the top level, one per prototype, and the instances that place
// prototypes) and tracing rays through them. Hit records: scene_hits.cpp.
#include "scene/scene.h"

#include <tbb/task_arena.h>

#include <algorithm>
#include <bit>
#include <cmath>
#include <stdexcept>
#include <string>

#include "core/rng.h"
#include "lights/light.h"
#include "lights/light_sampler.h"
#include "scene/scene_impl.h"

namespace caustica {

namespace {

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

// pbrt-v4's alpha masks, as an Embree filter for closest-hit and occlusion rays alike: a hit where
// the mesh's alpha texture is 0 is ignored; where it is in (0, 1), it is kept with that
// probability, decided by a hash of the ray's origin and direction (pbrt-v4's HashFloat(o, d)),
// so that the same ray always decides alike. Embree calls this from C code: it must not throw.
float ray_hash_float(const float o[3], const float d[3]) {
  uint64_t h = 0x616c706861ull;  // "alpha"
  for (int k = 0; k < 3; ++k) h = hash_combine(h, std::bit_cast<uint32_t>(o[k]));
  for (int k = 0; k < 3; ++k) h = hash_combine(h, std::bit_cast<uint32_t>(d[k]));
  return float(h >> 40) * 0x1p-24f;
}

void alpha_filter(const RTCFilterFunctionNArguments* args) {
  const auto* e = static_cast<const SceneData::MeshEntry*>(args->geometryUserPtr);
  const TriangleMesh& m = e->mesh;
  for (unsigned i = 0; i < args->N; ++i) {
    if (args->valid[i] != -1) continue;
    const unsigned prim = RTCHitN_primID(args->hit, args->N, i);
    const float b1 = RTCHitN_u(args->hit, args->N, i), b2 = RTCHitN_v(args->hit, args->N, i),
                b0 = 1 - b1 - b2;
    const uint32_t* idx = &m.indices[3 * size_t(prim)];
    Vec2 uv[3] = {{0, 0}, {1, 0}, {1, 1}};  // as TriangleVertices without uvs
    if (!m.uvs.empty())
      for (int k = 0; k < 3; ++k) uv[k] = m.uvs[idx[k]];
    const Vec3 p = m.positions[idx[0]] * b0 + m.positions[idx[1]] * b1 + m.positions[idx[2]] * b2;
    const float a = e->alpha->eval_float({uv[0] * b0 + uv[1] * b1 + uv[2] * b2, p});
    if (a >= 1) continue;
    bool masked = !(a > 0);
    if (!masked) {
      const float o[3] = {RTCRayN_org_x(args->ray, args->N, i),
                          RTCRayN_org_y(args->ray, args->N, i),
                          RTCRayN_org_z(args->ray, args->N, i)};
      const float d[3] = {RTCRayN_dir_x(args->ray, args->N, i),
                          RTCRayN_dir_y(args->ray, args->N, i),
                          RTCRayN_dir_z(args->ray, args->N, i)};
      masked = ray_hash_float(o, d) > a;
    }
    if (masked) args->valid[i] = 0;
  }
}

// Embree calls this from C code: never throw here; the constructor checks the device after.
void embree_error(void* user, RTCError, const char* str) {
  auto* message = static_cast<std::string*>(user);
  if (message->empty()) *message = str ? str : "unknown error";
}

bool embree_memory(void* user, ssize_t bytes, bool) {
  *static_cast<std::atomic<int64_t>*>(user) += int64_t(bytes);
  return true;
}

}  // namespace

namespace {

// Attaches each non-empty mesh as an Embree triangle geometry; extends *bounds (if given) by
// the vertices.
void attach_meshes(RTCDevice device, const std::vector<SceneData::MeshEntry>& meshes,
                   GeometryTable* table, Bounds3* bounds) {
  for (size_t mi = 0; mi < meshes.size(); ++mi) {
    const TriangleMesh& m = meshes[mi].mesh;
    if (m.triangle_count() == 0) continue;
    RTCGeometry g = rtcNewGeometry(device, RTC_GEOMETRY_TYPE_TRIANGLE);
    auto* vb = static_cast<float*>(rtcSetNewGeometryBuffer(
        g, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3, 3 * sizeof(float), m.positions.size()));
    for (size_t i = 0; i < m.positions.size(); ++i) {
      vb[3 * i] = m.positions[i].x;
      vb[3 * i + 1] = m.positions[i].y;
      vb[3 * i + 2] = m.positions[i].z;
      if (bounds) bounds->extend(m.positions[i]);
    }
    auto* ib = static_cast<uint32_t*>(rtcSetNewGeometryBuffer(
        g, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3, 3 * sizeof(uint32_t), m.triangle_count()));
    std::copy(m.indices.begin(), m.indices.end(), ib);
    if (meshes[mi].alpha) {
      rtcSetGeometryUserData(g, const_cast<SceneData::MeshEntry*>(&meshes[mi]));
      rtcSetGeometryIntersectFilterFunction(g, alpha_filter);
      rtcSetGeometryOccludedFilterFunction(g, alpha_filter);
    }
    rtcCommitGeometry(g);
    const unsigned id = rtcAttachGeometry(table->scene, g);
    rtcReleaseGeometry(g);
    if (table->mesh_of_geom.size() <= id) table->mesh_of_geom.resize(id + 1, -1);
    table->mesh_of_geom[id] = int(mi);
  }
}

// Dense primitive indices in geometry-id order (ids are assigned consecutively from 0);
// count(g) is geometry g's number of primitives.
template <class Count>
void assign_primitive_indices(GeometryTable* table, Count count) {
  table->first_primitive.assign(table->mesh_of_geom.size(), 0);
  uint64_t next = 0;
  for (size_t g = 0; g < table->mesh_of_geom.size(); ++g) {
    if (next > UINT32_MAX)
      throw std::runtime_error(
          "the scene has more than 2^32 primitives (counting each "
          "instance's), more than 32-bit primitive indices can name");
    table->first_primitive[g] = uint32_t(next);
    next += count(g);
  }
  if (next > UINT32_MAX)
    throw std::runtime_error(
        "the scene has more than 2^32 primitives (counting each "
        "instance's), more than 32-bit primitive indices can name");
  table->primitive_count = next;
}

// Embree's instance transform: the 3x4 affine part, column-major.
void set_instance_transform(RTCGeometry g, const Transform& t) {
  float xfm[12];
  for (int c = 0; c < 4; ++c)
    for (int r = 0; r < 3; ++r) xfm[3 * c + r] = t.matrix()(r, c);
  rtcSetGeometryTransform(g, 0, RTC_FORMAT_FLOAT3X4_COLUMN_MAJOR, xfm);
}

RTCScene new_embree_scene(RTCDevice device) {
  RTCScene scene = rtcNewScene(device);
  rtcSetSceneFlags(scene, RTC_SCENE_FLAG_ROBUST);
  rtcSetSceneBuildQuality(scene, RTC_BUILD_QUALITY_HIGH);
  return scene;
}

}  // namespace

Scene::Scene(SceneData data)
    : impl_(std::make_unique<Impl>()),
      meshes_(std::move(data.meshes)),
      spheres_(std::move(data.spheres)),
      prototypes_(std::move(data.prototypes)),
      instances_(std::move(data.instances)),
      lights_(std::move(data.lights)),
      media_(std::move(data.media)),
      default_medium_(data.default_medium),
      camera_params_(data.camera),
      camera_(data.camera),
      settings_(std::move(data.settings)),
      name_(std::move(data.name)) {
  auto check_medium = [&](int16_t m) {
    if (m != kNoMedium && (m < 0 || size_t(m) >= media_.size()))
      throw std::invalid_argument("a medium index is out of range");
  };
  check_medium(default_medium_);
  for (const auto& e : meshes_) has_interfaces_ |= !e.material;
  for (const auto& e : spheres_) has_interfaces_ |= !e.material;
  for (const auto& proto : prototypes_)
    for (const auto& e : proto.meshes) has_interfaces_ |= !e.material;
  for (const auto& e : meshes_) check_medium(e.media.inside), check_medium(e.media.outside);
  for (const auto& e : spheres_) check_medium(e.media.inside), check_medium(e.media.outside);
  build_accelerator();

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

void Scene::build_accelerator() {
  Impl& im = *impl_;
  // No "threads=N" here: Embree's TBB backend implements it with a process-wide
  // tbb::global_control, which would cap the renderer's own parallelism too.
  im.device = rtcNewDevice(nullptr);
  if (!im.device) throw std::runtime_error("could not create the Embree device");
  rtcSetDeviceErrorFunction(im.device, embree_error, &im.error);
  rtcSetDeviceMemoryMonitorFunction(im.device, embree_memory, &im.embree_bytes);
  // Build every BVH on one thread: its layout, and so the choice between equally close hits
  // (shared edges), is then the same for any thread count, keeping images bit-identical.
  tbb::task_arena single_threaded(1);
  for (const SceneData::Prototype& proto : prototypes_) {
    GeometryTable& table = im.prototypes.emplace_back();
    table.scene = new_embree_scene(im.device);
    attach_meshes(im.device, proto.meshes, &table, nullptr);
    single_threaded.execute([&] { rtcCommitScene(table.scene); });
    assign_primitive_indices(&table, [&](size_t g) {
      return table.mesh_of_geom[g] >= 0 ? proto.meshes[table.mesh_of_geom[g]].mesh.triangle_count()
                                        : 0;
    });
  }
  im.top.scene = new_embree_scene(im.device);
  attach_meshes(im.device, meshes_, &im.top, &bounds_);
  if (!spheres_.empty()) attach_spheres();
  attach_instances();
  single_threaded.execute([&] { rtcCommitScene(im.top.scene); });
  assign_primitive_indices(&im.top, [&](size_t g) -> uint64_t {
    if (g == im.sphere_geom_id) return spheres_.size();
    if (im.top.mesh_of_geom[g] >= 0) return meshes_[im.top.mesh_of_geom[g]].mesh.triangle_count();
    if (g < im.instance_of_geom.size() && im.instance_of_geom[g] != UINT32_MAX)
      return im.prototypes[instances_[im.instance_of_geom[g]].prototype].primitive_count;
    return 0;
  });
  if (!im.error.empty()) throw std::runtime_error("Embree: " + im.error);
}

void Scene::attach_spheres() {
  Impl& im = *impl_;
  im.sphere_geometry.spheres = &spheres_;
  RTCGeometry g = rtcNewGeometry(im.device, RTC_GEOMETRY_TYPE_USER);
  rtcSetGeometryUserPrimitiveCount(g, unsigned(spheres_.size()));
  rtcSetGeometryUserData(g, &im.sphere_geometry);
  rtcSetGeometryBoundsFunction(g, sphere_bounds, nullptr);
  rtcSetGeometryIntersectFunction(g, sphere_intersect);
  rtcSetGeometryOccludedFunction(g, sphere_occluded);
  rtcCommitGeometry(g);
  im.sphere_geom_id = rtcAttachGeometry(im.top.scene, g);
  rtcReleaseGeometry(g);
  if (im.top.mesh_of_geom.size() <= im.sphere_geom_id)
    im.top.mesh_of_geom.resize(im.sphere_geom_id + 1, -1);
  for (const auto& s : spheres_) {
    bounds_.extend(s.sphere.center - Vec3(s.sphere.radius, s.sphere.radius, s.sphere.radius));
    bounds_.extend(s.sphere.center + Vec3(s.sphere.radius, s.sphere.radius, s.sphere.radius));
  }
}

// One Embree instance per placement of a prototype; the bounds are those of the transformed
// vertices, as a flattened copy would give.
void Scene::attach_instances() {
  Impl& im = *impl_;
  for (uint32_t i = 0; i < instances_.size(); ++i) {
    const SceneData::InstanceEntry& inst = instances_[i];
    if (inst.prototype >= prototypes_.size())
      throw std::runtime_error("an instance of a prototype that does not exist");
    const Transform& t = inst.object_to_world;
    im.instance_swaps_handedness.push_back(t.swaps_handedness());
    const GeometryTable& proto = im.prototypes[inst.prototype];
    if (proto.primitive_count == 0) continue;
    RTCGeometry g = rtcNewGeometry(im.device, RTC_GEOMETRY_TYPE_INSTANCE);
    rtcSetGeometryInstancedScene(g, proto.scene);
    set_instance_transform(g, t);
    rtcCommitGeometry(g);
    const unsigned id = rtcAttachGeometry(im.top.scene, g);
    rtcReleaseGeometry(g);
    if (im.top.mesh_of_geom.size() <= id) im.top.mesh_of_geom.resize(id + 1, -1);
    if (im.instance_of_geom.size() <= id) im.instance_of_geom.resize(id + 1, UINT32_MAX);
    im.instance_of_geom[id] = i;
    for (const SceneData::MeshEntry& e : prototypes_[inst.prototype].meshes)
      if (e.mesh.triangle_count() > 0)
        for (const Vec3& p : e.mesh.positions) bounds_.extend(t.point(p));
  }
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
  for (const SceneData::InstanceEntry& inst : instances_)
    for (const auto& m : prototypes_[inst.prototype].meshes) n += m.mesh.triangle_count();
  return n;
}

size_t Scene::stored_triangle_count() const {
  size_t n = 0;
  for (const auto& m : meshes_) n += m.mesh.triangle_count();
  for (const SceneData::Prototype& proto : prototypes_)
    for (const auto& m : proto.meshes) n += m.mesh.triangle_count();
  return n;
}

static size_t mesh_bytes(const std::vector<SceneData::MeshEntry>& meshes) {
  size_t n = meshes.capacity() * sizeof(SceneData::MeshEntry);
  for (const auto& e : meshes) {
    const TriangleMesh& m = e.mesh;
    n += m.positions.capacity() * sizeof(Vec3) + m.normals.capacity() * sizeof(Vec3) +
         m.uvs.capacity() * sizeof(Vec2) + m.indices.capacity() * sizeof(uint32_t);
  }
  return n;
}

size_t Scene::geometry_bytes() const {
  size_t n = mesh_bytes(meshes_) + spheres_.capacity() * sizeof(SceneData::SphereEntry) +
             instances_.capacity() * sizeof(SceneData::InstanceEntry);
  for (const SceneData::Prototype& proto : prototypes_) n += mesh_bytes(proto.meshes);
  return n + size_t(std::max<int64_t>(impl_->embree_bytes.load(), 0));
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
  Impl::RayCounts& counts = impl_->local_counts();
  ++counts.all;
  ++counts.occlusion;
  RTCIntersectContext ctx;
  rtcInitIntersectContext(&ctx);
  RTCRay r;
  fill_ray(ray, &r);
  rtcOccluded1(impl_->top.scene, &ctx, &r);
  return r.tfar < 0;
}

Rgb Scene::shadow_transmittance(Ray ray, SegmentEnd start, SegmentEnd end) const {
  const float length_d = length(ray.d);  // ray.d may be unnormalised (Ray::spawn_ray_to)
  Rgb tr(1.f);
  for (int crossing = 0; crossing < kMaxInterfaceCrossings; ++crossing) {
    SurfaceInteraction si;
    if (!intersect(ray, &si)) return tr * transmittance(start, end, ray.tmax * length_d);
    if (si.material) return Rgb(0.f);  // a surface that scatters blocks the ray
    tr *= transmittance(start, si.medium_toward(-ray.d), si.t * length_d);
    if (tr.is_black()) return tr;
    start = si.medium_toward(ray.d);
    const float remaining = ray.tmax - si.t;  // toward the same end point
    ray = si.spawn_ray(ray.d);
    ray.tmax = remaining;
  }
  return Rgb(0.f);
}

bool Scene::intersect(const Ray& ray, SurfaceInteraction* si) const {
  ++impl_->local_counts().all;
  RTCIntersectContext ctx;
  rtcInitIntersectContext(&ctx);
  RTCRayHit rh;
  fill_ray(ray, &rh.ray);
  rh.hit.geomID = RTC_INVALID_GEOMETRY_ID;
  rh.hit.instID[0] = RTC_INVALID_GEOMETRY_ID;
  rtcIntersect1(impl_->top.scene, &ctx, &rh);
  if (rh.hit.geomID == RTC_INVALID_GEOMETRY_ID) return false;

  si->t = rh.ray.tfar;
  si->wo = -normalize(ray.d);
  const uint32_t inst_id = rh.hit.instID[0];
  Vec3 p_sphere;
  if (inst_id == RTC_INVALID_GEOMETRY_ID && rh.hit.geomID == impl_->sphere_geom_id)
    p_sphere = ray.o + ray.d * si->t;
  complete_hit(inst_id == RTC_INVALID_GEOMETRY_ID ? SurfaceInteraction::kNoInstance : inst_id,
               rh.hit.geomID, rh.hit.primID, rh.hit.u, rh.hit.v, p_sphere, si);
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
    rtcIntersect1(impl_->top.scene, &ctx, &rh);
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
    rtcOccluded1(impl_->top.scene, &ctx, &r);
    occluded += r.tfar < 0;
  }
  return occluded;
}

}  // namespace caustica
