// Linear Rec.709 RGB: the renderer's only colour representation.
#pragma once

#include <cmath>

#include "core/math.h"

namespace caustica {

struct Rgb {
  float r = 0, g = 0, b = 0;
  constexpr Rgb() = default;
  constexpr explicit Rgb(float v) : r(v), g(v), b(v) {}
  constexpr Rgb(float r_, float g_, float b_) : r(r_), g(g_), b(b_) {}
  constexpr float operator[](int i) const { return i == 0 ? r : (i == 1 ? g : b); }
  constexpr float& operator[](int i) { return i == 0 ? r : (i == 1 ? g : b); }
  constexpr Rgb& operator+=(Rgb o) {
    r += o.r;
    g += o.g;
    b += o.b;
    return *this;
  }
  constexpr Rgb& operator*=(Rgb o) {
    r *= o.r;
    g *= o.g;
    b *= o.b;
    return *this;
  }
  constexpr Rgb& operator*=(float s) {
    r *= s;
    g *= s;
    b *= s;
    return *this;
  }
  constexpr bool is_black() const { return r == 0 && g == 0 && b == 0; }
  bool is_finite() const { return std::isfinite(r) && std::isfinite(g) && std::isfinite(b); }
  constexpr float max_component() const { return std::max(r, std::max(g, b)); }
  constexpr float average() const { return (r + g + b) * (1.f / 3.f); }
  // Rec.709 / sRGB luminance weights.
  constexpr float luminance() const { return 0.2126f * r + 0.7152f * g + 0.0722f * b; }
};
constexpr Rgb operator+(Rgb a, Rgb b) { return {a.r + b.r, a.g + b.g, a.b + b.b}; }
constexpr Rgb operator-(Rgb a, Rgb b) { return {a.r - b.r, a.g - b.g, a.b - b.b}; }
constexpr Rgb operator*(Rgb a, Rgb b) { return {a.r * b.r, a.g * b.g, a.b * b.b}; }
constexpr Rgb operator*(Rgb a, float s) { return {a.r * s, a.g * s, a.b * s}; }
constexpr Rgb operator*(float s, Rgb a) { return {a.r * s, a.g * s, a.b * s}; }
constexpr Rgb operator/(Rgb a, float s) { return a * (1.f / s); }
constexpr Rgb operator/(Rgb a, Rgb b) {
  return {b.r != 0 ? a.r / b.r : 0.f, b.g != 0 ? a.g / b.g : 0.f, b.b != 0 ? a.b / b.b : 0.f};
}
constexpr bool operator==(Rgb a, Rgb b) { return a.r == b.r && a.g == b.g && a.b == b.b; }
inline Rgb exp(Rgb a) { return {std::exp(a.r), std::exp(a.g), std::exp(a.b)}; }
inline Rgb sqrt(Rgb a) { return {safe_sqrt(a.r), safe_sqrt(a.g), safe_sqrt(a.b)}; }
inline Rgb clamp(Rgb a, float lo, float hi) {
  return {clamp(a.r, lo, hi), clamp(a.g, lo, hi), clamp(a.b, lo, hi)};
}

// sRGB transfer functions (IEC 61966-2-1).
inline float srgb_to_linear(float v) {
  return v <= 0.04045f ? v / 12.92f : std::pow((v + 0.055f) / 1.055f, 2.4f);
}
inline float linear_to_srgb(float v) {
  return v <= 0.0031308f ? 12.92f * v : 1.055f * std::pow(v, 1.f / 2.4f) - 0.055f;
}

}  // namespace caustica
