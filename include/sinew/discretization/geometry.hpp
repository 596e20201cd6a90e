// Small geometry for contact and colliders: 3-vectors, closest points on triangles and segments,
// barycentric coordinates in a tetrahedron, axis-aligned boxes. Host only.
#pragma once

#include <algorithm>
#include <array>
#include <cmath>

namespace sinew::geom {

using Vec = std::array<double, 3>;

inline Vec operator+(const Vec& a, const Vec& b) { return {a[0] + b[0], a[1] + b[1], a[2] + b[2]}; }
inline Vec operator-(const Vec& a, const Vec& b) { return {a[0] - b[0], a[1] - b[1], a[2] - b[2]}; }
inline Vec operator*(double s, const Vec& a) { return {s * a[0], s * a[1], s * a[2]}; }
inline double dot(const Vec& a, const Vec& b) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }
inline Vec cross(const Vec& a, const Vec& b) {
  return {a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]};
}
inline double norm(const Vec& a) { return std::sqrt(dot(a, a)); }
inline double distance2(const Vec& a, const Vec& b) { return dot(a - b, a - b); }
inline Vec normalized(const Vec& a) {
  const double n = norm(a);
  return n > 0.0 ? (1.0 / n) * a : Vec{0.0, 0.0, 0.0};
}

// The point of triangle (a, b, c) closest to p, with its barycentric coordinates (w[0] a + w[1] b + w[2] c),
// by Voronoi regions (Ericson, Real-Time Collision Detection, 5.1.5). Degenerate triangles give a point
// on an edge or a vertex.
inline Vec closest_on_triangle(const Vec& p, const Vec& a, const Vec& b, const Vec& c, double w[3]) {
  const Vec ab = b - a, ac = c - a, ap = p - a;
  const double d1 = dot(ab, ap), d2 = dot(ac, ap);
  if (d1 <= 0.0 && d2 <= 0.0) {
    w[0] = 1.0, w[1] = 0.0, w[2] = 0.0;
    return a;
  }
  const Vec bp = p - b;
  const double d3 = dot(ab, bp), d4 = dot(ac, bp);
  if (d3 >= 0.0 && d4 <= d3) {
    w[0] = 0.0, w[1] = 1.0, w[2] = 0.0;
    return b;
  }
  const double vc = d1 * d4 - d3 * d2;
  if (vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0) {
    const double v = d1 / (d1 - d3);
    w[0] = 1.0 - v, w[1] = v, w[2] = 0.0;
    return a + v * ab;
  }
  const Vec cp = p - c;
  const double d5 = dot(ab, cp), d6 = dot(ac, cp);
  if (d6 >= 0.0 && d5 <= d6) {
    w[0] = 0.0, w[1] = 0.0, w[2] = 1.0;
    return c;
  }
  const double vb = d5 * d2 - d1 * d6;
  if (vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0) {
    const double v = d2 / (d2 - d6);
    w[0] = 1.0 - v, w[1] = 0.0, w[2] = v;
    return a + v * ac;
  }
  const double va = d3 * d6 - d5 * d4;
  if (va <= 0.0 && (d4 - d3) >= 0.0 && (d5 - d6) >= 0.0) {
    const double v = (d4 - d3) / ((d4 - d3) + (d5 - d6));
    w[0] = 0.0, w[1] = 1.0 - v, w[2] = v;
    return b + v * (c - b);
  }
  const double denom = va + vb + vc;
  if (!(std::fabs(denom) > 0.0)) {  // a degenerate triangle: its first vertex
    w[0] = 1.0, w[1] = 0.0, w[2] = 0.0;
    return a;
  }
  const double v = vb / denom, t = vc / denom;
  w[0] = 1.0 - v - t, w[1] = v, w[2] = t;
  return a + v * ab + t * ac;
}

// The parameter s in [0, 1] of the point of segment (a, b) closest to p.
inline double closest_on_segment(const Vec& p, const Vec& a, const Vec& b) {
  const Vec ab = b - a;
  const double l2 = dot(ab, ab);
  if (!(l2 > 0.0)) return 0.0;
  return std::clamp(dot(p - a, ab) / l2, 0.0, 1.0);
}

// Six times the signed volume of tetrahedron (a, b, c, d): positive when (b - a, c - a, d - a) is right-handed.
inline double tet_volume6(const Vec& a, const Vec& b, const Vec& c, const Vec& d) { return dot(b - a, cross(c - a, d - a)); }

// Whether segment pq passes through the interior of triangle abc: p and q strictly on opposite sides of
// its plane, and the line pq strictly inside its three edges (the signs of the volumes pq makes with
// each edge agree). Touching (an end point on the plane, the line through an edge or corner) is not a
// crossing: what counts is a surface edge through a face, which no state of a valid surface has.
inline bool segment_crosses_triangle(const Vec& p, const Vec& q, const Vec& a, const Vec& b, const Vec& c) {
  const double sp = tet_volume6(a, b, c, p), sq = tet_volume6(a, b, c, q);
  if (!((sp > 0.0 && sq < 0.0) || (sp < 0.0 && sq > 0.0))) return false;
  const double u = tet_volume6(p, q, a, b), v = tet_volume6(p, q, b, c), w = tet_volume6(p, q, c, a);
  return (u > 0.0 && v > 0.0 && w > 0.0) || (u < 0.0 && v < 0.0 && w < 0.0);
}

// Barycentric coordinates of p in tetrahedron (a, b, c, d); false for a degenerate one.
inline bool tet_barycentric(const Vec& p, const Vec& a, const Vec& b, const Vec& c, const Vec& d, double l[4]) {
  const Vec e1 = b - a, e2 = c - a, e3 = d - a, r = p - a;
  const double det = dot(e1, cross(e2, e3));
  if (!(std::fabs(det) > 0.0)) return false;
  l[1] = dot(r, cross(e2, e3)) / det;
  l[2] = dot(e1, cross(r, e3)) / det;
  l[3] = dot(e1, cross(e2, r)) / det;
  l[0] = 1.0 - l[1] - l[2] - l[3];
  return true;
}

// The signed solid angle of triangle (a, b, c) seen from p (Van Oosterom and Strackee 1983):
// tan(Omega / 2) = [a' b' c'] / (|a'||b'||c'| + (a'.b')|c'| + (a'.c')|b'| + (b'.c')|a'|), x' = x - p.
// Positive where p lies behind the triangle's right-handed normal (inside an outward surface); 0 when p is
// one of its corners. Summed over a closed surface and divided by 4 pi: the winding number of p.
inline double solid_angle(const Vec& p, const Vec& a, const Vec& b, const Vec& c) {
  const Vec x = a - p, y = b - p, z = c - p;
  const double lx = norm(x), ly = norm(y), lz = norm(z);
  const double num = dot(x, cross(y, z));
  const double den = lx * ly * lz + dot(x, y) * lz + dot(x, z) * ly + dot(y, z) * lx;
  if (num == 0.0 && den == 0.0) return 0.0;
  return 2.0 * std::atan2(num, den);
}

struct Box {
  Vec lo{HUGE_VAL, HUGE_VAL, HUGE_VAL}, hi{-HUGE_VAL, -HUGE_VAL, -HUGE_VAL};
  void add(const Vec& p) {
    for (int i = 0; i < 3; ++i) {
      lo[i] = std::min(lo[i], p[i]);
      hi[i] = std::max(hi[i], p[i]);
    }
  }
  void add(const Box& b) {
    add(b.lo);
    add(b.hi);
  }
  void inflate(double r) {
    for (int i = 0; i < 3; ++i) {
      lo[i] -= r;
      hi[i] += r;
    }
  }
  bool contains(const Vec& p) const {
    return p[0] >= lo[0] && p[0] <= hi[0] && p[1] >= lo[1] && p[1] <= hi[1] && p[2] >= lo[2] && p[2] <= hi[2];
  }
  bool overlaps(const Box& b) const {
    return lo[0] <= b.hi[0] && b.lo[0] <= hi[0] && lo[1] <= b.hi[1] && b.lo[1] <= hi[1] && lo[2] <= b.hi[2] && b.lo[2] <= hi[2];
  }
  // Squared distance from p to the box (0 inside).
  double distance2(const Vec& p) const {
    double d = 0.0;
    for (int i = 0; i < 3; ++i) {
      const double e = p[i] < lo[i] ? lo[i] - p[i] : (p[i] > hi[i] ? p[i] - hi[i] : 0.0);
      d += e * e;
    }
    return d;
  }
  Vec center() const { return 0.5 * (lo + hi); }
};

}  // namespace sinew::geom
