// The camera-path seam with a test double: a complete integrator is its estimate() alone. This
// one returns the emission the camera ray sees directly, through the seam's pixel loop, streams,
// filter and film, and the vertex helpers' emitter enumeration.
#include "integrators/camera_path.h"

#include <gtest/gtest.h>

#include "integrators/path_vertex.h"
#include "io/builtin_scenes.h"
#include "render/renderer.h"
#include "scene/scene.h"
#include "test_scenes.h"

using namespace caustica;

namespace {

class EmissionSeen final : public CameraPathIntegrator {
 public:
  explicit EmissionSeen(uint64_t seed) : CameraPathIntegrator(seed) {}
  const char* name() const override { return "emission-seen"; }

 protected:
  Rgb estimate(const Scene& scene, const CameraSample& sample, Pcg32&, ScratchArena&,
               uint64_t*) const override {
    Rgb L(0.f);
    SurfaceInteraction si;
    const bool hit = scene.intersect(sample.ray, &si);
    for_each_emitter_seen(scene.infinite_lights(), sample.ray, hit ? &si : nullptr,
                          [&](const Light&, Rgb Le) { L += Le; });
    return L;
  }
};

Image render_double(const Scene& scene, int spp, uint64_t seed) {
  EmissionSeen integrator(seed);
  RenderBudget budget;
  budget.spp = spp;
  RenderCallbacks cb;
  cb.quiet = true;
  return render(scene, integrator, budget, cb).image;
}

}  // namespace

TEST(CameraPathSeam, AnEstimateIsAWholeIntegrator) {
  // Inside the emitting furnace sphere every camera ray sees Le exactly.
  FurnaceParams p;
  p.emission = 1.5f;
  auto furnace = make_furnace_scene(p, 16, 12);
  const Image img = render_double(*furnace, 2, 1);
  ASSERT_EQ(img.width(), 16);
  ASSERT_EQ(img.height(), 12);
  for (const Rgb& v : img.pixels()) ASSERT_FLOAT_EQ(v.average(), 1.5f);
  // The environment furnace: the environment (1) where the ray escapes, black on the sphere.
  auto env = make_builtin_scene("env-furnace", 24, 24);
  const Image sky = render_double(*env, 1, 1);
  EXPECT_EQ(sky.at(0, 0).average(), 1.f);
  EXPECT_EQ(sky.at(12, 12).average(), 0.f);
}

TEST(CameraPathSeam, StreamsAreKeyedByPixelAndIterationNotThread) {
  auto scene = make_builtin_scene("cornell", 24, 24);
  EmissionSeen a(7), b(7);
  RenderBudget budget;
  budget.spp = 3;
  RenderCallbacks cb;
  cb.quiet = true;
  const Image one = [&] {
    tbb::global_control limit(tbb::global_control::max_allowed_parallelism, 1);
    return render(*scene, a, budget, cb).image;
  }();
  const Image two = [&] {
    tbb::global_control limit(tbb::global_control::max_allowed_parallelism, 2);
    return render(*scene, b, budget, cb).image;
  }();
  for (size_t i = 0; i < one.pixel_count(); ++i) ASSERT_TRUE(one[i] == two[i]) << i;
}
