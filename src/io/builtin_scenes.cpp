#include "io/builtin_scenes.h"

#include <cmath>

#include "io/scene_builder.h"
#include "lights/lights.h"
#include "materials/materials.h"

namespace caustica {

namespace {

TriangleMesh mesh_from(std::initializer_list<float> p) {
  TriangleMesh m;
  const auto* v = p.begin();
  for (size_t i = 0; i + 2 < p.size(); i += 3) m.positions.emplace_back(v[i], v[i + 1], v[i + 2]);
  for (uint32_t i = 0; i < m.positions.size(); ++i) m.indices.push_back(i);
  return m;
}

MaterialPtr diffuse(Rgb c) { return make_diffuse(make_constant_texture(c)); }

// The camera of scenes/cornell-caustics.pbrt: `Scale -1 1 1` then LookAt, fov 45.
CameraParams cornell_camera(int w, int h) {
  CameraParams c;
  const Transform world_to_camera =
      Transform::scale({-1, 1, 1}) * Transform::look_at({-0.0439815f, -4.12529f, 0.222539f},
                                                        {-0.0370952f, -3.12678f, 0.168323f},
                                                        {0.000373896f, 0.0542148f, 0.998529f});
  c.camera_to_world = world_to_camera.inverse();
  c.width = w > 0 ? w : 512;
  c.height = h > 0 ? h : 512;
  c.fov_degrees = 45;
  return c;
}

// The box of cornell-caustics.pbrt: white floor/ceiling/back, green left, red right, and the
// light box on the ceiling with its one-sided emitting quad facing down (L = 25.0333).
void add_cornell_box(SceneBuilder& b) {
  const Rgb white(0.803922f), green(0.156863f, 0.803922f, 0.172549f),
      red(0.803922f, 0.152941f, 0.152941f);
  b.add_mesh(mesh_from({-1.27029f, 1.30455f,  -1.28002f, -1.27029f, -1.25549f, -1.28002f, 1.28975f,
                        -1.25549f, -1.28002f, 1.28975f,  -1.25549f, -1.28002f, 1.28975f,  1.30455f,
                        -1.28002f, -1.27029f, 1.30455f,  -1.28002f, -1.27029f, 1.30455f,  -1.28002f,
                        1.28975f,  1.30455f,  -1.28002f, 1.28975f,  1.30455f,  1.28002f,  1.28975f,
                        1.30455f,  1.28002f,  -1.27029f, 1.30455f,  1.28002f,  -1.27029f, 1.30455f,
                        -1.28002f, 1.28975f,  1.30455f,  1.28002f,  1.28975f,  -1.25549f, 1.28002f,
                        -1.27029f, -1.25549f, 1.28002f,  -1.27029f, -1.25549f, 1.28002f,  -1.27029f,
                        1.30455f,  1.28002f,  1.28975f,  1.30455f,  1.28002f}),
             diffuse(white));
  b.add_mesh(mesh_from({-1.27029f, 1.30455f, 1.28002f, -1.27029f, -1.25549f, 1.28002f, -1.27029f,
                        -1.25549f, -1.28002f, -1.27029f, -1.25549f, -1.28002f, -1.27029f, 1.30455f,
                        -1.28002f, -1.27029f, 1.30455f, 1.28002f}),
             diffuse(green));
  b.add_mesh(mesh_from({1.28975f, 1.30455f, -1.28002f, 1.28975f, -1.25549f, -1.28002f, 1.28975f,
                        -1.25549f, 1.28002f, 1.28975f, -1.25549f, 1.28002f, 1.28975f, 1.30455f,
                        1.28002f, 1.28975f, 1.30455f, -1.28002f}),
             diffuse(red));
  b.add_mesh(
      mesh_from({-0.25f, 0.25f,  1.26002f, 0.25f,  0.25f,  1.28002f, 0.25f,  0.25f,  1.26002f,
                 0.25f,  0.25f,  1.28002f, -0.25f, 0.25f,  1.26002f, -0.25f, 0.25f,  1.28002f,
                 -0.25f, 0.25f,  1.28002f, -0.25f, -0.25f, 1.26002f, -0.25f, -0.25f, 1.28002f,
                 -0.25f, -0.25f, 1.26002f, -0.25f, 0.25f,  1.28002f, -0.25f, 0.25f,  1.26002f,
                 0.25f,  0.25f,  1.26002f, 0.25f,  -0.25f, 1.28002f, 0.25f,  -0.25f, 1.26002f,
                 0.25f,  -0.25f, 1.28002f, 0.25f,  0.25f,  1.26002f, 0.25f,  0.25f,  1.28002f,
                 -0.25f, -0.25f, 1.26002f, 0.25f,  -0.25f, 1.26002f, 0.25f,  -0.25f, 1.28002f,
                 0.25f,  -0.25f, 1.28002f, -0.25f, -0.25f, 1.28002f, -0.25f, -0.25f, 1.26002f}),
      diffuse(white));
  const AreaEmission light{Rgb(25.0333f), false};
  b.add_mesh(mesh_from({-0.25f, 0.25f, 1.26002f, 0.25f, -0.25f, 1.26002f, -0.25f, -0.25f, 1.26002f,
                        0.25f, -0.25f, 1.26002f, -0.25f, 0.25f, 1.26002f, 0.25f, 0.25f, 1.26002f}),
             diffuse(Rgb(0.f)), &light);
}

constexpr Vec3 kLeftSphere(-0.53885f, 0.02453f, -0.78002f),
    kRightSphere(0.55831f, 0.02453f, -0.78002f);

void finish_cornell(SceneBuilder& b, int w, int h) {
  b.set_camera(cornell_camera(w, h));
  b.settings().spp = 64;
  b.settings().max_depth = 10;
}

std::unique_ptr<Scene> cornell(int w, int h) {
  SceneBuilder b;
  add_cornell_box(b);
  b.add_sphere({kLeftSphere, 0.5f}, diffuse(Rgb(0.803922f)));
  b.add_sphere({kRightSphere, 0.5f}, diffuse(Rgb(0.803922f)));
  finish_cornell(b, w, h);
  return b.build("cornell");
}

std::unique_ptr<Scene> cornell_glass(int w, int h) {
  SceneBuilder b;
  add_cornell_box(b);
  b.add_sphere({kLeftSphere, 0.5f}, make_mirror(Rgb(1.f)));
  DielectricParams glass;
  glass.eta = 1.6f;
  b.add_sphere({kRightSphere, 0.5f}, make_dielectric(glass));
  finish_cornell(b, w, h);
  return b.build("cornell-glass");
}

// Cornell box with two rough metal spheres: glossy transport without delta paths, so every
// integrator (including light tracing and photon mapping) must converge to the same image.
std::unique_ptr<Scene> cornell_glossy(int w, int h) {
  SceneBuilder b;
  add_cornell_box(b);
  ConductorParams gold;
  gold.reflectance = make_constant_texture(Rgb(0.9f, 0.7f, 0.3f));
  gold.u_roughness = gold.v_roughness = make_constant_texture(Rgb(0.3f));
  gold.remap_roughness = false;
  b.add_sphere({kLeftSphere, 0.5f}, make_conductor(gold));
  ConductorParams steel = gold;
  steel.reflectance = make_constant_texture(Rgb(0.8f));
  steel.u_roughness = steel.v_roughness = make_constant_texture(Rgb(0.1f));
  b.add_sphere({kRightSphere, 0.5f}, make_conductor(steel));
  finish_cornell(b, w, h);
  return b.build("cornell-glossy");
}

// Cornell box with absorbing media and no delta paths, so every integrator must converge to the
// same image: on the left a ball of coloured absorbing medium bounded by an interface (no
// material, geometry/medium.h), on the right a diffuse ball inside a larger ball of another
// medium. Light paths, camera paths, shadow rays, connections and merges all cross both.
std::unique_ptr<Scene> cornell_absorbing(int w, int h) {
  SceneBuilder b;
  add_cornell_box(b);
  const int16_t blue = b.add_medium({Rgb(3.0f, 1.2f, 0.3f)}),
                amber = b.add_medium({Rgb(0.4f, 1.0f, 2.5f)});
  b.add_sphere({kLeftSphere, 0.5f}, nullptr, nullptr, {blue, kNoMedium});
  b.add_sphere({kRightSphere, 0.5f}, nullptr, nullptr, {amber, kNoMedium});
  b.add_sphere({kRightSphere, 0.3f}, diffuse(Rgb(0.803922f)));
  finish_cornell(b, w, h);
  return b.build("cornell-absorbing");
}

// A Cornell box whose floor is covered by a displaced height field of about a million
// triangles, with the glass sphere resting on it: enough geometry that BVH traversal, not
// shading, dominates a ray's cost (`caustica bench`). Deterministic: the heights are a fixed sum
// of sines, no random numbers.
std::unique_ptr<Scene> many_triangles(int w, int h) {
  SceneBuilder b;
  add_cornell_box(b);
  constexpr int kQuads = 708;  // 2 * 708^2 = 1,002,528 triangles
  constexpr float x0 = -1.27029f, x1 = 1.28975f, y0 = -1.25549f, y1 = 1.30455f, floor = -1.28002f;
  TriangleMesh field;
  field.positions.reserve(size_t(kQuads + 1) * (kQuads + 1));
  for (int j = 0; j <= kQuads; ++j)
    for (int i = 0; i <= kQuads; ++i) {
      const float x = x0 + (x1 - x0) * float(i) / kQuads, y = y0 + (y1 - y0) * float(j) / kQuads;
      // Dunes plus a fine ripple (period ~ 8 quads) so that neighbouring triangles differ.
      const float dunes = 0.5f + 0.5f * std::sin(4.1f * x + 1.3f) * std::cos(3.7f * y - 0.4f);
      const float ripple = 0.5f + 0.5f * std::sin(170.f * x + 40.f * y);
      field.positions.emplace_back(x, y, floor + 0.01f + 0.18f * dunes + 0.012f * ripple);
    }
  field.indices.reserve(size_t(kQuads) * kQuads * 6);
  for (int j = 0; j < kQuads; ++j)
    for (int i = 0; i < kQuads; ++i) {
      const uint32_t a = uint32_t(j * (kQuads + 1) + i), c = a + kQuads + 1;
      field.indices.insert(field.indices.end(), {a, a + 1, c + 1, a, c + 1, c});
    }
  b.add_mesh(std::move(field), diffuse(Rgb(0.75f, 0.65f, 0.45f)));
  DielectricParams glass;
  glass.eta = 1.6f;
  b.add_sphere({kRightSphere + Vec3(0, 0, 0.15f), 0.5f}, make_dielectric(glass));
  finish_cornell(b, w, h);
  return b.build("many-triangles");
}

// The camera at the origin looking down +y, inside whatever surrounds it.
CameraParams origin_camera(int w, int h, float fov) {
  CameraParams c;
  c.camera_to_world = Transform::look_at({0, 0, 0}, {0, 1, 0}, {0, 0, 1}).inverse();
  c.width = w;
  c.height = h;
  c.fov_degrees = fov;
  return c;
}

std::unique_ptr<Scene> env_furnace(int w, int h) {
  SceneBuilder b;
  b.add_sphere({{0, 3, 0}, 1.f}, diffuse(Rgb(1.f)));
  b.add_light(make_uniform_environment(Rgb(1.f)));
  b.set_camera(origin_camera(w > 0 ? w : 32, h > 0 ? h : 32, 40));
  b.settings().spp = 64;
  b.settings().max_depth = 100;
  return b.build("env-furnace");
}

}  // namespace

std::unique_ptr<Scene> make_furnace_scene(const FurnaceParams& params, int w, int h) {
  SceneBuilder b;
  // A closed sphere seen from inside: its normals face inward (ReverseOrientation), so the
  // one-sided emitter radiates into the sphere.
  Sphere s{{0, 0, 0}, 1.f, true};
  const AreaEmission e{Rgb(params.emission), false};
  b.add_sphere(s, diffuse(Rgb(params.albedo)), &e);
  b.set_camera(origin_camera(w, h, 60));
  b.settings().spp = 64;
  b.settings().max_depth = 1000;
  return b.build("furnace");
}

std::vector<BuiltinSceneInfo> builtin_scenes() {
  return {
      {"cornell-glass",
       "the default: Cornell box with a mirror and a glass sphere (= cornell-caustics.pbrt)"},
      {"cornell", "Cornell box, diffuse only, area light"},
      {"cornell-glossy", "Cornell box with two rough metal spheres (no delta paths)"},
      {"cornell-absorbing",
       "Cornell box with two balls of absorbing medium, one around a diffuse ball (no delta "
       "paths)"},
      {"furnace",
       "camera inside a closed diffuse sphere, albedo 0.5, emitting 1: radiance is exactly 2"},
      {"many-triangles", "Cornell box, floor a 1,002,528-triangle height field, glass sphere"},
      {"env-furnace",
       "albedo-1 diffuse sphere under a uniform environment of radiance 1: every pixel is 1"},
  };
}

std::unique_ptr<Scene> make_builtin_scene(const std::string& name, int w, int h) {
  if (name == "cornell-glass") return cornell_glass(w, h);
  if (name == "cornell") return cornell(w, h);
  if (name == "cornell-glossy") return cornell_glossy(w, h);
  if (name == "cornell-absorbing") return cornell_absorbing(w, h);
  if (name == "furnace") return make_furnace_scene(FurnaceParams{}, w > 0 ? w : 32, h > 0 ? h : 32);
  if (name == "env-furnace") return env_furnace(w, h);
  if (name == "many-triangles") return many_triangles(w, h);
  return nullptr;
}

}  // namespace caustica
