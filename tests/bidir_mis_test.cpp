// MIS partition of unity for the bidirectional core: for random complete paths, the weights the
// renderer's partial sums (dVCM, dVC, dVM) give every technique able to make the path must sum to
// one, and each must equal the weight of a brute-force oracle that multiplies out the pdfs of
// every vertex explicitly (Veach 1997 ch. 10; Georgiev et al. 2012 eq. 7 and section 4).
#include <gtest/gtest.h>

#include <cmath>
#include <map>
#include <random>

#include "core/rng.h"
#include "geometry/texture.h"
#include "image/image.h"
#include "integrators/bidir/bidir_guiding.h"
#include "integrators/bidir/light_vertex.h"
#include "integrators/bidir/path_weights.h"
#include "integrators/bidir/techniques.h"
#include "io/builtin_scenes.h"
#include "io/scene_builder.h"
#include "lights/light.h"
#include "lights/light_sampler.h"
#include "lights/lights.h"
#include "materials/material.h"
#include "materials/materials.h"
#include "scene/scene.h"

using namespace caustica;
using namespace caustica::bidir;

namespace {

// A small open scene with the light types the Cornell boxes lack: a point light, a spot light
// and a sphere emitter (cone-sampled NEE), over a diffuse floor with a glass and a rough ball.
std::unique_ptr<Scene> mixed_lights_scene() {
  SceneBuilder b;
  TriangleMesh floor;
  floor.positions = {{-2, 0, -2}, {2, 0, -2}, {2, 0, 2}, {-2, 0, 2}};
  floor.indices = {0, 2, 1, 0, 3, 2};
  b.add_mesh(floor, make_diffuse(make_constant_texture(Rgb(0.7f, 0.6f, 0.5f))));
  TriangleMesh wall;
  wall.positions = {{-2, 0, 2}, {2, 0, 2}, {2, 3, 2}, {-2, 3, 2}};
  wall.indices = {0, 1, 2, 0, 2, 3};
  b.add_mesh(wall, make_diffuse(make_constant_texture(Rgb(0.5f, 0.7f, 0.6f))));
  DielectricParams glass;
  glass.eta = 1.5f;
  b.add_sphere({{-0.6f, 0.5f, 0.3f}, 0.5f}, make_dielectric(glass));
  ConductorParams rough;
  rough.reflectance = make_constant_texture(Rgb(0.9f, 0.7f, 0.4f));
  rough.u_roughness = rough.v_roughness = make_constant_texture(Rgb(0.3f));
  rough.remap_roughness = false;
  b.add_sphere({{0.7f, 0.4f, 0.6f}, 0.4f}, make_conductor(rough));
  AreaEmission e{Rgb(6.f, 5.f, 4.f), false};
  b.add_sphere({{0.2f, 2.2f, 0.0f}, 0.25f}, make_diffuse(make_constant_texture(Rgb(0.5f))), &e);
  b.add_light(make_point_light({-1.0f, 2.0f, -1.0f}, Rgb(3.f)));
  b.add_light(make_spot_light({1.2f, 2.4f, -0.5f}, {-0.3f, -1.f, 0.4f}, Rgb(8.f), 40.f, 10.f));
  CameraParams c;
  c.width = c.height = 32;
  c.fov_degrees = 60;
  c.camera_to_world = Transform::look_at({0, 1.5f, -4.5f}, {0, 0.6f, 0}, {0, 1, 0}).inverse();
  b.set_camera(c);
  return b.build("mis-test");
}

// The corners the Cornell boxes miss: a distant light and an image environment (importance
// sampled), a floor and a ball with interpolated shading normals that lean away from the
// geometric ones, glass, and a thin-lens camera (lens points off the centre).
std::unique_ptr<Scene> corners_scene() {
  SceneBuilder b;
  TriangleMesh floor;
  floor.positions = {{-3, 0, -3}, {3, 0, -3}, {3, 0, 3}, {-3, 0, 3}};
  floor.indices = {0, 2, 1, 0, 3, 2};
  floor.normals = {normalize(Vec3(0.3f, 1, 0.1f)), normalize(Vec3(-0.2f, 1, 0.3f)),
                   normalize(Vec3(0.1f, 1, -0.4f)), normalize(Vec3(-0.3f, 1, -0.2f))};
  b.add_mesh(floor, make_diffuse(make_constant_texture(Rgb(0.7f, 0.6f, 0.5f))));
  // A coarse octahedron ball with smooth (vertex) normals.
  TriangleMesh ball;
  const Vec3 c(0.6f, 0.5f, 0.4f);
  const Vec3 axes[6] = {{1, 0, 0}, {-1, 0, 0}, {0, 1, 0}, {0, -1, 0}, {0, 0, 1}, {0, 0, -1}};
  for (const Vec3& a : axes) {
    ball.positions.push_back(c + a * 0.45f);
    ball.normals.push_back(a);
  }
  ball.indices = {0, 2, 4, 2, 1, 4, 1, 3, 4, 3, 0, 4, 2, 0, 5, 1, 2, 5, 3, 1, 5, 0, 3, 5};
  b.add_mesh(ball, make_diffuse(make_constant_texture(Rgb(0.5f, 0.7f, 0.6f))));
  DielectricParams glass;
  glass.eta = 1.5f;
  b.add_sphere({{-0.7f, 0.5f, 0.2f}, 0.5f}, make_dielectric(glass));
  b.add_light(make_distant_light(normalize(Vec3(0.3f, -1.f, 0.5f)), Rgb(2.f, 1.8f, 1.5f)));
  auto sky = std::make_shared<Image>(16, 8);
  for (int y = 0; y < 8; ++y)
    for (int x = 0; x < 16; ++x) sky->at(x, y) = Rgb(0.2f + 0.1f * x, 0.5f, 1.5f - 0.15f * y);
  b.add_light(make_image_environment(sky, EnvironmentMapping::LatLong, Transform()));
  CameraParams cam;
  cam.width = 40;
  cam.height = 28;
  cam.fov_degrees = 55;
  cam.lens_radius = 0.15f;
  cam.focal_distance = 4.f;
  cam.camera_to_world = Transform::look_at({0, 1.5f, -4.f}, {0, 0.4f, 0}, {0, 1, 0}).inverse();
  b.set_camera(cam);
  return b.build("corners");
}

// Builds a random complete path by tracing a light subpath (Importance mode) of 1-4 surface
// vertices whose last vertex the camera sees, or (one in five) an area light's emission point
// the camera sees directly. Returns false if the walk failed.
bool random_path(const Scene& scene, Pcg32& rng, ScratchArena& arena, ExplicitPath* path) {
  float pmf;
  const Light* light = scene.light_sampler().sample(rng.next_float(), &pmf);
  const Vec2 u_pos = rng.next_2d(), u_dir = rng.next_2d();
  const auto le = light->sample_le(u_pos, u_dir);
  if (!le || !(le->pdf_pos > 0) || !(le->pdf_dir > 0)) return false;
  path->light = light;
  path->light_point = le->p;
  path->light_normal = le->n;
  path->emit_dir = le->dir;
  path->surfaces.clear();
  Vec3 o = le->p;
  if (light->type() == LightType::Area) o = o + face_forward(le->n, le->dir) * 1e-4f;
  Ray ray{o, le->dir, kInfinity};
  const int vertices = int(rng.next_bounded(5));
  if (vertices == 0) {  // the light seen from the lens
    if (light->type() != LightType::Area) return false;
    path->lens_point = scene.camera().position();
    if (!scene.camera().is_pinhole()) {
      const auto cs = scene.camera().sample_wi(le->p, rng.next_2d());
      if (!cs) return false;
      path->lens_point = cs->p_lens;
    }
    const Vec3 to_lens = normalize(path->lens_point - le->p);
    return !light->radiance(le->p, le->n, {}, to_lens).is_black() &&
           scene.camera().raster_of(path->lens_point, -to_lens).has_value() &&
           camera_pdf_w(scene.camera(), path->lens_point, -to_lens) > 0;
  }
  for (int i = 0; i < vertices; ++i) {
    SurfaceInteraction si;
    if (!scene.intersect(ray, &si) || !si.material) return false;
    const Bsdf bsdf = si.material->bsdf(si, arena);
    if (!bsdf.valid() || si.area_light) return false;  // keep emitters at the path's start only
    path->surfaces.push_back(si);
    if (i + 1 == vertices) break;
    const float uc = rng.next_float();
    const auto bs = bsdf.sample(si.wo, uc, rng.next_2d(), TransportMode::Importance);
    if (!bs) return false;
    ray = si.spawn_ray(bs->wi);
  }
  path->lens_point = scene.camera().position();
  if (!scene.camera().is_pinhole()) {  // a lens point from which the last vertex is on the film
    const auto cs = scene.camera().sample_wi(path->surfaces.back().p, rng.next_2d());
    if (!cs) return false;
    path->lens_point = cs->p_lens;
  }
  // Only paths that carry light: every non-delta vertex scatters from its predecessor toward its
  // successor (a zero BSDF there would leave the camera side unable to sample the path at all).
  for (size_t i = 0; i < path->surfaces.size(); ++i) {
    const SurfaceInteraction& si = path->surfaces[i];
    const Bsdf bsdf = si.material->bsdf(si, arena);
    if (bsdf.is_delta()) continue;
    const Vec3 next = i + 1 < path->surfaces.size() ? path->surfaces[i + 1].p : path->lens_point;
    if (bsdf.f(si.wo, normalize(next - si.p), TransportMode::Importance).is_black()) return false;
  }
  const Vec3 last = path->surfaces.back().p;
  return scene.camera()
             .raster_of(path->lens_point, normalize(last - path->lens_point))
             .has_value() &&
         camera_pdf_w(scene.camera(), path->lens_point, normalize(last - path->lens_point)) > 0;
}

struct Key {
  bool merge;
  int s, t;
  bool operator<(const Key& o) const { return std::tie(merge, s, t) < std::tie(o.merge, o.s, o.t); }
};

// The oracle: every technique's path pdf as an explicit product of area densities, in double.
// Conventions shared with the renderer (mis.h): geometric cosines, delta bounces have pdf 1 in
// both directions, no Russian roulette, n = N for light tracing, merges multiply by N pi r^2.
// connections: the count of each connection technique (s, t >= 2).
std::map<Key, double> oracle_weights(const Scene& scene, const ExplicitPath& path, bool connect,
                                     bool merge, bool power, double light_paths, double radius,
                                     ScratchArena& arena, double raster_density = 1,
                                     double connections = 1, const BidirGuiding* guiding = nullptr,
                                     double merge_scale = 1, bool correlation_aware = false) {
  const Light& light = *path.light;
  const bool finite = !light.is_infinite();
  const double pmf = scene.light_sampler().pmf(&light);
  const int k = int(path.surfaces.size()) + 1;
  std::vector<Vec3> x(k + 1);
  for (int i = 1; i < k; ++i) x[i] = path.surfaces[i - 1].p;
  x[0] = finite ? path.light_point : x[1] - path.emit_dir * 1e3f;
  x[k] = path.lens_point;
  auto dir = [&](int a, int b) { return normalize(x[b] - x[a]); };
  auto d2 = [&](int a, int b) { return double(distance_squared(x[a], x[b])); };
  auto cos_at = [&](int i, Vec3 w) {
    if (i == 0)
      return light.type() == LightType::Area ? double(abs_dot(path.light_normal, w)) : 1.0;
    return double(abs_dot(path.surfaces[i - 1].ng, w));
  };
  std::vector<Bsdf> bsdf(k);
  for (int i = 1; i < k; ++i)
    bsdf[i] = path.surfaces[i - 1].material->bsdf(path.surfaces[i - 1], arena);
  auto delta = [&](int i) { return bsdf[i].is_delta(); };
  // Guided vertices sample from mixtures (vertex_guides.h): their densities, both ways.
  auto pdf = [&](int i, Vec3 wo, Vec3 wi, TransportMode mode) {
    const VertexGuides g =
        guiding ? guiding->at(x[i], path.surfaces[i - 1].ng, bsdf[i]) : VertexGuides{};
    return double(direction_pdf(bsdf[i], g, wo, wi, mode));
  };
  // Solid angle -> area at x[to] (x0 of an infinite light stays a direction).
  auto to_area = [&](int from, int to) {
    return (to == 0 && !finite) ? 1.0 : cos_at(to, dir(to, from)) / d2(from, to);
  };
  const Vec3 emit = finite ? dir(0, 1) : path.emit_dir;

  std::vector<double> light_pdf(k), camera_pdf(k);
  float pdf_pos, pdf_dir;
  light.pdf_le(x[0], finite ? path.light_normal : path.emit_dir, emit, &pdf_pos, &pdf_dir);
  light_pdf[0] = pmf * (finite ? pdf_pos : pdf_dir);
  if (k >= 2) light_pdf[1] = finite ? pdf_dir * to_area(0, 1) : pdf_pos * cos_at(1, emit);
  for (int i = 1; i + 1 < k; ++i) {
    const Vec3 wo = i == 1 ? -emit : dir(i, i - 1);
    const double p = delta(i) ? 1.0 : pdf(i, wo, dir(i, i + 1), TransportMode::Importance);
    light_pdf[i + 1] = p * to_area(i, i + 1);
  }
  // The pixel filter's raster density scales the camera ray's pdf (techniques.h).
  camera_pdf[k - 1] =
      camera_pdf_w(scene.camera(), x[k], dir(k, k - 1)) * raster_density * to_area(k, k - 1);
  for (int i = k - 1; i >= 1; --i) {
    const Vec3 wi = i == 1 ? (finite ? dir(1, 0) : -emit) : dir(i, i - 1);
    const double p = delta(i) ? 1.0 : pdf(i, dir(i, i + 1), wi, TransportMode::Radiance);
    camera_pdf[i - 1] = p * to_area(i, i - 1);
  }
  double nee_pdf = 0;
  if (k == 1)
    ;  // no vertex to sample the light from
  else if (light.is_delta())
    nee_pdf = pmf;
  else if (finite)
    nee_pdf = pmf * light.pdf_li(x[1], dir(1, 0), x[0], path.light_normal) * to_area(1, 0);
  else
    nee_pdf = pmf * light.pdf_li(x[1], -emit, {}, {});

  auto prod = [](const std::vector<double>& v, int lo, int hi) {  // product over [lo, hi]
    double p = 1;
    for (int i = lo; i <= hi; ++i) p *= v[i];
    return p;
  };
  // The learned probability with which the vertex x_i takes technique t toward x_j (guided:
  // next event estimation, lens connections and connections; technique_probabilities.h):
  // it multiplies that technique's count.
  auto q = [&](GuidingField::Technique t, int i, Vec3 toward) {
    if (!guiding) return 1.0;
    return double(guiding->probabilities_at(x[i], path.surfaces[i - 1].ng).of(t, toward));
  };
  std::map<Key, double> p;
  if (connect && !light.is_delta()) p[{false, 0, k + 1}] = prod(camera_pdf, 0, k - 1);
  if (connect && k >= 2 && !delta(1))
    p[{false, 1, k}] = q(GuidingField::kNextEvent, 1, finite ? dir(1, 0) : -emit) * nee_pdf *
                       prod(camera_pdf, 1, k - 1);
  for (int s = 2; connect && s <= k - 1; ++s)
    if (!delta(s - 1) && !delta(s))
      p[{false, s, k + 1 - s}] = q(GuidingField::kConnection, s - 1, dir(s - 1, s)) * connections *
                                 prod(light_pdf, 0, s - 1) * prod(camera_pdf, s, k - 1);
  // t = 1; for k = 1 the emission point of an area light itself (s = 1, t = 1).
  if (connect && (k == 1 ? light.type() == LightType::Area : !delta(k - 1)))
    p[{false, k, 1}] = (k == 1 ? 1.0 : q(GuidingField::kLensConnection, k - 1, dir(k - 1, k))) *
                       light_paths * prod(light_pdf, 0, k - 1);
  // Correlation-aware MIS (Grittmann et al. 2021): the merge at x_j counts c_j times, from the
  // acceptances min(1, A p) of the area densities with which each side samples each vertex (1
  // where a delta lobe samples it, and for a delta or infinite light's position).
  std::vector<double> correlation(k, 1.0);
  if (correlation_aware) {
    const double area = kPi * radius * radius;
    auto accept = [&](double p) { return std::min(1.0, area * p); };
    std::vector<double> a_light(k), a_camera(k);
    a_light[0] = finite && !light.is_delta() ? accept(light_pdf[0]) : 1.0;
    for (int i = 1; i < k; ++i) a_light[i] = i >= 2 && delta(i - 1) ? 1.0 : accept(light_pdf[i]);
    for (int i = 0; i < k; ++i)
      a_camera[i] = i + 1 <= k - 1 && delta(i + 1) ? 1.0 : accept(camera_pdf[i]);
    for (int j = 1; j < k; ++j) {
      const double cam = prod(a_camera, j, k - 1), lit = prod(a_light, 0, j);
      const double denominator = cam + lit - cam * lit;
      correlation[j] = denominator > 0 ? std::max(cam / denominator, 1.0 / light_paths) : 1.0;
    }
  }
  for (int j = 1; merge && j <= k - 1; ++j)
    if (!delta(j))
      p[{true, j + 1, k + 1 - j}] = correlation[j] * merge_scale * light_paths * kPi * radius *
                                    radius * prod(light_pdf, 0, j) * prod(camera_pdf, j, k - 1);
  double total = 0;
  for (auto& [key, v] : p) {
    v = power ? v * v : v;
    total += v;
  }
  for (auto& [key, v] : p) v /= total;
  return p;
}

struct Case {
  const char* scene;
  BidirAlgorithm algorithm;
  MisHeuristic heuristic;
  float light_paths = 1024;  // N; the scenes have 32 x 32 pixels (corners: 40 x 28)
  int connections = 1;       // per camera vertex
  bool pixel_merges = true;  // false: a pixel of adaptive-vcm that does not merge
  bool guided = false;       // guided-bpt / guided-vcm: densities of trained guiding fields
  bool guide_camera = true, guide_light = true;  // which subpaths (--guiding-subpaths)
  float merge_scale = 1;                         // --merge-mis-scale
  bool correlation_aware = false;                // --merge-mis correlation-aware
  float radius = 0.02f;
};

// Fields of guided-bpt / guided-vcm trained on synthetic records: surface points hit by rays from
// random points of the scene's box, with arrival directions biased differently for radiance and
// importance (so that forward and reverse densities differ), and a spatial threshold low enough
// that the trees split.
std::unique_ptr<BidirGuiding> trained_guiding(const Scene& scene, bool guide_camera = true,
                                              bool guide_light = true) {
  auto g = std::make_unique<BidirGuiding>();
  GuidingSettings settings;
  settings.guide_camera_paths = guide_camera;
  settings.guide_light_paths = guide_light;
  // The fields are trained on the synthetic photons and importons below (the defaults learn
  // them from the subpaths' own vertices, which this test does not trace).
  settings.radiance_records = GuidingSettings::RadianceRecords::Photons;
  settings.importance_records = GuidingSettings::ImportanceRecords::Importons;
  settings.spatial_threshold = 200;
  settings.bsdf_fraction = 0.3f;
  g->prepare(scene.bounds(), settings, 6000, 0, 0);  // no budget: it trains forever; 6000 pixels
  const InverseVarianceCombiner no_variances;
  std::mt19937 gen(5);
  std::uniform_real_distribution<float> u(0.f, 1.f);
  const Bounds3 b = scene.bounds();
  auto hit = [&](Vec3 bias, SurfaceInteraction* si) {
    const Vec3 d = b.diagonal();
    const Vec3 o = b.lo + Vec3(u(gen) * d.x, u(gen) * d.y, u(gen) * d.z);
    const Vec3 dir = normalize(bias + Vec3(u(gen), u(gen), u(gen)) * 2.f - Vec3(1, 1, 1));
    Ray ray{o, dir, kInfinity};
    return scene.intersect(ray, si);
  };
  for (int pass = 0; pass < 3; ++pass) {
    const uint32_t first = pass == 0 ? 0 : 1u << pass;  // passes 0-1, 2-3, 4-7
    g->begin_iteration(first, 0.0);
    std::vector<LightVertex> photons;
    for (int i = 0; i < 6000; ++i) {
      SurfaceInteraction si;
      if (hit(Vec3(0, -0.8f, 0), &si))
        photons.push_back(pack_light_vertex(
            {si.p, si.wo, scene.primitive_index(si), 1, Rgb(0.1f + u(gen)), MisSums{}}));
      if (hit(Vec3(0.7f, 0, 0), &si))
        g->record_camera_vertex(uint64_t(i), 1, si.p, si.ng, si.wo, Rgb(0.1f + u(gen)));
    }
    // Technique counts per radiance leaf (technique_probabilities.h): one leaf in four saw
    // something, the others took enough samples and saw nothing, so that probabilities below
    // 1 (the floor) and of 1 both enter the weights, differently per technique.
    const uint32_t leaves = uint32_t(g->radiance().leaf_count());
    for (uint32_t leaf = 0; leaf < leaves; ++leaf)
      for (int t = 0; t < GuidingField::kTechniques; ++t)
        for (uint32_t j = 0; j < GuidingField::kNeeEvidence; ++j)
          g->count_technique(GuidingField::Technique(t), leaf,
                             (leaf * 3 + uint32_t(t)) % 4 == 0 && j % 2 == 0);
    g->end_iteration(scene, photons);
    // Ends the pass (as after its last iteration, 1, 3 or 7): what it learned is sampled next.
    EXPECT_TRUE(g->end_pass_after(first == 0 ? 1 : 2 * first - 1, 0.0, no_variances));
  }
  return g;
}

// With filter_densities, each path is weighted for a pixel whose filter has a random raster
// density (0.01 to 4) at the path's raster point, as non-box pixel filters give.
void check_partition_of_unity(const Scene& scene, const Case& c, int paths,
                              bool filter_densities = false) {
  Pcg32 rng(7, 11);
  ScratchArena arena;
  const std::unique_ptr<BidirGuiding> guiding =
      c.guided ? trained_guiding(scene, c.guide_camera, c.guide_light) : nullptr;
  int guided_vertices = 0, reduced_vertices = 0;
  const float light_paths = c.light_paths, radius = c.radius;
  const bool connect = c.algorithm != BidirAlgorithm::Bpm,
             merge = c.algorithm != BidirAlgorithm::Bpt &&
                     c.algorithm != BidirAlgorithm::GuidedBpt && c.pixel_merges;
  int checked = 0, attempts = 0, with_delta = 0, seen_directly = 0;
  double worst_sum = 0, worst_oracle = 0;
  int stop_compared = 0;            // techniques whose photon-mapping density was compared
  double moved_by_correlation = 0;  // the largest change of a weight by correlation-aware MIS
  ExplicitPath path;
  while (checked < paths && attempts < 50 * paths) {
    ++attempts;
    arena.reset();
    if (!random_path(scene, rng, arena, &path)) continue;
    const float density = filter_densities ? 0.01f + 3.99f * rng.next_float() : 1.f;
    const auto weights = production_weights(scene, c.algorithm, c.heuristic, light_paths, radius,
                                            path, arena, density, c.connections, c.pixel_merges,
                                            guiding.get(), c.merge_scale, c.correlation_aware);
    const auto oracle = oracle_weights(
        scene, path, connect, merge, c.heuristic == MisHeuristic::Power, light_paths, radius, arena,
        density, c.connections, guiding.get(), c.merge_scale, c.correlation_aware);
    if (oracle.empty() || !std::isfinite(oracle.begin()->second))
      continue;                 // no technique can make it
    if (c.correlation_aware) {  // the correlation must matter, or the case proves nothing
      const auto balance = oracle_weights(
          scene, path, connect, merge, c.heuristic == MisHeuristic::Power, light_paths, radius,
          arena, density, c.connections, guiding.get(), c.merge_scale, false);
      for (const auto& [key, w] : oracle)
        moved_by_correlation = std::max(moved_by_correlation, std::abs(w - balance.at(key)));
    }
    double sum = 0;
    for (const auto& w : weights) {
      sum += w.weight;
      const auto it = oracle.find({w.merge, w.s, w.t});
      ASSERT_NE(it, oracle.end()) << c.scene << ": production technique the oracle lacks: merge "
                                  << w.merge << " s " << w.s << " t " << w.t;
      worst_oracle = std::max(worst_oracle, std::abs(double(w.weight) - it->second));
      EXPECT_NEAR(w.weight, it->second, 1e-3)
          << c.scene << " merge " << w.merge << " s " << w.s << " t " << w.t << " k "
          << path.surfaces.size() + 1 << " path " << checked;
    }
    ASSERT_EQ(weights.size(), oracle.size()) << c.scene;
    worst_sum = std::max(worst_sum, std::abs(sum - 1));
    // adaptive-vcm's per-pixel photon mapping (PixelMode::Stop): exactly one technique makes
    // the path there, and every technique's terms give the same density of it relative to
    // theirs (the proxy correction of its variance; checked where a technique's weight is not
    // negligible, so its terms are not dominated by rounding).
    if (connect && merge) {
      double stop_sum = 0, reference = 0, heaviest = 0;
      for (const auto& w : weights) {
        stop_sum += w.stop_weight;
        if (w.weight > heaviest) {
          heaviest = w.weight;
          reference = w.stop_ratio;
        }
      }
      ASSERT_NEAR(stop_sum, 1.0, 1e-6) << c.scene << " path " << checked;
      for (const auto& w : weights) {
        if (!(w.weight > 1e-3)) continue;
        EXPECT_NEAR(w.stop_ratio, reference, 2e-3 * reference + 1e-12)
            << c.scene << " merge " << w.merge << " s " << w.s << " t " << w.t << " path "
            << checked;
        stop_compared += &w != &weights.front() || weights.size() > 1;
      }
    }
    seen_directly += path.surfaces.empty();
    for (const SurfaceInteraction& si : path.surfaces)
      if (si.material->bsdf(si, arena).is_delta()) {
        ++with_delta;
        break;
      }
    if (guiding) {
      for (const SurfaceInteraction& si : path.surfaces) {
        const VertexGuides g = guiding->at(si.p, si.ng, si.material->bsdf(si, arena));
        const bool radiance = g.guide(TransportMode::Radiance, si.wo) != nullptr;
        const bool importance = g.guide(TransportMode::Importance, si.wo) != nullptr;
        EXPECT_TRUE(c.guide_camera || !radiance) << "an unguided camera side has a guide";
        EXPECT_TRUE(c.guide_light || !importance) << "an unguided light side has a guide";
        guided_vertices += (radiance || !c.guide_camera) && (importance || !c.guide_light);
        const VertexProbabilities q = guiding->probabilities_at(si.p, si.ng);
        reduced_vertices += q.of(GuidingField::kNextEvent, si.wo) < 1 ||
                            q.of(GuidingField::kConnection, si.wo) < 1 ||
                            q.of(GuidingField::kLensConnection, si.wo) < 1;
      }
    }
    ASSERT_NEAR(sum, 1.0, 1e-4) << c.scene << " path " << checked << " with " << weights.size()
                                << " techniques";
    ++checked;
  }
  EXPECT_EQ(checked, paths) << c.scene << ": could not build enough paths";
  if (connect && merge) {
    EXPECT_GT(stop_compared, paths) << c.scene;
  }
  // Area lights seen straight from the lens (s = 0 against s = 1, t = 1) are among the paths.
  bool area_lights = false;
  for (const Light* l : scene.lights()) area_lights |= l->type() == LightType::Area;
  if (area_lights && connect) {
    EXPECT_GT(seen_directly, paths / 50) << c.scene;
  }
  // The guided cases must exercise guided densities: on average a guided vertex per two paths.
  if (guiding) {
    EXPECT_GT(2 * guided_vertices, paths) << c.scene;
    // ... and learned technique probabilities below 1: on average one vertex in four paths.
    EXPECT_GT(4 * reduced_vertices, paths) << c.scene;
  }
  if (c.correlation_aware) {
    EXPECT_GT(moved_by_correlation, 0.02) << c.scene;
  }
  std::printf(
      "[ partition ] %-14s %d paths (%d through delta vertices, %d lights seen directly), max "
      "|sum - 1| = %.2e, max |w - oracle| = %.2e%s\n",
      c.scene, checked, with_delta, seen_directly, worst_sum, worst_oracle,
      c.correlation_aware
          ? (", correlation moved a weight by " + std::to_string(moved_by_correlation)).c_str()
          : "");
}

std::unique_ptr<Scene> scene_named(const std::string& name) {
  if (name == "mixed-lights") return mixed_lights_scene();
  if (name == "corners") return corners_scene();
  return make_builtin_scene(name, 32, 32);
}

}  // namespace

class BidirMisPartition : public ::testing::TestWithParam<Case> {};

TEST_P(BidirMisPartition, WeightsSumToOneAndMatchBruteForce) {
  const Case c = GetParam();
  auto scene = scene_named(c.scene);
  check_partition_of_unity(*scene, c, 10000);
}

INSTANTIATE_TEST_SUITE_P(
    Bidir, BidirMisPartition,
    ::testing::Values(
        Case{"cornell", BidirAlgorithm::Vcm, MisHeuristic::Balance},
        Case{"cornell-glass", BidirAlgorithm::Vcm, MisHeuristic::Balance},
        Case{"cornell-glass", BidirAlgorithm::Vcm, MisHeuristic::Power},
        Case{"cornell-glass", BidirAlgorithm::Bpt, MisHeuristic::Balance},
        Case{"cornell-glass", BidirAlgorithm::Bpm, MisHeuristic::Balance},
        Case{"mixed-lights", BidirAlgorithm::Vcm, MisHeuristic::Balance},
        Case{"env-furnace", BidirAlgorithm::Vcm, MisHeuristic::Power},
        Case{"cornell", BidirAlgorithm::Vcm, MisHeuristic::Balance, 300},
        Case{"corners", BidirAlgorithm::Vcm, MisHeuristic::Balance, 700},
        Case{"corners", BidirAlgorithm::Vcm, MisHeuristic::Power, 5000},
        Case{"corners", BidirAlgorithm::Bpt, MisHeuristic::Balance, 700},
        // adaptive-vcm's counts: several connections per camera vertex, fewer
        // or more light paths than pixels, pixels that do not merge.
        Case{"cornell-glass", BidirAlgorithm::Vcm, MisHeuristic::Balance, 256, 4},
        Case{"corners", BidirAlgorithm::Vcm, MisHeuristic::Balance, 2240, 2, false},
        Case{"mixed-lights", BidirAlgorithm::Vcm, MisHeuristic::Power, 512, 8},
        Case{"cornell-glass", BidirAlgorithm::Bpt, MisHeuristic::Balance, 2048, 2, false},
        // guided-vcm / guided-bpt: guided densities forward and reverse.
        Case{"cornell", BidirAlgorithm::GuidedVcm, MisHeuristic::Balance, 1024, 1, true, true},
        Case{"mixed-lights", BidirAlgorithm::GuidedVcm, MisHeuristic::Power, 1024, 1, true, true},
        Case{"corners", BidirAlgorithm::GuidedBpt, MisHeuristic::Balance, 700, 2, true, true},
        // --guiding-subpaths camera / light: one side guided, the other the BSDF's alone.
        Case{"cornell", BidirAlgorithm::GuidedVcm, MisHeuristic::Balance, 1024, 1, true, true, true,
             false},
        Case{"corners", BidirAlgorithm::GuidedVcm, MisHeuristic::Balance, 700, 1, true, true, false,
             true},
        // --merge-mis-scale: the merges' count scaled in the weights (renderer and oracle).
        Case{"cornell-glass", BidirAlgorithm::Vcm, MisHeuristic::Balance, 1024, 1, true, false,
             true, true, 0.25f},
        Case{"corners", BidirAlgorithm::Vcm, MisHeuristic::Power, 700, 2, true, false, true, true,
             4.f},
        Case{"cornell", BidirAlgorithm::GuidedVcm, MisHeuristic::Balance, 1024, 1, true, true, true,
             true, 0.5f},
        // --merge-mis correlation-aware: each merge's count times c_j (renderer and oracle),
        // with radii whose acceptances lie well below 1, around it, and at 1 for the first hits.
        Case{"cornell", BidirAlgorithm::Vcm, MisHeuristic::Balance, 1024, 1, true, false, true,
             true, 1.f, true},
        Case{"cornell-glass", BidirAlgorithm::Vcm, MisHeuristic::Power, 1024, 1, true, false, true,
             true, 1.f, true, 0.2f},
        Case{"mixed-lights", BidirAlgorithm::Vcm, MisHeuristic::Balance, 1024, 1, true, false, true,
             true, 1.f, true, 0.1f},
        Case{"env-furnace", BidirAlgorithm::Vcm, MisHeuristic::Balance, 1024, 1, true, false, true,
             true, 1.f, true, 0.5f},
        Case{"corners", BidirAlgorithm::Vcm, MisHeuristic::Balance, 700, 1, true, false, true, true,
             1.f, true, 0.05f}),
    [](const auto& info) {
      std::string n =
          std::string(info.param.scene) + "_" + std::to_string(int(info.param.algorithm)) + "_" +
          (info.param.heuristic == MisHeuristic::Power ? "power" : "balance") + "_N" +
          std::to_string(int(info.param.light_paths)) + "_c" +
          std::to_string(info.param.connections) + (info.param.pixel_merges ? "" : "_nomerge") +
          (info.param.guided ? "_guided" : "") + (info.param.guide_light ? "" : "_camera") +
          (info.param.guide_camera ? "" : "_light") +
          (info.param.merge_scale == 1
               ? ""
               : "_mergescale" + std::to_string(int(100 * info.param.merge_scale))) +
          (info.param.correlation_aware
               ? "_correlated_r" + std::to_string(int(1000 * info.param.radius))
               : "");
      for (char& ch : n)
        if (ch == '-') ch = '_';
      return n;
    });

// Pixel filters other than the box give the camera technique a raster density other than 1
// (render/pixel_filter.h); the renderer's weights must still sum to one and match the oracle.
TEST(BidirMisPartition, WeightsWithPixelFilterDensitiesSumToOneAndMatchBruteForce) {
  auto scene = scene_named("cornell-glass");
  check_partition_of_unity(*scene, {"cornell-glass", BidirAlgorithm::Vcm, MisHeuristic::Balance},
                           3000, true);
  check_partition_of_unity(*scene, {"cornell-glass", BidirAlgorithm::Bpt, MisHeuristic::Power},
                           3000, true);
}

TEST(BidirLightVertex, PackingRoundTrips) {
  std::mt19937 gen(3);
  std::uniform_real_distribution<float> u(0, 1);
  for (int i = 0; i < 1000; ++i) {
    LightVertexData v;
    v.p = {-1 + 5 * u(gen), -2 + 7 * u(gen), -3 + 9 * u(gen)};
    v.wo = normalize(Vec3(u(gen) - 0.5f, u(gen) - 0.5f, u(gen) - 0.5f));
    v.primitive = uint32_t(gen());
    v.depth = int(gen() % 200);
    v.throughput = Rgb(u(gen), u(gen), u(gen)) * std::ldexp(1.f, int(gen() % 60) - 30);
    v.mis = {std::ldexp(u(gen), int(gen() % 80) - 40), std::ldexp(u(gen), int(gen() % 80) - 40),
             u(gen), std::ldexp(u(gen), int(gen() % 80) - 40), v.depth == 1};
    const LightVertexData r = unpack_light_vertex(pack_light_vertex(v));
    EXPECT_EQ(r.p, v.p);                    // exact: merging must not depend on the scene's extent
    EXPECT_LT(length(r.wo - v.wo), 2e-4f);  // angle in radians, to first order
    EXPECT_EQ(r.primitive, v.primitive);
    EXPECT_EQ(r.depth, v.depth);
    const float m = v.throughput.max_component();
    for (int c = 0; c < 3; ++c)
      EXPECT_NEAR(r.throughput[c], v.throughput[c], m * 0x1p-16f);  // half a step of 16 bits
    // 24-bit floats: 16 significant bits, rounded.
    EXPECT_NEAR(r.mis.vcm, v.mis.vcm, v.mis.vcm * 0x1p-16f);
    EXPECT_NEAR(r.mis.rest, v.mis.rest, v.mis.rest * 0x1p-16f);
    EXPECT_NEAR(r.mis.conn, v.mis.conn, v.mis.conn * 0x1p-16f);
    EXPECT_NEAR(r.mis.merge, v.mis.merge, v.mis.merge * 0x1p-16f);
    EXPECT_EQ(r.mis.first, v.depth == 1);
  }
}
