// Rotation-variant SVD of a 3x3 matrix (paper Eq. 2): F = U diag(s) V^T with det U = det V = +1.
// Reflections go into Sigma: s0 >= s1 >= |s2| and s2 < 0 exactly when det F < 0.
//
// Method (as in McAdams et al. 2011, without the float tricks): V from a Jacobi eigen-decomposition
// of F^T F, then a Givens QR of B = F V. Using QR instead of U = F V / s keeps U a rotation and the
// singular values accurate when some of them are zero or repeated.
#pragma once

#include <sinew/core/small_matrix.hpp>
#include <sinew/core/sym_eigen.hpp>

namespace sinew {

struct Svd3 {
  Mat3 U, V;
  double s[3];
};

namespace detail {
// Left-multiply rows (p, q) of B by the Givens rotation that zeroes B(q, col) into B(p, col) >= 0,
// and accumulate the transpose into U (so that U * B stays invariant).
KOKKOS_INLINE_FUNCTION void givens_zero(Mat3& B, Mat3& U, int p, int q, int col) {
  const double a = B(p, col), b = B(q, col);
  const double r = std::sqrt(a * a + b * b);
  if (r == 0.0) return;
  const double c = a / r, s = b / r;
  for (int j = 0; j < 3; ++j) {
    const double bp = B(p, j), bq = B(q, j);
    B(p, j) = c * bp + s * bq;
    B(q, j) = -s * bp + c * bq;
  }
  for (int i = 0; i < 3; ++i) {  // U <- U G^T
    const double up = U(i, p), uq = U(i, q);
    U(i, p) = c * up + s * uq;
    U(i, q) = -s * up + c * uq;
  }
}
}  // namespace detail

KOKKOS_INLINE_FUNCTION Svd3 svd3(const Mat3& F) {
  // 1. V: eigenvectors of F^T F, sorted by decreasing eigenvalue, made a rotation.
  const Mat3 C = transpose(F) * F;
  double A[9], ev[3], Q[9];
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) A[3 * i + j] = C(i, j);
  jacobi_eigen<3>(A, ev, Q);
  int order[3] = {0, 1, 2};
  for (int i = 0; i < 2; ++i)
    for (int j = 0; j < 2 - i; ++j)
      if (ev[order[j]] < ev[order[j + 1]]) {
        const int t = order[j];
        order[j] = order[j + 1];
        order[j + 1] = t;
      }
  Svd3 out;
  for (int k = 0; k < 3; ++k)
    for (int r = 0; r < 3; ++r) out.V(r, k) = Q[3 * r + order[k]];
  if (det(out.V) < 0.0)
    for (int r = 0; r < 3; ++r) out.V(r, 2) = -out.V(r, 2);

  // 2. B = F V = U R by Givens QR; the columns of B are orthogonal, so R is diagonal up to
  //    round-off. Each rotation makes the pivot non-negative, so only R(2,2) can carry a sign.
  Mat3 B = F * out.V;
  out.U = Mat3::identity();
  detail::givens_zero(B, out.U, 0, 1, 0);
  detail::givens_zero(B, out.U, 0, 2, 0);
  detail::givens_zero(B, out.U, 1, 2, 1);
  out.s[0] = B(0, 0);
  out.s[1] = B(1, 1);
  out.s[2] = B(2, 2);
  return out;
}

// Polar decomposition F = R S from the rotation-variant SVD: R = U V^T is a rotation and S = V Sigma V^T
// is symmetric (indefinite when F is inverted), as the corotational models (Eq. 3, 49) use it.
struct Polar3 {
  Mat3 R, S;
};
KOKKOS_INLINE_FUNCTION Polar3 polar3(const Mat3& F) {
  const Svd3 d = svd3(F);
  Polar3 p;
  p.R = d.U * transpose(d.V);
  p.S = d.V * Mat3::diag(d.s[0], d.s[1], d.s[2]) * transpose(d.V);
  return p;
}

}  // namespace sinew
