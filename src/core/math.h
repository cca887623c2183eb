// Scalar helpers and constants shared by every layer.
#pragma once

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstdint>
#include <limits>

namespace caustica {

inline constexpr float kPi = 3.14159265358979323846f;
inline constexpr float kInvPi = 0.31830988618379067154f;
inline constexpr float kInv2Pi = 0.15915494309189533577f;
inline constexpr float kInv4Pi = 0.07957747154594766788f;
inline constexpr float kInfinity = std::numeric_limits<float>::infinity();
// Largest float strictly below 1: uniform samples live in [0, kOneMinusEpsilon].
inline constexpr float kOneMinusEpsilon = 0x1.fffffep-1f;

template <typename T>
constexpr T sqr(T v) {
  return v * v;
}

template <typename T>
constexpr T clamp(T v, T lo, T hi) {
  return std::min(std::max(v, lo), hi);
}

// std::nextafter(v, +infinity) and (v, -infinity) without the library call (pbrt-v4's
// NextFloatUp/Down): the same float for every input, infinities and signed zeros included.
inline float next_float_up(float v) {
  if (v == kInfinity) return v;
  if (v == 0.f) v = 0.f;  // -0 steps to the smallest positive float, as +0 does
  const uint32_t bits = std::bit_cast<uint32_t>(v);
  return std::bit_cast<float>(v >= 0 ? bits + 1 : bits - 1);
}
inline float next_float_down(float v) {
  if (v == -kInfinity) return v;
  if (v == 0.f) v = -0.f;
  const uint32_t bits = std::bit_cast<uint32_t>(v);
  return std::bit_cast<float>(v > 0 ? bits - 1 : bits + 1);
}

inline float lerp(float t, float a, float b) { return (1 - t) * a + t * b; }
inline float safe_sqrt(float v) { return std::sqrt(std::max(v, 0.f)); }
inline float safe_acos(float v) { return std::acos(clamp(v, -1.f, 1.f)); }
inline float safe_asin(float v) { return std::asin(clamp(v, -1.f, 1.f)); }
inline float radians(float deg) { return deg * (kPi / 180.f); }
inline float degrees(float rad) { return rad * (180.f / kPi); }

// Veach 1997, eq. 9.13 with beta = 2, written for two techniques with sample counts folded in.
inline float power_heuristic(float pdf_a, float pdf_b) {
  const float a = pdf_a * pdf_a, b = pdf_b * pdf_b;
  if (std::isinf(a)) return 1.f;
  return a + b > 0 ? a / (a + b) : 0.f;
}
inline float balance_heuristic(float pdf_a, float pdf_b) {
  if (std::isinf(pdf_a)) return 1.f;
  return pdf_a + pdf_b > 0 ? pdf_a / (pdf_a + pdf_b) : 0.f;
}

}  // namespace caustica
