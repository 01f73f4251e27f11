// Small 3-vector over double: the only math type the simulator needs.
#pragma once

#include <cmath>

namespace sandflow {

using Real = double;

struct Vec3 {
  Real x = 0, y = 0, z = 0;

  constexpr Vec3() = default;
  constexpr Vec3(Real x_, Real y_, Real z_) : x(x_), y(y_), z(z_) {}

  constexpr Real operator[](int i) const { return i == 0 ? x : (i == 1 ? y : z); }
  constexpr Real& operator[](int i) { return i == 0 ? x : (i == 1 ? y : z); }

  constexpr Vec3 operator+(const Vec3& o) const { return {x + o.x, y + o.y, z + o.z}; }
  constexpr Vec3 operator-(const Vec3& o) const { return {x - o.x, y - o.y, z - o.z}; }
  constexpr Vec3 operator-() const { return {-x, -y, -z}; }
  constexpr Vec3 operator*(Real s) const { return {x * s, y * s, z * s}; }
  constexpr Vec3 operator/(Real s) const { return {x / s, y / s, z / s}; }
  constexpr Vec3& operator+=(const Vec3& o) { x += o.x; y += o.y; z += o.z; return *this; }
  constexpr Vec3& operator-=(const Vec3& o) { x -= o.x; y -= o.y; z -= o.z; return *this; }
  constexpr Vec3& operator*=(Real s) { x *= s; y *= s; z *= s; return *this; }
  constexpr bool operator==(const Vec3&) const = default;
};

constexpr Vec3 operator*(Real s, const Vec3& v) { return v * s; }
constexpr Real dot(const Vec3& a, const Vec3& b) { return a.x * b.x + a.y * b.y + a.z * b.z; }
constexpr Vec3 cross(const Vec3& a, const Vec3& b) {
  return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x};
}
constexpr Real norm2(const Vec3& a) { return dot(a, a); }
inline Real norm(const Vec3& a) { return std::sqrt(norm2(a)); }
inline bool is_finite(const Vec3& a) {
  return std::isfinite(a.x) && std::isfinite(a.y) && std::isfinite(a.z);
}
constexpr Vec3 min(const Vec3& a, const Vec3& b) {
  return {a.x < b.x ? a.x : b.x, a.y < b.y ? a.y : b.y, a.z < b.z ? a.z : b.z};
}
constexpr Vec3 max(const Vec3& a, const Vec3& b) {
  return {a.x > b.x ? a.x : b.x, a.y > b.y ? a.y : b.y, a.z > b.z ? a.z : b.z};
}
/// to = v a coordinate at a time (where the default copy, a block move, would pass a vector held
/// in registers through the stack).
inline void store(Vec3& to, const Vec3& v) {
  to.x = v.x;
  to.y = v.y;
  to.z = v.z;
}
/// p lies in the closed box [lo, hi]; a NaN coordinate does not (it fails every comparison).
constexpr bool in_box(const Vec3& p, const Vec3& lo, const Vec3& hi) {
  return p.x >= lo.x && p.x <= hi.x && p.y >= lo.y && p.y <= hi.y && p.z >= lo.z && p.z <= hi.z;
}

/// Row-major 3x3 matrix, used for the rotations of geometry.
struct Mat3 {
  Real m[3][3] = {{1, 0, 0}, {0, 1, 0}, {0, 0, 1}};

  constexpr Vec3 operator*(const Vec3& v) const {
    return {m[0][0] * v.x + m[0][1] * v.y + m[0][2] * v.z,
            m[1][0] * v.x + m[1][1] * v.y + m[1][2] * v.z,
            m[2][0] * v.x + m[2][1] * v.y + m[2][2] * v.z};
  }
  constexpr Mat3 operator*(const Mat3& o) const {
    Mat3 r;
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j)
        r.m[i][j] = m[i][0] * o.m[0][j] + m[i][1] * o.m[1][j] + m[i][2] * o.m[2][j];
    return r;
  }
  constexpr Mat3 transposed() const {
    Mat3 r;
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j) r.m[i][j] = m[j][i];
    return r;
  }
};

constexpr Real kPi = 3.14159265358979323846;
constexpr Real deg_to_rad(Real deg) { return deg * kPi / 180.0; }
constexpr Real rad_to_deg(Real rad) { return rad * 180.0 / kPi; }

/// Rotation from Euler angles in degrees, applied about x, then y, then z (extrinsic).
inline Mat3 rotation_xyz_deg(const Vec3& deg) {
  const Real cx = std::cos(deg_to_rad(deg.x)), sx = std::sin(deg_to_rad(deg.x));
  const Real cy = std::cos(deg_to_rad(deg.y)), sy = std::sin(deg_to_rad(deg.y));
  const Real cz = std::cos(deg_to_rad(deg.z)), sz = std::sin(deg_to_rad(deg.z));
  Mat3 rx{{{1, 0, 0}, {0, cx, -sx}, {0, sx, cx}}};
  Mat3 ry{{{cy, 0, sy}, {0, 1, 0}, {-sy, 0, cy}}};
  Mat3 rz{{{cz, -sz, 0}, {sz, cz, 0}, {0, 0, 1}}};
  return rz * (ry * rx);
}

}  // namespace sandflow
