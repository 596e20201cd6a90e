// The pieces of barrier self contact (ContactSettings::barrier; terms/contact.hpp), in the manner of
// Incremental Potential Contact (Li et al. 2020): the unsigned distance between a surface vertex and a
// surface triangle, with its gradient and Hessian in the twelve coordinates; a log barrier in the
// squared distance that grows without bound as the two touch; and a continuous collision test (additive
// CCD, Li, Kaufman and Jiang 2021) that bounds a step so that no vertex passes through a triangle; and
// the same for two edges (ContactSettings::edge_pairs), with IPC's mollifier for near-parallel edges.
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

// Additive CCD (Li, Kaufman and Jiang 2021, Alg. 1) along a linear motion over t in [0, t_max]: the
// distance dist(t) changes no faster than L, a bound on the pair's relative motion, so an advance by
// less than d / L cannot pass through. Returns a t at which the distance is still at least `keep` times
// the distance at 0 (t_max when the motion never comes that near), after at most `iterations` advances
// (then the t reached: conservative).
template <class Dist>
double additive_toi(Dist&& dist, double L, double t_max, double keep, int iterations) {
  if (!(L > 0.0)) return t_max;
  const double d0 = dist(0.0);
  if (!(d0 > 0.0)) return 0.0;
  // Over [t, t + (d - floor) / L] the distance stays above floor; 0.9 of that per advance, until the
  // end of the interval or until the distance has come within 1% of the floor (the approach converges
  // there geometrically: a collision).
  const double floor = keep * d0;
  double t = 0.0, d = d0;
  for (int k = 0; k < iterations; ++k) {
    const double advance = 0.9 * (d - floor) / L;
    if (t + advance >= t_max) return t_max;
    t += advance;
    d = dist(t);
    if (d - floor <= 0.01 * floor) return t;
  }
  return t;
}

// A vertex p moving by dp against a triangle (a, b, c) moving by (da, db, dc) (additive_toi).
inline double vertex_triangle_toi(const geom::Vec& p, const geom::Vec& a, const geom::Vec& b, const geom::Vec& c, const geom::Vec& dp,
                                  const geom::Vec& da, const geom::Vec& db, const geom::Vec& dc, double t_max, double keep = 0.1,
                                  int iterations = 200) {
  using namespace geom;
  const Vec mean = 0.25 * (dp + da + db + dc);
  const double L = geom::norm(dp - mean) + std::max({geom::norm(da - mean), geom::norm(db - mean), geom::norm(dc - mean)});
  return additive_toi([&](double t) { return point_triangle_distance(p + t * dp, a + t * da, b + t * db, c + t * dc); }, L, t_max,
                      keep, iterations);
}

// ---- edge-edge pairs ------------------------------------------------------------------------------------
// Point-triangle pairs keep every vertex out of every face, but two edges can still pass through each
// other with no vertex crossing a face (two blades crossing; a convex lattice corner swept through
// another part's edge). IPC therefore adds the edge-edge distance, with a mollifier that fades the
// barrier out as the edges turn parallel, where the edge-edge distance stops being smooth (Li et al.
// 2020, Sec. 4.3).

// The parameters s, t in [0, 1] of the closest points of the segments (a0, a1) and (b0, b1) (Ericson,
// Real-Time Collision Detection, 5.1.9; parallel segments take s = 0).
inline void closest_segment_parameters(const geom::Vec& a0, const geom::Vec& a1, const geom::Vec& b0, const geom::Vec& b1, double& s,
                                       double& t) {
  using namespace geom;
  const Vec d1 = a1 - a0, d2 = b1 - b0, r = a0 - b0;
  const double a = dot(d1, d1), e = dot(d2, d2), f = dot(d2, r);
  s = t = 0.0;
  if (!(a > 0.0) && !(e > 0.0)) return;
  if (!(a > 0.0)) {
    t = std::clamp(f / e, 0.0, 1.0);
    return;
  }
  const double c = dot(d1, r);
  if (!(e > 0.0)) {
    s = std::clamp(-c / a, 0.0, 1.0);
    return;
  }
  const double b = dot(d1, d2), denom = a * e - b * b;
  s = denom > 1e-14 * a * e ? std::clamp((b * f - c * e) / denom, 0.0, 1.0) : 0.0;
  t = (b * s + f) / e;
  if (t < 0.0) {
    t = 0.0;
    s = std::clamp(-c / a, 0.0, 1.0);
  } else if (t > 1.0) {
    t = 1.0;
    s = std::clamp((b - c) / a, 0.0, 1.0);
  }
}

inline double segment_distance(const geom::Vec& a0, const geom::Vec& a1, const geom::Vec& b0, const geom::Vec& b1) {
  using namespace geom;
  double s, t;
  closest_segment_parameters(a0, a1, b0, b1, s, t);
  return std::sqrt(geom::distance2(a0 + s * (a1 - a0), b0 + t * (b1 - b0)));
}

// Which parts of the segments are closest: their interiors (the lines' distance), an end point of one
// and the other's interior, or two end points. Points are numbered a0, a1, b0, b1 (0-3).
struct EdgeFeature {
  enum Kind { Lines, PointEdge, Points } kind = Lines;
  int p = 0, q = 0;  // PointEdge: point p, edge q (0: a, 1: b); Points: points p and q
};
inline EdgeFeature closest_edge_feature(const geom::Vec& a0, const geom::Vec& a1, const geom::Vec& b0, const geom::Vec& b1) {
  double s, t;
  closest_segment_parameters(a0, a1, b0, b1, s, t);
  const double tol = 1e-12;
  const bool s_in = s > tol && s < 1.0 - tol, t_in = t > tol && t < 1.0 - tol;
  const int sa = s < 0.5 ? 0 : 1, tb = t < 0.5 ? 2 : 3;
  if (s_in && t_in) return {EdgeFeature::Lines, 0, 0};
  if (s_in) return {EdgeFeature::PointEdge, tb, 0};
  if (t_in) return {EdgeFeature::PointEdge, sa, 1};
  return {EdgeFeature::Points, sa, tb};
}

// f(x) with x a Hyper: the chain rule with f's value and first two derivatives at x.v.
template <int N>
Hyper<N> chain(const Hyper<N>& x, double f, double f1, double f2) {
  Hyper<N> r;
  r.v = f;
  for (int i = 0; i < N; ++i) r.g[i] = f1 * x.g[i];
  for (int i = 0; i < N; ++i)
    for (int j = 0; j < N; ++j) r.h[i * N + j] = f2 * x.g[i] * x.g[j] + f1 * x.h[i * N + j];
  return r;
}

// The mollified edge-edge barrier per unit of stiffness, m(c) b(D), with its gradient and Hessian in
// (a0, a1, b0, b1) (Distance2's layout): D the squared distance of `feature`, c = |(a1 - a0) x (b1 - b0)|^2,
// m(c) = (2 - c / eps) c / eps below eps and 1 above (C1 in c; IPC's e_k, with eps = 1e-3 |A1 - A0|^2
// |B1 - B0|^2 at rest), so that the energy vanishes as the edges turn parallel instead of jumping.
inline Distance2 edge_edge_barrier(const geom::Vec& a0, const geom::Vec& a1, const geom::Vec& b0, const geom::Vec& b1, EdgeFeature f,
                                   double Dhat, double eps) {
  using H = Hyper<12>;
  const geom::Vec* pts[4] = {&a0, &a1, &b0, &b1};
  V3<H> x[4];
  for (int k = 0; k < 4; ++k) x[k] = {H::variable((*pts[k])[0], 3 * k), H::variable((*pts[k])[1], 3 * k + 1), H::variable((*pts[k])[2], 3 * k + 2)};
  const V3<H> ea = x[1] - x[0], eb = x[3] - x[2];
  const V3<H> n = cross(ea, eb);
  H D;
  if (f.kind == EdgeFeature::Lines) {  // ((a0 - b0) . n)^2 / |n|^2
    const H s = dot(x[0] - x[2], n);
    D = s * s / dot(n, n);
  } else if (f.kind == EdgeFeature::PointEdge) {  // |p - e0|^2 - ((p - e0) . e)^2 / |e|^2
    const V3<H>& e0 = x[2 * f.q];
    const V3<H> e = f.q == 0 ? ea : eb, r = x[f.p] - e0;
    const H s = dot(r, e);
    D = dot(r, r) - s * s / dot(e, e);
  } else {
    const V3<H> r = x[f.p] - x[f.q];
    D = dot(r, r);
  }
  Distance2 out{};
  const Law b = law(D.v, Dhat);
  if (b.e == 0.0) return out;
  const H B = chain(D, b.e, b.d1, b.d2);
  const H c = dot(n, n);
  H E = B;
  if (c.v < eps) {
    const double y = c.v / eps;
    E = chain(c, (2.0 - y) * y, (2.0 - 2.0 * y) / eps, -2.0 / (eps * eps)) * B;
  }
  out.value = E.v;
  std::copy(E.g, E.g + 12, out.grad);
  std::copy(E.h, E.h + 144, out.hess);
  return out;
}

// An edge (a0, a1) moving by (da0, da1) against an edge (b0, b1) moving by (db0, db1) (additive_toi).
inline double edge_edge_toi(const geom::Vec& a0, const geom::Vec& a1, const geom::Vec& b0, const geom::Vec& b1, const geom::Vec& da0,
                            const geom::Vec& da1, const geom::Vec& db0, const geom::Vec& db1, double t_max, double keep = 0.1,
                            int iterations = 200) {
  using namespace geom;
  const Vec mean = 0.25 * (da0 + da1 + db0 + db1);
  const double L = std::max(geom::norm(da0 - mean), geom::norm(da1 - mean)) + std::max(geom::norm(db0 - mean), geom::norm(db1 - mean));
  return additive_toi([&](double t) { return segment_distance(a0 + t * da0, a1 + t * da1, b0 + t * db0, b1 + t * db1); }, L, t_max,
                      keep, iterations);
}

}  // namespace sinew::barrier
