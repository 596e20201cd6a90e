// The pieces of barrier self contact (ContactSettings::barrier; terms/contact.hpp), in the manner of
// Incremental Potential Contact (Li et al. 2020): the unsigned distance between a surface vertex and a
// surface triangle, with its gradient and Hessian in the twelve coordinates; a log barrier in the
// squared distance that grows without bound as the two touch; and a continuous collision test (additive
// CCD, Li, Kaufman and Jiang 2021) that bounds a step so that no vertex passes through a triangle.
// Where the paper's penalty springs (Sec. 6) act on a plane frozen when the pair was found, the barrier's
// distance follows the surface inside Newton: a crease's samples cannot slide past a frozen plane into
// the body, because no state the line search accepts has one on the other side of a face.
#pragma once

#include <sinew/core/sym_eigen.hpp>
#include <sinew/discretization/geometry.hpp>

#include <algorithm>
#include <cmath>

namespace sinew::barrier {

// A number with its gradient and Hessian in N variables (forward-mode second derivatives): the distance
// formulas below are rational in the coordinates, so + - * / are all they need.
template <int N>
struct Hyper {
  double v = 0.0, g[N] = {}, h[N * N] = {};
  static Hyper variable(double value, int i) {
    Hyper r;
    r.v = value;
    r.g[i] = 1.0;
    return r;
  }
  friend Hyper operator+(const Hyper& a, const Hyper& b) {
    Hyper r;
    r.v = a.v + b.v;
    for (int i = 0; i < N; ++i) r.g[i] = a.g[i] + b.g[i];
    for (int i = 0; i < N * N; ++i) r.h[i] = a.h[i] + b.h[i];
    return r;
  }
  friend Hyper operator-(const Hyper& a, const Hyper& b) {
    Hyper r;
    r.v = a.v - b.v;
    for (int i = 0; i < N; ++i) r.g[i] = a.g[i] - b.g[i];
    for (int i = 0; i < N * N; ++i) r.h[i] = a.h[i] - b.h[i];
    return r;
  }
  friend Hyper operator*(const Hyper& a, const Hyper& b) {
    Hyper r;
    r.v = a.v * b.v;
    for (int i = 0; i < N; ++i) r.g[i] = a.v * b.g[i] + b.v * a.g[i];
    for (int i = 0; i < N; ++i)
      for (int j = 0; j < N; ++j) r.h[i * N + j] = a.v * b.h[i * N + j] + b.v * a.h[i * N + j] + a.g[i] * b.g[j] + b.g[i] * a.g[j];
    return r;
  }
  // 1 / b: gradient -g / v^2, Hessian 2 g g^T / v^3 - h / v^2.
  friend Hyper inverse(const Hyper& b) {
    Hyper r;
    const double i1 = 1.0 / b.v, i2 = i1 * i1;
    r.v = i1;
    for (int i = 0; i < N; ++i) r.g[i] = -b.g[i] * i2;
    for (int i = 0; i < N; ++i)
      for (int j = 0; j < N; ++j) r.h[i * N + j] = 2.0 * b.g[i] * b.g[j] * i2 * i1 - b.h[i * N + j] * i2;
    return r;
  }
  friend Hyper operator/(const Hyper& a, const Hyper& b) { return a * inverse(b); }
};

template <class T>
struct V3 {
  T x, y, z;
  friend V3 operator-(const V3& a, const V3& b) { return {a.x - b.x, a.y - b.y, a.z - b.z}; }
  friend T dot(const V3& a, const V3& b) { return a.x * b.x + a.y * b.y + a.z * b.z; }
  friend V3 cross(const V3& a, const V3& b) { return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x}; }
};

// Which part of the triangle (a, b, c) is closest to p: the face, an edge (0: a-b, 1: b-c, 2: c-a) or a
// vertex (0: a, 1: b, 2: c). The squared distance to that part is smooth in the twelve coordinates; the
// squared distance to the triangle is C1 across the parts' borders (that of a convex set).
struct Feature {
  enum Kind { Face, Edge, Vertex } kind = Face;
  int index = 0;
};
inline Feature closest_feature(const geom::Vec& p, const geom::Vec& a, const geom::Vec& b, const geom::Vec& c) {
  double w[3];
  geom::closest_on_triangle(p, a, b, c, w);
  const bool on[3] = {w[0] > 1e-12, w[1] > 1e-12, w[2] > 1e-12};
  const int n = on[0] + on[1] + on[2];
  if (n == 3) return {Feature::Face, 0};
  if (n == 1) return {Feature::Vertex, on[0] ? 0 : (on[1] ? 1 : 2)};
  return {Feature::Edge, !on[2] ? 0 : (!on[0] ? 1 : 2)};  // the edge whose end points carry the weight
}

// The squared distance from p to the feature f of the triangle (a, b, c), its gradient and Hessian in
// (p, a, b, c) (12 coordinates, row-major Hessian).
struct Distance2 {
  double value, grad[12], hess[144];
};
inline Distance2 distance2(const geom::Vec& p, const geom::Vec& a, const geom::Vec& b, const geom::Vec& c, Feature f) {
  using H = Hyper<12>;
  const geom::Vec* pts[4] = {&p, &a, &b, &c};
  V3<H> x[4];
  for (int k = 0; k < 4; ++k) x[k] = {H::variable((*pts[k])[0], 3 * k), H::variable((*pts[k])[1], 3 * k + 1), H::variable((*pts[k])[2], 3 * k + 2)};
  H d2;
  if (f.kind == Feature::Face) {  // ((p - a) . n)^2 / |n|^2, n = (b - a) x (c - a)
    const V3<H> n = cross(x[2] - x[1], x[3] - x[1]);
    const H s = dot(x[0] - x[1], n);
    d2 = s * s / dot(n, n);
  } else if (f.kind == Feature::Edge) {  // |p - e0|^2 - ((p - e0) . e)^2 / |e|^2
    const V3<H>& e0 = x[1 + f.index];
    const V3<H> e = x[1 + (f.index + 1) % 3] - e0, r = x[0] - e0;
    const H s = dot(r, e);
    d2 = dot(r, r) - s * s / dot(e, e);
  } else {
    const V3<H> r = x[0] - x[1 + f.index];
    d2 = dot(r, r);
  }
  Distance2 out;
  out.value = d2.v;
  std::copy(d2.g, d2.g + 12, out.grad);
  std::copy(d2.h, d2.h + 144, out.hess);
  return out;
}

// The barrier in the squared distance D below D^ = dhat^2 (IPC's b(d, dhat) written in d^2): zero with
// its first two derivatives at D^, +inf at D = 0.
//   b(D) = -(D - D^)^2 ln(D / D^),  b' = -2 (D - D^) ln(D / D^) - (D - D^)^2 / D,
//   b'' = -2 ln(D / D^) - 4 (D - D^) / D + (D - D^)^2 / D^2.
struct Law {
  double e, d1, d2;
};
inline Law law(double D, double Dhat) {
  if (!(D < Dhat)) return {0.0, 0.0, 0.0};
  if (!(D > 0.0)) return {HUGE_VAL, -HUGE_VAL, HUGE_VAL};
  const double r = D - Dhat, l = std::log(D / Dhat);
  return {-r * r * l, -2.0 * r * l - r * r / D, -2.0 * l - 4.0 * r / D + r * r / (D * D)};
}

// H (12 x 12, symmetric, row-major) with its negative eigenvalues set to zero.
inline void project_psd(double* H) {
  double A[144], lambda[12], Q[144];
  std::copy(H, H + 144, A);
  jacobi_eigen<12>(A, lambda, Q);
  bool negative = false;
  for (double l : lambda) negative = negative || l < 0.0;
  if (!negative) return;
  for (int i = 0; i < 12; ++i)
    for (int j = 0; j < 12; ++j) {
      double s = 0.0;
      for (int k = 0; k < 12; ++k)
        if (lambda[k] > 0.0) s += Q[i * 12 + k] * lambda[k] * Q[j * 12 + k];
      H[i * 12 + j] = s;
    }
}

inline double point_triangle_distance(const geom::Vec& p, const geom::Vec& a, const geom::Vec& b, const geom::Vec& c) {
  using namespace geom;
  double w[3];
  return std::sqrt(geom::distance2(p, geom::closest_on_triangle(p, a, b, c, w)));
}

// Additive CCD (Li, Kaufman and Jiang 2021, Alg. 1) of a vertex p moving by dp against a triangle
// (a, b, c) moving by (da, db, dc), linearly over t in [0, t_max]: the distance changes no faster than
// L, a bound on the relative motion, so an advance by less than d / L cannot pass through. Returns a t
// at which the distance is still at least `keep` times the distance at 0 (t_max when the motion never
// comes that near), after at most `iterations` advances (then the t reached: conservative).
inline double vertex_triangle_toi(const geom::Vec& p, const geom::Vec& a, const geom::Vec& b, const geom::Vec& c, const geom::Vec& dp,
                                  const geom::Vec& da, const geom::Vec& db, const geom::Vec& dc, double t_max, double keep = 0.1,
                                  int iterations = 200) {
  using namespace geom;
  const Vec mean = 0.25 * (dp + da + db + dc);
  const double lp = geom::norm(dp - mean) + std::max({geom::norm(da - mean), geom::norm(db - mean), geom::norm(dc - mean)});
  if (!(lp > 0.0)) return t_max;
  const double d0 = point_triangle_distance(p, a, b, c);
  if (!(d0 > 0.0)) return 0.0;
  // Over [t, t + (d - floor) / L] the distance stays above floor; 0.9 of that per advance, until the
  // end of the interval or until the distance has come within 1% of the floor (the approach converges
  // there geometrically: a collision).
  const double floor = keep * d0;
  double t = 0.0, d = d0;
  for (int k = 0; k < iterations; ++k) {
    const double advance = 0.9 * (d - floor) / lp;
    if (t + advance >= t_max) return t_max;
    t += advance;
    d = point_triangle_distance(p + t * dp, a + t * da, b + t * db, c + t * dc);
    if (d - floor <= 0.01 * floor) return t;
  }
  return t;
}

}  // namespace sinew::barrier
