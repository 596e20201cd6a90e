// Fixed-size 3x3 and 9x9 matrices for device kernels: no heap, no virtual calls, trivially copyable.
//
// Mat3 is stored column-major so that its raw storage *is* the paper's vec(F) (Eq. 17: vec stacks
// the columns), which makes the 9x9 Hessian d2Psi/dvec(F)^2 index directly into it.
#pragma once

#include <Kokkos_Macros.hpp>
#include <cmath>

namespace sinew {

struct Vec3 {
  double v[3];
  KOKKOS_INLINE_FUNCTION double& operator[](int i) { return v[i]; }
  KOKKOS_INLINE_FUNCTION const double& operator[](int i) const { return v[i]; }
};

KOKKOS_INLINE_FUNCTION Vec3 cross(const Vec3& a, const Vec3& b) {
  return Vec3{{a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]}};
}
KOKKOS_INLINE_FUNCTION double dot(const Vec3& a, const Vec3& b) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }

struct Mat3 {
  double a[9];  // a[i + 3*j] = A(i, j)
  KOKKOS_INLINE_FUNCTION double& operator()(int i, int j) { return a[i + 3 * j]; }
  KOKKOS_INLINE_FUNCTION const double& operator()(int i, int j) const { return a[i + 3 * j]; }
  KOKKOS_INLINE_FUNCTION double& operator[](int k) { return a[k]; }
  KOKKOS_INLINE_FUNCTION const double& operator[](int k) const { return a[k]; }
  KOKKOS_INLINE_FUNCTION Vec3 col(int j) const { return Vec3{{a[3 * j], a[3 * j + 1], a[3 * j + 2]}}; }
  KOKKOS_INLINE_FUNCTION void set_col(int j, const Vec3& c) {
    a[3 * j] = c[0];
    a[3 * j + 1] = c[1];
    a[3 * j + 2] = c[2];
  }
  KOKKOS_INLINE_FUNCTION static Mat3 zero() { return Mat3{{0, 0, 0, 0, 0, 0, 0, 0, 0}}; }
  KOKKOS_INLINE_FUNCTION static Mat3 identity() { return Mat3{{1, 0, 0, 0, 1, 0, 0, 0, 1}}; }
  KOKKOS_INLINE_FUNCTION static Mat3 diag(double d0, double d1, double d2) {
    return Mat3{{d0, 0, 0, 0, d1, 0, 0, 0, d2}};
  }
};

KOKKOS_INLINE_FUNCTION Mat3 operator+(const Mat3& A, const Mat3& B) {
  Mat3 C;
  for (int k = 0; k < 9; ++k) C[k] = A[k] + B[k];
  return C;
}
KOKKOS_INLINE_FUNCTION Mat3 operator-(const Mat3& A, const Mat3& B) {
  Mat3 C;
  for (int k = 0; k < 9; ++k) C[k] = A[k] - B[k];
  return C;
}
KOKKOS_INLINE_FUNCTION Mat3 operator*(double s, const Mat3& A) {
  Mat3 C;
  for (int k = 0; k < 9; ++k) C[k] = s * A[k];
  return C;
}
KOKKOS_INLINE_FUNCTION Mat3 operator*(const Mat3& A, const Mat3& B) {
  Mat3 C;
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) C(i, j) = A(i, 0) * B(0, j) + A(i, 1) * B(1, j) + A(i, 2) * B(2, j);
  return C;
}
KOKKOS_INLINE_FUNCTION Mat3 transpose(const Mat3& A) {
  Mat3 C;
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) C(i, j) = A(j, i);
  return C;
}
KOKKOS_INLINE_FUNCTION double trace(const Mat3& A) { return A(0, 0) + A(1, 1) + A(2, 2); }
KOKKOS_INLINE_FUNCTION double ddot(const Mat3& A, const Mat3& B) {
  double s = 0;
  for (int k = 0; k < 9; ++k) s += A[k] * B[k];
  return s;
}
KOKKOS_INLINE_FUNCTION double frobenius2(const Mat3& A) { return ddot(A, A); }
KOKKOS_INLINE_FUNCTION double det(const Mat3& A) { return dot(A.col(0), cross(A.col(1), A.col(2))); }

// dJ/dF = [f1 x f2 | f2 x f0 | f0 x f1] (Eq. 19), the cofactor matrix of F.
KOKKOS_INLINE_FUNCTION Mat3 cofactor(const Mat3& F) {
  Mat3 G;
  const Vec3 f0 = F.col(0), f1 = F.col(1), f2 = F.col(2);
  G.set_col(0, cross(f1, f2));
  G.set_col(1, cross(f2, f0));
  G.set_col(2, cross(f0, f1));
  return G;
}

// The rotation of a unit quaternion (w, x, y, z).
KOKKOS_INLINE_FUNCTION Mat3 rotation_of_quaternion(double w, double x, double y, double z) {
  Mat3 R;
  R(0, 0) = 1 - 2 * (y * y + z * z);
  R(0, 1) = 2 * (x * y - z * w);
  R(0, 2) = 2 * (x * z + y * w);
  R(1, 0) = 2 * (x * y + z * w);
  R(1, 1) = 1 - 2 * (x * x + z * z);
  R(1, 2) = 2 * (y * z - x * w);
  R(2, 0) = 2 * (x * z - y * w);
  R(2, 1) = 2 * (y * z + x * w);
  R(2, 2) = 1 - 2 * (x * x + y * y);
  return R;
}

// 9x9 matrix in the vec(F) basis, row-major (Hessians are symmetric, so the order rarely matters).
struct Mat9 {
  double a[81];
  KOKKOS_INLINE_FUNCTION double& operator()(int r, int c) { return a[9 * r + c]; }
  KOKKOS_INLINE_FUNCTION const double& operator()(int r, int c) const { return a[9 * r + c]; }
  KOKKOS_INLINE_FUNCTION static Mat9 zero() {
    Mat9 H;
    for (int k = 0; k < 81; ++k) H.a[k] = 0.0;
    return H;
  }
  KOKKOS_INLINE_FUNCTION void add_identity(double s) {
    for (int k = 0; k < 9; ++k) a[10 * k] += s;
  }
  // this += s * vec(X) vec(Y)^T
  KOKKOS_INLINE_FUNCTION void add_outer(double s, const Mat3& X, const Mat3& Y) {
    for (int r = 0; r < 9; ++r) {
      const double sx = s * X[r];
      for (int c = 0; c < 9; ++c) a[9 * r + c] += sx * Y[c];
    }
  }
  KOKKOS_INLINE_FUNCTION void add_sym_outer(double s, const Mat3& X) { add_outer(s, X, X); }
};

// this += s * H_J, the volume Hessian d2J/dF2 of Eq. 28: 3x3 blocks of cross-product matrices
// (Eq. 29) of the columns of F. Block (i, j) maps column j of dF to column i of dP.
KOKKOS_INLINE_FUNCTION void add_volume_hessian(Mat9& H, double s, const Mat3& F) {
  // Block (i, j) = s * eps_{ijk} * hat(f_k), where hat(x) y = x cross y.
  for (int i = 0; i < 3; ++i) {
    for (int j = 0; j < 3; ++j) {
      if (i == j) continue;
      const int k = 3 - i - j;
      // eps_{ijk} = +1 for cyclic (i, j, k)
      const double sign = ((j - i + 3) % 3 == 1) ? 1.0 : -1.0;
      // hat(f_k) = [[0, -x2, x1], [x2, 0, -x0], [-x1, x0, 0]]; block (0,1) of Eq. 28 is -hat(f2), so
      // block(i,j) = -eps_{ijk} hat(f_k).
      const double x0 = F(0, k), x1 = F(1, k), x2 = F(2, k);
      const double hat[3][3] = {{0, -x2, x1}, {x2, 0, -x0}, {-x1, x0, 0}};
      for (int r = 0; r < 3; ++r)
        for (int c = 0; c < 3; ++c) H(3 * i + r, 3 * j + c) += -sign * s * hat[r][c];
    }
  }
}

}  // namespace sinew
