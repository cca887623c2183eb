#include "film/film.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <atomic>
#include <stdexcept>

namespace caustica {

Film::Film(int width, int height)
    : width_(width), height_(height), total_(3 * size_t(width) * size_t(height), FixedSum(0)) {}

void Film::add_image(const Image& image, float scale) {
  // Each pixel is independent, so the split over threads cannot change a result.
  std::atomic<uint64_t> nonfinite{0};
  tbb::parallel_for(tbb::blocked_range<size_t>(0, pixel_count(), 1 << 12),
                    [&](const tbb::blocked_range<size_t>& r) {
                      uint64_t dropped = 0;
                      for (size_t i = r.begin(); i != r.end(); ++i) {
                        const Rgb v = image[i] * scale;
                        if (!v.is_finite())
                          ++dropped;
                        else if (v.r != 0 || v.g != 0 || v.b != 0)
                          add_exactly(i, v);
                      }
                      if (dropped) nonfinite += dropped;
                    });
  if (const uint64_t n = nonfinite.load()) count_nonfinite(n);
}

void Film::end_iteration() { ++iterations_; }

void Film::add(const Film& other) {
  if (other.width_ != width_ || other.height_ != height_)
    throw std::invalid_argument("Film::add: films differ in size");
  for (size_t i = 0; i < total_.size(); ++i) total_[i] += other.total_[i];
  iterations_ += other.iterations_;
  nonfinite_.fetch_add(other.nonfinite_count());
}

Image Film::image() const {
  Image out(width_, height_);
  const double inv = iterations_ > 0 ? 1.0 / iterations_ : 0.0;
  for (size_t i = 0; i < pixel_count(); ++i)
    out[i] = Rgb(float(from_fixed(total_[3 * i]) * inv), float(from_fixed(total_[3 * i + 1]) * inv),
                 float(from_fixed(total_[3 * i + 2]) * inv));
  return out;
}

}  // namespace caustica
