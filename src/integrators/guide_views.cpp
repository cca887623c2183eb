#include "integrators/guide_views.h"

#include <algorithm>
#include <cmath>
#include <string>

#include "core/math.h"
#include "geometry/camera.h"
#include "guiding/guiding_field.h"
#include "scene/scene.h"

namespace caustica {

namespace {

// The distribution learned at the first surface the central ray of pixel (x, y) hits (through
// interfaces without a BSDF, at most a few), and that point; nullptr where the ray misses or
// nothing was learned.
const DirectionalQuadtree* learned_at_pixel(const Scene& scene, const GuideLookup& lookup, int x,
                                            int y, Vec3* point, bool* hit) {
  Ray ray = scene.camera().generate_ray(Vec2(float(x) + 0.5f, float(y) + 0.5f), Vec2(0.5f, 0.5f));
  SurfaceInteraction si;
  *hit = false;
  for (int k = 0; k < 8 && scene.intersect(ray, &si); ++k) {
    if (si.material) {
      *hit = true;
      break;
    }
    ray = si.spawn_ray(ray.d);
  }
  if (!*hit) return nullptr;
  *point = si.p;
  const DirectionalQuadtree* d = lookup(si.p, GuidingField::side_class(face_forward(si.ng, si.wo)));
  return d && d->total() > 0 ? d : nullptr;
}

// The solid-angle density over the view's cells: the square's x is (cos theta + 1) / 2 and its
// y phi / 2 pi (direction_to_square), drawn with phi across and cos theta up.
std::vector<float> density_cells(const DirectionalQuadtree& d) {
  std::vector<float> density(size_t(kViewWidth) * kViewHeight);
  for (int row = 0; row < kViewHeight; ++row)
    for (int col = 0; col < kViewWidth; ++col) {
      const Vec2 square((float(kViewHeight - 1 - row) + 0.5f) / kViewHeight,
                        (float(col) + 0.5f) / kViewWidth);
      density[size_t(row) * kViewWidth + col] = d.pdf_square(square) * kInv4Pi;
    }
  return density;
}

// The cells as the report draws them, one byte each (255 sqrt(density / the view's largest)),
// in base64: a few hundred characters per view.
std::string grey_base64(const std::vector<float>& density) {
  float peak = 0;
  for (float v : density) peak = std::max(peak, v);
  std::string bytes(density.size(), '\0');
  for (size_t i = 0; i < density.size(); ++i)
    bytes[i] =
        char(peak > 0 ? int(std::lround(255 * std::sqrt(std::max(0.f, density[i]) / peak))) : 0);
  static constexpr char kDigits[] =
      "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
  std::string out;
  for (size_t i = 0; i < bytes.size(); i += 3) {
    uint32_t v = uint32_t(uint8_t(bytes[i])) << 16;
    if (i + 1 < bytes.size()) v |= uint32_t(uint8_t(bytes[i + 1])) << 8;
    if (i + 2 < bytes.size()) v |= uint32_t(uint8_t(bytes[i + 2]));
    out += kDigits[(v >> 18) & 63];
    out += kDigits[(v >> 12) & 63];
    out += i + 1 < bytes.size() ? kDigits[(v >> 6) & 63] : '=';
    out += i + 2 < bytes.size() ? kDigits[v & 63] : '=';
  }
  return out;
}

}  // namespace

nlohmann::json guide_views(const Scene& scene, const GuideLookup& lookup) {
  const Camera& camera = scene.camera();
  nlohmann::json views = nlohmann::json::array();
  for (int j = 0; j < 3; ++j)
    for (int i = 0; i < 3; ++i) {
      const int x = camera.width() * (2 * i + 1) / 6, y = camera.height() * (2 * j + 1) / 6;
      nlohmann::json v = {{"pixel", {x, y}}};
      Vec3 p;
      bool hit;
      const DirectionalQuadtree* d = learned_at_pixel(scene, lookup, x, y, &p, &hit);
      if (hit) v["point"] = {p.x, p.y, p.z};
      if (d) v["density"] = density_cells(*d);
      views.push_back(v);
    }
  // The grid the report's click shows: kClickColumns across, rows for square cells.
  const int columns = std::min(kClickColumns, camera.width());
  const int rows = std::clamp(int(std::lround(double(columns) * camera.height() / camera.width())),
                              1, camera.height());
  nlohmann::json cells = nlohmann::json::array();
  for (int r = 0; r < rows; ++r)
    for (int c = 0; c < columns; ++c) {
      const int x = int((int64_t(2 * c + 1) * camera.width()) / (2 * columns));
      const int y = int((int64_t(2 * r + 1) * camera.height()) / (2 * rows));
      Vec3 p;
      bool hit;
      const DirectionalQuadtree* d = learned_at_pixel(scene, lookup, x, y, &p, &hit);
      cells.push_back(d ? grey_base64(density_cells(*d)) : std::string());
    }
  return {{"width", kViewWidth},
          {"height", kViewHeight},
          {"views", views},
          {"grid", {{"columns", columns}, {"rows", rows}, {"cells", cells}}}};
}

}  // namespace caustica
