// Rigid transforms x -> R x + t (bones, colliders) and rotations about an axis.
#pragma once

#include <sinew/core/small_matrix.hpp>

#include <algorithm>
#include <array>
#include <cmath>

namespace sinew {

struct Rigid {
  Mat3 R = Mat3::identity();
  std::array<double, 3> t{{0.0, 0.0, 0.0}};
  std::array<double, 3> apply(const std::array<double, 3>& x) const {
    std::array<double, 3> y;
    for (int i = 0; i < 3; ++i) y[i] = R(i, 0) * x[0] + R(i, 1) * x[1] + R(i, 2) * x[2] + t[i];
    return y;
  }
  // R v: a direction (no translation).
  std::array<double, 3> rotate(const std::array<double, 3>& v) const {
    std::array<double, 3> y;
    for (int i = 0; i < 3; ++i) y[i] = R(i, 0) * v[0] + R(i, 1) * v[1] + R(i, 2) * v[2];
    return y;
  }
  // this after other: x -> this(other(x))
  Rigid after(const Rigid& o) const {
    Rigid c;
    c.R = R * o.R;
    c.t = apply(o.t);
    return c;
  }
  Rigid inverse() const {
    Rigid i;
    i.R = transpose(R);
    for (int r = 0; r < 3; ++r) i.t[r] = -(i.R(r, 0) * t[0] + i.R(r, 1) * t[1] + i.R(r, 2) * t[2]);
    return i;
  }
};

// The rotation nearest to A (the polar factor, by Higham's iteration R <- (R + R^-T) / 2).
inline Mat3 nearest_rotation(const Mat3& A) {
  Mat3 R = A;
  for (int it = 0; it < 30; ++it) {
    const Mat3 Rt = (1.0 / det(R)) * cofactor(R);  // R^-T
    Mat3 next;
    double change = 0.0;
    for (int k = 0; k < 9; ++k) {
      next[k] = 0.5 * (R[k] + Rt[k]);
      change = std::max(change, std::fabs(next[k] - R[k]));
    }
    R = next;
    if (change < 1e-15) break;
  }
  return R;
}

// Rotation about a unit axis by an angle (Rodrigues).
inline Mat3 axis_angle(const std::array<double, 3>& k, double angle) {
  const double c = std::cos(angle), s = std::sin(angle), t = 1 - c;
  Mat3 R;
  R(0, 0) = c + k[0] * k[0] * t;
  R(0, 1) = k[0] * k[1] * t - k[2] * s;
  R(0, 2) = k[0] * k[2] * t + k[1] * s;
  R(1, 0) = k[1] * k[0] * t + k[2] * s;
  R(1, 1) = c + k[1] * k[1] * t;
  R(1, 2) = k[1] * k[2] * t - k[0] * s;
  R(2, 0) = k[2] * k[0] * t - k[1] * s;
  R(2, 1) = k[2] * k[1] * t + k[0] * s;
  R(2, 2) = c + k[2] * k[2] * t;
  return R;
}

}  // namespace sinew
