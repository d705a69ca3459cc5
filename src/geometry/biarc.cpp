// Biarc and chord fitting of planar curves within a deviation tolerance (geometry.hpp). Each piece
// [u_a, u_b] gets the equal-tangent-length biarc through its end points with the curve's end
// tangents; if the curve strays from it by more than the tolerance (checked at interior
// samples, with a safety margin) the piece is halved. The result is tangent-continuous.
#include <algorithm>
#include <array>
#include <cmath>

#include "trochomill/error.hpp"
#include "trochomill/geometry.hpp"

namespace trochomill {
namespace {

constexpr int kCheckSamples = 24;  // interior samples per piece for the deviation check
constexpr double kSafety = 0.8;    // accept a piece below 0.8 * tolerance at the samples
constexpr int kMaxDepth = 30;

double cross2(double ax, double ay, double bx, double by) { return ax * by - ay * bx; }

// Arc from A with unit tangent T to B (planar, z = A.z).
FitArc arc_from_tangent(const Vec3& A, const Vec3& T, const Vec3& B) {
  FitArc arc;
  arc.start = A;
  arc.end = B;
  const double cx = B.x() - A.x(), cy = B.y() - A.y();
  const double chord2 = cx * cx + cy * cy;
  const double nc = cross2(T.x(), T.y(), cx, cy);  // left normal n = (-Ty, Tx): n.c = T x c
  if (std::abs(nc) <= 1e-12 * std::max(1.0, chord2)) {
    arc.is_line = true;
    return arc;
  }
  const double rho = chord2 / (2.0 * nc);  // signed radius, > 0 turns left (ccw)
  arc.cx = A.x() - rho * T.y();
  arc.cy = A.y() + rho * T.x();
  arc.radius_mm = std::abs(rho);
  arc.sweep_rad = 2.0 * std::atan2(nc, T.x() * cx + T.y() * cy);
  return arc;
}

double distance_to_arc(const FitArc& arc, const Vec3& p) {
  if (arc.is_line) {
    const Vec3 d = arc.end - arc.start;
    const double L2 = d.x() * d.x() + d.y() * d.y();
    double t =
        L2 > 0 ? ((p.x() - arc.start.x()) * d.x() + (p.y() - arc.start.y()) * d.y()) / L2 : 0;
    t = std::clamp(t, 0.0, 1.0);
    return std::hypot(p.x() - arc.start.x() - t * d.x(), p.y() - arc.start.y() - t * d.y());
  }
  const double a0 = std::atan2(arc.start.y() - arc.cy, arc.start.x() - arc.cx);
  const double ap = std::atan2(p.y() - arc.cy, p.x() - arc.cx);
  double rel = ap - a0;  // angle from the start in the arc's direction
  if (arc.sweep_rad >= 0) {
    rel = std::fmod(rel, 2 * M_PI);
    if (rel < 0) rel += 2 * M_PI;
  } else {
    rel = std::fmod(-rel, 2 * M_PI);
    if (rel < 0) rel += 2 * M_PI;
  }
  if (rel <= std::abs(arc.sweep_rad)) {
    return std::abs(std::hypot(p.x() - arc.cx, p.y() - arc.cy) - arc.radius_mm);
  }
  return std::min(std::hypot(p.x() - arc.start.x(), p.y() - arc.start.y()),
                  std::hypot(p.x() - arc.end.x(), p.y() - arc.end.y()));
}

// The equal-tangent-length biarc through P0 (tangent T0) and P1 (tangent T1).
bool biarc(const Vec3& P0, const Vec3& T0, const Vec3& P1, const Vec3& T1, FitArc& a1, FitArc& a2) {
  const Vec3 v = P1 - P0;
  const Vec3 t = T0 + T1;
  const double vt = v.dot(t), vv = v.dot(v), tt = t.dot(t);
  double d;
  const double denom = 4.0 - tt;  // = 2 - 2 T0.T1 >= 0
  if (denom <= 1e-12) {
    if (std::abs(vt) <= 1e-15) return false;
    d = vv / (2.0 * vt);
  } else {
    d = (-vt + std::sqrt(vt * vt + denom * vv)) / denom;
  }
  if (!(d > 0) || !std::isfinite(d)) return false;
  const Vec3 J = 0.5 * ((P0 + d * T0) + (P1 - d * T1));
  a1 = arc_from_tangent(P0, T0, J);
  // Second arc: from J to P1 with the tangent that arrives along T1; build it backwards.
  FitArc back = arc_from_tangent(P1, -T1, J);
  a2 = back;
  a2.start = J;
  a2.end = P1;
  a2.sweep_rad = -back.sweep_rad;
  return true;
}

void fit_piece(const PlanarCurve& c, double ua, double ub, double tol, int depth,
               std::vector<FitArc>& out) {
  const Vec3 P0 = c.point(ua), P1 = c.point(ub);
  const Vec3 T0 = c.unit_tangent(ua), T1 = c.unit_tangent(ub);
  FitArc a1, a2;
  bool ok = T0.squaredNorm() > 0 && T1.squaredNorm() > 0 && biarc(P0, T0, P1, T1, a1, a2);
  // A biarc arc turning 135 degrees or more over a piece this short is a loop, however close
  // the curve's samples lie to it: halve the piece instead.
  ok = ok && std::abs(a1.sweep_rad) < 0.75 * M_PI && std::abs(a2.sweep_rad) < 0.75 * M_PI;
  if (ok) {
    for (int k = 1; k < kCheckSamples && ok; ++k) {
      const Vec3 p = c.point(ua + (ub - ua) * k / kCheckSamples);
      ok = std::min(distance_to_arc(a1, p), distance_to_arc(a2, p)) <= kSafety * tol;
    }
  }
  if (ok || depth >= kMaxDepth) {
    if (!ok) {
      throw Error("biarc fit did not converge: the curve has a feature below the tolerance");
    }
    out.push_back(a1);
    out.push_back(a2);
    return;
  }
  const double um = 0.5 * (ua + ub);
  fit_piece(c, ua, um, tol, depth + 1, out);
  fit_piece(c, um, ub, tol, depth + 1, out);
}

double chord_deviation(const PlanarCurve& c, double ua, double ub) {
  const Vec3 A = c.point(ua), B = c.point(ub);
  const Vec3 d = B - A;
  const double L2 = d.squaredNorm();
  double dev = 0;
  for (int k = 1; k < kCheckSamples; ++k) {
    const Vec3 p = c.point(ua + (ub - ua) * k / kCheckSamples);
    const double t = L2 > 0 ? std::clamp((p - A).dot(d) / L2, 0.0, 1.0) : 0.0;
    dev = std::max(dev, (p - A - t * d).norm());
  }
  return dev;
}

void chord_piece(const PlanarCurve& c, double ua, double ub, double tol, int depth,
                 std::vector<Vec3>& out) {
  if (chord_deviation(c, ua, ub) <= kSafety * tol || depth >= kMaxDepth) {
    out.push_back(c.point(ub));
    return;
  }
  const double um = 0.5 * (ua + ub);
  chord_piece(c, ua, um, tol, depth + 1, out);
  chord_piece(c, um, ub, tol, depth + 1, out);
}

}  // namespace

std::vector<FitArc> fit_biarcs(const PlanarCurve& curve, double u0, double u1, int pieces,
                               double tolerance_mm) {
  if (!(tolerance_mm > 0)) throw InputError("arc tolerance must be > 0 mm");
  std::vector<FitArc> out;
  const int n = std::max(1, pieces);
  const double du = (u1 - u0) / n;
  for (int i = 0; i < n; ++i)
    fit_piece(curve, u0 + du * i, u0 + du * (i + 1), tolerance_mm, 0, out);
  return out;
}

std::vector<Vec3> fit_chords(const PlanarCurve& curve, double u0, double u1, int pieces,
                             double tolerance_mm) {
  if (!(tolerance_mm > 0)) throw InputError("arc tolerance must be > 0 mm");
  std::vector<Vec3> out;
  const int n = std::max(1, pieces);
  const double du = (u1 - u0) / n;
  for (int i = 0; i < n; ++i)
    chord_piece(curve, u0 + du * i, u0 + du * (i + 1), tolerance_mm, 0, out);
  return out;
}

ContourPiece to_piece(const FitArc& a) {
  const Vec2 s(a.start.x(), a.start.y()), e(a.end.x(), a.end.y());
  if (a.is_line) return ContourPiece::line(s, e);
  return ContourPiece::arc(s, e, Vec2(a.cx, a.cy), a.sweep_rad >= 0);
}

}  // namespace trochomill
