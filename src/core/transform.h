// Affine/projective 4x4 transforms with cached inverse, following pbrt-v4's conventions
// (column vectors; LookAt builds a left-handed camera frame).
#pragma once

#include <array>

#include "core/vec.h"

namespace caustica {

struct Mat4 {
  std::array<std::array<float, 4>, 4> m{};
  static Mat4 identity();
  static Mat4 from_rows(const float v[16]);
  // Column-major as pbrt's `Transform [...]` / `ConcatTransform [...]` lists them.
  static Mat4 from_column_major(const float v[16]);
  Mat4 transposed() const;
  // Returns false (and leaves *out untouched) when the matrix is singular.
  bool inverse(Mat4* out) const;
  float operator()(int r, int c) const { return m[r][c]; }
};
Mat4 operator*(const Mat4& a, const Mat4& b);
bool operator==(const Mat4& a, const Mat4& b);

class Transform {
 public:
  Transform() : m_(Mat4::identity()), inv_(Mat4::identity()) {}
  Transform(const Mat4& m, const Mat4& inv) : m_(m), inv_(inv) {}
  // Throws std::invalid_argument if m is singular.
  explicit Transform(const Mat4& m);

  static Transform translate(Vec3 d);
  static Transform scale(Vec3 s);
  // Rotation by theta_degrees about axis (right-handed rotation as in pbrt's Rotate).
  static Transform rotate(float theta_degrees, Vec3 axis);
  // World-to-camera transform of pbrt's LookAt (left-handed camera space, +z forward).
  static Transform look_at(Vec3 pos, Vec3 look, Vec3 up);
  // pbrt's Perspective(fov, n, f): camera space to a projective screen space.
  static Transform perspective(float fov_degrees, float z_near, float z_far);

  const Mat4& matrix() const { return m_; }
  const Mat4& inverse_matrix() const { return inv_; }
  Transform inverse() const { return Transform(inv_, m_); }
  bool is_identity() const;
  // True when the transform flips handedness (negative determinant of the 3x3 part).
  bool swaps_handedness() const;

  Vec3 point(Vec3 p) const;  // homogeneous divide applied
  Vec3 vector(Vec3 v) const;
  Vec3 normal(Vec3 n) const;  // inverse transpose, not normalised
  Ray ray(const Ray& r) const { return {point(r.o), vector(r.d), r.tmax}; }
  Bounds3 bounds(const Bounds3& b) const;

 private:
  Mat4 m_, inv_;
};
Transform operator*(const Transform& a, const Transform& b);

}  // namespace caustica
