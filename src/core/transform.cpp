#include "core/transform.h"

#include <cmath>
#include <stdexcept>

namespace caustica {

Mat4 Mat4::identity() {
  Mat4 r;
  for (int i = 0; i < 4; ++i) r.m[i][i] = 1.f;
  return r;
}

Mat4 Mat4::from_rows(const float v[16]) {
  Mat4 r;
  for (int i = 0; i < 4; ++i)
    for (int j = 0; j < 4; ++j) r.m[i][j] = v[i * 4 + j];
  return r;
}

Mat4 Mat4::from_column_major(const float v[16]) { return from_rows(v).transposed(); }

Mat4 Mat4::transposed() const {
  Mat4 r;
  for (int i = 0; i < 4; ++i)
    for (int j = 0; j < 4; ++j) r.m[i][j] = m[j][i];
  return r;
}

bool Mat4::inverse(Mat4* out) const {
  // Gauss-Jordan elimination with partial pivoting, in double for robustness.
  double a[4][8];
  for (int i = 0; i < 4; ++i)
    for (int j = 0; j < 4; ++j) {
      a[i][j] = m[i][j];
      a[i][j + 4] = (i == j) ? 1.0 : 0.0;
    }
  for (int c = 0; c < 4; ++c) {
    int pivot = c;
    for (int r = c + 1; r < 4; ++r)
      if (std::abs(a[r][c]) > std::abs(a[pivot][c])) pivot = r;
    if (std::abs(a[pivot][c]) < 1e-30) return false;
    if (pivot != c)
      for (int j = 0; j < 8; ++j) std::swap(a[c][j], a[pivot][j]);
    const double inv = 1.0 / a[c][c];
    for (int j = 0; j < 8; ++j) a[c][j] *= inv;
    for (int r = 0; r < 4; ++r) {
      if (r == c) continue;
      const double f = a[r][c];
      if (f == 0) continue;
      for (int j = 0; j < 8; ++j) a[r][j] -= f * a[c][j];
    }
  }
  for (int i = 0; i < 4; ++i)
    for (int j = 0; j < 4; ++j) out->m[i][j] = float(a[i][j + 4]);
  return true;
}

Mat4 operator*(const Mat4& a, const Mat4& b) {
  Mat4 r;
  for (int i = 0; i < 4; ++i)
    for (int j = 0; j < 4; ++j) {
      double s = 0;
      for (int k = 0; k < 4; ++k) s += double(a.m[i][k]) * b.m[k][j];
      r.m[i][j] = float(s);
    }
  return r;
}

bool operator==(const Mat4& a, const Mat4& b) { return a.m == b.m; }

Transform::Transform(const Mat4& m) : m_(m) {
  if (!m.inverse(&inv_)) throw std::invalid_argument("singular transformation matrix");
}

Transform Transform::translate(Vec3 d) {
  const float f[16] = {1, 0, 0, d.x, 0, 1, 0, d.y, 0, 0, 1, d.z, 0, 0, 0, 1};
  const float g[16] = {1, 0, 0, -d.x, 0, 1, 0, -d.y, 0, 0, 1, -d.z, 0, 0, 0, 1};
  return {Mat4::from_rows(f), Mat4::from_rows(g)};
}

Transform Transform::scale(Vec3 s) {
  const float f[16] = {s.x, 0, 0, 0, 0, s.y, 0, 0, 0, 0, s.z, 0, 0, 0, 0, 1};
  return Transform(Mat4::from_rows(f));
}

Transform Transform::rotate(float theta_degrees, Vec3 axis) {
  const Vec3 a = normalize(axis);
  const float s = std::sin(radians(theta_degrees)), c = std::cos(radians(theta_degrees));
  Mat4 m = Mat4::identity();
  m.m[0][0] = a.x * a.x + (1 - a.x * a.x) * c;
  m.m[0][1] = a.x * a.y * (1 - c) - a.z * s;
  m.m[0][2] = a.x * a.z * (1 - c) + a.y * s;
  m.m[1][0] = a.x * a.y * (1 - c) + a.z * s;
  m.m[1][1] = a.y * a.y + (1 - a.y * a.y) * c;
  m.m[1][2] = a.y * a.z * (1 - c) - a.x * s;
  m.m[2][0] = a.x * a.z * (1 - c) - a.y * s;
  m.m[2][1] = a.y * a.z * (1 - c) + a.x * s;
  m.m[2][2] = a.z * a.z + (1 - a.z * a.z) * c;
  return {m, m.transposed()};
}

Transform Transform::look_at(Vec3 pos, Vec3 look, Vec3 up) {
  Mat4 cam_to_world = Mat4::identity();
  const Vec3 dir = normalize(look - pos);
  Vec3 right = cross(normalize(up), dir);
  if (length(right) == 0)
    throw std::invalid_argument("LookAt: 'up' is parallel to the view direction");
  right = normalize(right);
  const Vec3 new_up = cross(dir, right);
  for (int i = 0; i < 3; ++i) {
    cam_to_world.m[i][0] = right[i];
    cam_to_world.m[i][1] = new_up[i];
    cam_to_world.m[i][2] = dir[i];
    cam_to_world.m[i][3] = pos[i];
  }
  Mat4 world_to_cam;
  cam_to_world.inverse(&world_to_cam);
  return {world_to_cam, cam_to_world};
}

Transform Transform::perspective(float fov_degrees, float n, float f) {
  const float p[16] = {1, 0, 0, 0, 0, 1, 0, 0, 0, 0, f / (f - n), -f * n / (f - n), 0, 0, 1, 0};
  const float inv_tan = 1.f / std::tan(radians(fov_degrees) / 2);
  return Transform::scale({inv_tan, inv_tan, 1}) * Transform(Mat4::from_rows(p));
}

bool Transform::is_identity() const { return m_ == Mat4::identity(); }

bool Transform::swaps_handedness() const {
  const auto& a = m_.m;
  const float det = a[0][0] * (a[1][1] * a[2][2] - a[1][2] * a[2][1]) -
                    a[0][1] * (a[1][0] * a[2][2] - a[1][2] * a[2][0]) +
                    a[0][2] * (a[1][0] * a[2][1] - a[1][1] * a[2][0]);
  return det < 0;
}

Vec3 Transform::point(Vec3 p) const {
  const auto& a = m_.m;
  const float x = a[0][0] * p.x + a[0][1] * p.y + a[0][2] * p.z + a[0][3];
  const float y = a[1][0] * p.x + a[1][1] * p.y + a[1][2] * p.z + a[1][3];
  const float z = a[2][0] * p.x + a[2][1] * p.y + a[2][2] * p.z + a[2][3];
  const float w = a[3][0] * p.x + a[3][1] * p.y + a[3][2] * p.z + a[3][3];
  return w == 1.f ? Vec3(x, y, z) : Vec3(x, y, z) / w;
}

Vec3 Transform::vector(Vec3 v) const {
  const auto& a = m_.m;
  return {a[0][0] * v.x + a[0][1] * v.y + a[0][2] * v.z,
          a[1][0] * v.x + a[1][1] * v.y + a[1][2] * v.z,
          a[2][0] * v.x + a[2][1] * v.y + a[2][2] * v.z};
}

Vec3 Transform::normal(Vec3 n) const {
  const auto& a = inv_.m;
  return {a[0][0] * n.x + a[1][0] * n.y + a[2][0] * n.z,
          a[0][1] * n.x + a[1][1] * n.y + a[2][1] * n.z,
          a[0][2] * n.x + a[1][2] * n.y + a[2][2] * n.z};
}

Bounds3 Transform::bounds(const Bounds3& b) const {
  Bounds3 r;
  for (int i = 0; i < 8; ++i)
    r.extend(
        point({(i & 1) ? b.hi.x : b.lo.x, (i & 2) ? b.hi.y : b.lo.y, (i & 4) ? b.hi.z : b.lo.z}));
  return r;
}

Transform operator*(const Transform& a, const Transform& b) {
  return {a.matrix() * b.matrix(), b.inverse_matrix() * a.inverse_matrix()};
}

}  // namespace caustica
