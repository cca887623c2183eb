#include "integrators/guide_views.h"

#include "core/math.h"
#include "geometry/camera.h"
#include "guiding/guiding_field.h"
#include "scene/scene.h"

namespace caustica {

nlohmann::json guide_views(
    const Scene& scene, const std::function<const DirectionalQuadtree*(Vec3 p, int side)>& lookup) {
  const Camera& camera = scene.camera();
  nlohmann::json views = nlohmann::json::array();
  for (int j = 0; j < 3; ++j)
    for (int i = 0; i < 3; ++i) {
      const int x = camera.width() * (2 * i + 1) / 6, y = camera.height() * (2 * j + 1) / 6;
      nlohmann::json v = {{"pixel", {x, y}}};
      Ray ray = camera.generate_ray(Vec2(float(x) + 0.5f, float(y) + 0.5f), Vec2(0.5f, 0.5f));
      SurfaceInteraction si;
      // Through interfaces without a BSDF to the first surface, at most a few times.
      bool hit = false;
      for (int k = 0; k < 8 && scene.intersect(ray, &si); ++k) {
        if (si.material) {
          hit = true;
          break;
        }
        ray = si.spawn_ray(ray.d);
      }
      if (hit) {
        v["point"] = {si.p.x, si.p.y, si.p.z};
        const int side = GuidingField::side_class(face_forward(si.ng, si.wo));
        const DirectionalQuadtree* d = lookup(si.p, side);
        if (d && d->total() > 0) {
          std::vector<float> density(size_t(kViewWidth) * kViewHeight);
          for (int row = 0; row < kViewHeight; ++row)
            for (int col = 0; col < kViewWidth; ++col) {
              // The square's x is (cos theta + 1) / 2 and its y phi / 2 pi (direction_to_square):
              // drawn with phi across and cos theta up.
              const Vec2 square((float(kViewHeight - 1 - row) + 0.5f) / kViewHeight,
                                (float(col) + 0.5f) / kViewWidth);
              density[size_t(row) * kViewWidth + col] = d->pdf_square(square) * kInv4Pi;
            }
          v["density"] = density;
        }
      }
      views.push_back(v);
    }
  return {{"width", kViewWidth}, {"height", kViewHeight}, {"views", views}};
}

}  // namespace caustica
