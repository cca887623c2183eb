#include "film/pixel_filter.h"

#include <stdexcept>
#include <string>

#include "core/math.h"

namespace caustica {

namespace {

// pbrt-v4's Gaussian(x, 0, sigma): the normal density.
float gaussian(float x, float sigma) {
  return std::exp(-x * x / (2 * sigma * sigma)) / std::sqrt(2 * kPi * sigma * sigma);
}

// Mitchell & Netravali 1988, eq. 8 (pbrt-v4's Mitchell1D), support [-2, 2].
float mitchell_1d(float x, float b, float c) {
  x = std::abs(x);
  if (x <= 1)
    return ((12 - 9 * b - 6 * c) * x * x * x + (-18 + 12 * b + 6 * c) * x * x + (6 - 2 * b)) *
           (1.f / 6.f);
  if (x <= 2)
    return ((-b - 6 * c) * x * x * x + (6 * b + 30 * c) * x * x + (-12 * b - 48 * c) * x +
            (8 * b + 24 * c)) *
           (1.f / 6.f);
  return 0;
}

// sin(pi x) / (pi x), pbrt-v4's Sinc.
float sinc(float x) {
  const float px = kPi * x;
  return 1 - px * px == 1 ? 1.f : std::sin(px) / px;
}

// Tabulated kinds: 32 cells per unit of radius, as pbrt-v4's FilterSampler.
bool tabulated(PixelFilterKind kind) {
  return kind == PixelFilterKind::Gaussian || kind == PixelFilterKind::Mitchell ||
         kind == PixelFilterKind::Lanczos;
}

}  // namespace

PixelFilter::Axis::Axis(const PixelFilterParams& p, float r)
    : kind(p.kind), radius(r), sigma(p.sigma), b(p.b), c(p.c), tau(p.tau) {
  if (!(r > 0) || !std::isfinite(r))
    throw std::invalid_argument("pixel filter radius must be positive, got " + std::to_string(r));
  switch (kind) {
    case PixelFilterKind::Box:
      integral = 2 * r;
      break;
    case PixelFilterKind::Triangle:
      integral = r * r;
      break;
    case PixelFilterKind::Gaussian: {
      if (!(sigma > 0)) throw std::invalid_argument("gaussian filter sigma must be positive");
      gauss_at_radius = gaussian(r, sigma);
      // integral over [-r, r] of (g(x) - g(r)): erf(r / (sigma sqrt 2)) - 2 r g(r).
      integral = float(std::erf(double(r) / (double(sigma) * std::sqrt(2.0))) -
                       2.0 * double(r) * double(gauss_at_radius));
      break;
    }
    case PixelFilterKind::Mitchell:
      // f_x(x) = k(2x / r) and the Mitchell-Netravali kernel k integrates to 1 for any B, C.
      integral = r / 2;
      break;
    case PixelFilterKind::Lanczos: {
      if (!(tau > 0)) throw std::invalid_argument("sinc filter tau must be positive");
      // Composite Simpson's rule; the integrand is smooth inside [-r, r].
      const int n = 8192;
      const double h = 2.0 * r / n;
      double sum = evaluate(-r) + evaluate(r);
      for (int i = 1; i < n; ++i) sum += (i % 2 ? 4.0 : 2.0) * evaluate(float(-r + i * h));
      integral = float(sum * h / 3);
      break;
    }
  }
  if (!(integral > 0))
    throw std::invalid_argument(std::string(pixel_filter_name(kind)) +
                                " filter: its integral is not positive");
  if (!tabulated(kind)) return;

  const int n = std::max(1, int(32 * r));
  table.resize(n);
  std::vector<float> magnitude(n);
  double sum = 0, sum_abs = 0;
  for (int i = 0; i < n; ++i) {
    table[i] = evaluate(-r + (float(i) + 0.5f) * (2 * r / float(n)));
    magnitude[i] = std::abs(table[i]);
    sum += table[i];
    sum_abs += magnitude[i];
  }
  if (!(sum > 0))
    throw std::invalid_argument(std::string(pixel_filter_name(kind)) +
                                " filter: its tabulated integral is not positive");
  distribution = Distribution1D(std::move(magnitude));
  weight_scale = float(sum_abs / sum);  // exactly 1 when f >= 0
}

float PixelFilter::Axis::evaluate(float x) const {
  switch (kind) {
    case PixelFilterKind::Box:
      return std::abs(x) <= radius ? 1.f : 0.f;
    case PixelFilterKind::Triangle:
      return std::max(0.f, radius - std::abs(x));
    case PixelFilterKind::Gaussian:
      // pbrt-v4 subtracts the value at the radius so that f falls to 0 there.
      return std::max(0.f, gaussian(x, sigma) - gauss_at_radius);
    case PixelFilterKind::Mitchell:
      return mitchell_1d(2 * x / radius, b, c);
    case PixelFilterKind::Lanczos:
      return std::abs(x) > radius ? 0.f : sinc(x) * sinc(x / tau);
  }
  return 0;
}

float PixelFilter::Axis::sample(float u, float* pdf, float* weight) const {
  switch (kind) {
    case PixelFilterKind::Box:
      *pdf = 1 / (2 * radius);
      *weight = 1;
      return -radius + 2 * radius * u;
    case PixelFilterKind::Triangle: {
      // Inverse of the tent's CDF, one half at a time (pbrt-v4's SampleTent).
      const float x =
          u < 0.5f ? -radius + radius * std::sqrt(2 * u) : radius - radius * std::sqrt(2 * (1 - u));
      *pdf = (radius - std::abs(x)) / (radius * radius);
      *weight = 1;
      return x;
    }
    default: {
      float pdf01;
      size_t cell;
      const float t = distribution.sample_continuous(u, &pdf01, &cell);
      *pdf = pdf01 / (2 * radius);
      *weight = table[cell] < 0 ? -weight_scale : weight_scale;
      return -radius + 2 * radius * t;
    }
  }
}

float PixelFilter::Axis::pdf(float x, float* weight) const {
  *weight = 0;
  if (!(x >= -radius && x < radius)) return 0;
  switch (kind) {
    case PixelFilterKind::Box:
      *weight = 1;
      return 1 / (2 * radius);
    case PixelFilterKind::Triangle:
      *weight = 1;
      return (radius - std::abs(x)) / (radius * radius);
    default: {
      const float t = (x + radius) / (2 * radius);
      const size_t cell = std::min(size_t(t * float(table.size())), table.size() - 1);
      *weight = table[cell] < 0 ? -weight_scale : weight_scale;
      return distribution.pdf_continuous(t) / (2 * radius);
    }
  }
}

PixelFilter::PixelFilter(const PixelFilterParams& params)
    : params_(params), x_(params, params.radius.x), y_(params, params.radius.y) {}

FilterSample PixelFilter::sample(Vec2 u) const {
  FilterSample s;
  float pdf_x, pdf_y, weight_x, weight_y;
  s.offset.x = x_.sample(u.x, &pdf_x, &weight_x);
  s.offset.y = y_.sample(u.y, &pdf_y, &weight_y);
  s.pdf = pdf_x * pdf_y;
  s.weight = weight_x * weight_y;
  return s;
}

FilterSample PixelFilter::at(Vec2 offset) const {
  FilterSample s;
  s.offset = offset;
  float weight_x, weight_y;
  s.pdf = x_.pdf(offset.x, &weight_x) * y_.pdf(offset.y, &weight_y);
  s.weight = s.pdf > 0 ? weight_x * weight_y : 0.f;
  return s;
}

CameraFilterSample PixelFilter::sample_camera(int x, int y, Vec2 u) const {
  if (params_.kind == PixelFilterKind::Box) {
    // x + (1/2 - r) + 2 r u: for r = 1/2 this is x + u bit for bit, the uniform jitter the
    // built-in scenes have always used.
    const Vec2 r = radius();
    return {{float(x) + (0.5f - r.x) + 2 * r.x * u.x, float(y) + (0.5f - r.y) + 2 * r.y * u.y},
            (1 / (2 * r.x)) * (1 / (2 * r.y)),
            1.f};
  }
  const FilterSample s = sample(u);
  return {{float(x) + 0.5f + s.offset.x, float(y) + 0.5f + s.offset.y}, s.pdf, s.weight};
}

}  // namespace caustica
