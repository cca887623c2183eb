#include "film/film.h"

namespace caustica {

Film::Film(int width, int height) : width_(width), height_(height), sum_(3 * size_t(width) * size_t(height), 0.0) {}

void Film::add_image(const Image& image, float scale) {
  for (size_t i = 0; i < pixel_count(); ++i) {
    const Rgb v = image[i] * scale;
    if (!v.is_finite()) {
      count_nonfinite();
      continue;
    }
    sum_[3 * i] += v.r;
    sum_[3 * i + 1] += v.g;
    sum_[3 * i + 2] += v.b;
  }
}

Image Film::image() const {
  Image out(width_, height_);
  const double inv = iterations_ > 0 ? 1.0 / iterations_ : 0.0;
  for (size_t i = 0; i < pixel_count(); ++i)
    out[i] = Rgb(float(sum_[3 * i] * inv), float(sum_[3 * i + 1] * inv), float(sum_[3 * i + 2] * inv));
  return out;
}

}  // namespace caustica
