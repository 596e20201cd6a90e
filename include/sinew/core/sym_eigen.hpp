// Symmetric eigen-decomposition by cyclic Jacobi rotations, fixed size, device-safe.
//
// Jacobi is slow for large N but unconditionally robust (repeated and zero eigenvalues included) and
// accurate to a few ulps relative to the matrix norm, which is what a per-quadrature-point PSD
// projection of a 3x3 or 9x9 block needs.
#pragma once

#include <Kokkos_Macros.hpp>
#include <cmath>

namespace sinew {

// A is N x N row-major symmetric and is destroyed. On return evals[k] holds the eigenvalues and
// column k of Q (row-major, Q[r*N + k]) the matching unit eigenvector, unsorted.
template <int N>
KOKKOS_INLINE_FUNCTION void jacobi_eigen(double* A, double* evals, double* Q) {
  for (int r = 0; r < N; ++r)
    for (int c = 0; c < N; ++c) Q[r * N + c] = (r == c) ? 1.0 : 0.0;
  double norm2 = 0.0;
  for (int k = 0; k < N * N; ++k) norm2 += A[k] * A[k];
  const double tiny = 1e-36 * norm2 + 1e-300;
  for (int sweep = 0; sweep < 60; ++sweep) {
    double off = 0.0;
    for (int p = 0; p < N; ++p)
      for (int q = p + 1; q < N; ++q) off += A[p * N + q] * A[p * N + q];
    if (off <= tiny) break;
    for (int p = 0; p < N; ++p) {
      for (int q = p + 1; q < N; ++q) {
        const double apq = A[p * N + q];
        if (apq * apq <= 1e-40 * norm2 + 1e-300) continue;
        const double app = A[p * N + p], aqq = A[q * N + q];
        // Rotation angle that annihilates A(p,q) (Golub & Van Loan, Alg. 8.4.2), stable form.
        const double theta = (aqq - app) / (2.0 * apq);
        const double t = (theta >= 0 ? 1.0 : -1.0) / (std::fabs(theta) + std::sqrt(theta * theta + 1.0));
        const double c = 1.0 / std::sqrt(t * t + 1.0), s = t * c;
        for (int k = 0; k < N; ++k) {  // A <- A J (columns p, q)
          const double akp = A[k * N + p], akq = A[k * N + q];
          A[k * N + p] = c * akp - s * akq;
          A[k * N + q] = s * akp + c * akq;
        }
        for (int k = 0; k < N; ++k) {  // A <- J^T A (rows p, q)
          const double apk = A[p * N + k], aqk = A[q * N + k];
          A[p * N + k] = c * apk - s * aqk;
          A[q * N + k] = s * apk + c * aqk;
        }
        A[p * N + q] = A[q * N + p] = 0.0;
        for (int k = 0; k < N; ++k) {  // Q <- Q J
          const double qkp = Q[k * N + p], qkq = Q[k * N + q];
          Q[k * N + p] = c * qkp - s * qkq;
          Q[k * N + q] = s * qkp + c * qkq;
        }
      }
    }
  }
  for (int k = 0; k < N; ++k) evals[k] = A[k * N + k];
}

}  // namespace sinew
