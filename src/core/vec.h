// Small fixed-size float vectors. Points, directions and normals share Vec3;
// names (p, wo, n) carry the meaning.
#pragma once

#include <cmath>

#include "core/math.h"

namespace caustica {

struct Vec2 {
  float x = 0, y = 0;
  constexpr Vec2() = default;
  constexpr Vec2(float x_, float y_) : x(x_), y(y_) {}
  constexpr float operator[](int i) const { return i == 0 ? x : y; }
  constexpr float& operator[](int i) { return i == 0 ? x : y; }
};
constexpr Vec2 operator+(Vec2 a, Vec2 b) { return {a.x + b.x, a.y + b.y}; }
constexpr Vec2 operator-(Vec2 a, Vec2 b) { return {a.x - b.x, a.y - b.y}; }
constexpr Vec2 operator*(Vec2 a, float s) { return {a.x * s, a.y * s}; }
constexpr Vec2 operator*(float s, Vec2 a) { return {a.x * s, a.y * s}; }

struct Vec3 {
  float x = 0, y = 0, z = 0;
  constexpr Vec3() = default;
  constexpr Vec3(float x_, float y_, float z_) : x(x_), y(y_), z(z_) {}
  constexpr float operator[](int i) const { return i == 0 ? x : (i == 1 ? y : z); }
  constexpr float& operator[](int i) { return i == 0 ? x : (i == 1 ? y : z); }
  constexpr Vec3 operator-() const { return {-x, -y, -z}; }
  constexpr Vec3& operator+=(Vec3 o) {
    x += o.x;
    y += o.y;
    z += o.z;
    return *this;
  }
  constexpr Vec3& operator-=(Vec3 o) {
    x -= o.x;
    y -= o.y;
    z -= o.z;
    return *this;
  }
  constexpr Vec3& operator*=(float s) {
    x *= s;
    y *= s;
    z *= s;
    return *this;
  }
};
constexpr Vec3 operator+(Vec3 a, Vec3 b) { return {a.x + b.x, a.y + b.y, a.z + b.z}; }
constexpr Vec3 operator-(Vec3 a, Vec3 b) { return {a.x - b.x, a.y - b.y, a.z - b.z}; }
constexpr Vec3 operator*(Vec3 a, float s) { return {a.x * s, a.y * s, a.z * s}; }
constexpr Vec3 operator*(float s, Vec3 a) { return {a.x * s, a.y * s, a.z * s}; }
constexpr Vec3 operator/(Vec3 a, float s) { return a * (1.f / s); }
constexpr Vec3 operator*(Vec3 a, Vec3 b) { return {a.x * b.x, a.y * b.y, a.z * b.z}; }
constexpr bool operator==(Vec3 a, Vec3 b) { return a.x == b.x && a.y == b.y && a.z == b.z; }

constexpr float dot(Vec3 a, Vec3 b) { return a.x * b.x + a.y * b.y + a.z * b.z; }
inline float abs_dot(Vec3 a, Vec3 b) { return std::abs(dot(a, b)); }
constexpr Vec3 cross(Vec3 a, Vec3 b) {
  return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x};
}
constexpr float length_squared(Vec3 v) { return dot(v, v); }
inline float length(Vec3 v) { return std::sqrt(dot(v, v)); }
inline Vec3 normalize(Vec3 v) { return v / length(v); }
inline float distance(Vec3 a, Vec3 b) { return length(a - b); }
inline float distance_squared(Vec3 a, Vec3 b) { return length_squared(a - b); }
inline Vec3 min(Vec3 a, Vec3 b) {
  return {std::fmin(a.x, b.x), std::fmin(a.y, b.y), std::fmin(a.z, b.z)};
}
inline Vec3 max(Vec3 a, Vec3 b) {
  return {std::fmax(a.x, b.x), std::fmax(a.y, b.y), std::fmax(a.z, b.z)};
}
inline Vec3 abs(Vec3 v) { return {std::abs(v.x), std::abs(v.y), std::abs(v.z)}; }
inline float max_component(Vec3 v) { return std::fmax(v.x, std::fmax(v.y, v.z)); }
// Flip n to the hemisphere of v.
inline Vec3 face_forward(Vec3 n, Vec3 v) { return dot(n, v) < 0.f ? -n : n; }
inline bool is_finite(Vec3 v) {
  return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z);
}

// Mirror of wo about n (both pointing away from the surface).
inline Vec3 reflect(Vec3 wo, Vec3 n) { return -wo + 2.f * dot(wo, n) * n; }

struct Ray {
  Vec3 o;
  Vec3 d;
  float tmax = kInfinity;
  Vec3 at(float t) const { return o + d * t; }
};

struct Bounds3 {
  Vec3 lo{kInfinity, kInfinity, kInfinity};
  Vec3 hi{-kInfinity, -kInfinity, -kInfinity};
  void extend(Vec3 p) {
    lo = min(lo, p);
    hi = max(hi, p);
  }
  void extend(const Bounds3& b) {
    lo = min(lo, b.lo);
    hi = max(hi, b.hi);
  }
  bool empty() const { return lo.x > hi.x; }
  Vec3 center() const { return (lo + hi) * 0.5f; }
  Vec3 diagonal() const { return hi - lo; }
  // Centre and radius of a sphere that encloses the box.
  void bounding_sphere(Vec3* c, float* r) const {
    *c = center();
    *r = empty() ? 0.f : distance(*c, hi);
  }
};

}  // namespace caustica
