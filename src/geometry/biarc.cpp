// Biarc and chord fitting of planar curves within a deviation tolerance (geometry.hpp). Each piece
// [u_a, u_b] gets the equal-tangent-length biarc through its end points with the curve's end
// tangents, accepted where the curve stays within the tolerance of it (checked at interior
// samples, with a safety margin); each piece as long as such a biarc allows. The result is
// tangent-continuous.
#include <algorithm>
#include <array>
#include <cmath>
#include <optional>
#include <utility>
#include <vector>

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

// The biarc through P0 (tangent T0) and P1 (tangent T1) whose first tangent length is `ratio`
// times its second (1: the equal-tangent-length biarc). With v = P1 - P0 and tangent lengths
// d1 = ratio d2, the junction's condition |v - d1 T0 - d2 T1| = d1 + d2 is the quadratic
// (1 - T0.T1) 2 ratio d2^2 + 2 (ratio v.T0 + v.T1) d2 - v.v = 0 in d2; its positive root.
bool biarc(const Vec3& P0, const Vec3& T0, const Vec3& P1, const Vec3& T1, double ratio, FitArc& a1,
           FitArc& a2) {
  const Vec3 v = P1 - P0;
  const double qa = 2.0 * ratio * (1.0 - T0.dot(T1));
  const double qb = 2.0 * (ratio * v.dot(T0) + v.dot(T1));
  const double vv = v.dot(v);
  double d2;
  if (qa <= 1e-12) {
    if (std::abs(qb) <= 1e-15) return false;
    d2 = vv / qb;
  } else {
    // The root (-qb + sqrt(qb^2 + 4 qa vv)) / (2 qa), written without cancellation.
    const double disc = std::sqrt(qb * qb + 4.0 * qa * vv);
    d2 = qb >= 0 ? 2.0 * vv / (qb + disc) : (-qb + disc) / (2.0 * qa);
  }
  const double d1 = ratio * d2;
  if (!(d1 > 0) || !(d2 > 0) || !std::isfinite(d1) || !std::isfinite(d2)) return false;
  // The junction divides the segment between the two tangent ends in the ratio d1 : d2.
  const Vec3 Q0 = P0 + d1 * T0, Q1 = P1 - d2 * T1;
  const Vec3 J = Q0 + (d1 / (d1 + d2)) * (Q1 - Q0);
  a1 = arc_from_tangent(P0, T0, J);
  // Second arc: from J to P1 with the tangent that arrives along T1; build it backwards.
  FitArc back = arc_from_tangent(P1, -T1, J);
  a2 = back;
  a2.start = J;
  a2.end = P1;
  a2.sweep_rad = -back.sweep_rad;
  return true;
}

// The biarc of the curve from ua to ub, if it stays within the tolerance (with the margin) at
// the interior samples.
bool fit_span(const PlanarCurve& c, double ua, double ub, double tol, FitArc& a1, FitArc& a2) {
  const Vec3 P0 = c.point(ua), P1 = c.point(ub);
  const Vec3 T0 = c.unit_tangent(ua), T1 = c.unit_tangent(ub);
  if (!(T0.squaredNorm() > 0) || !(T1.squaredNorm() > 0)) return false;
  // The samples coarse to fine (the middle, the quarters, the eighths, then the rest): a
  // biarc that strays usually does so at the first ones, so most rejections look at few.
  static constexpr std::array<int, kCheckSamples - 1> kOrder = {
      12, 6, 18, 3, 9, 15, 21, 1, 2, 4, 5, 7, 8, 10, 11, 13, 14, 16, 17, 19, 20, 22, 23};
  std::array<Vec3, kCheckSamples - 1> samples;
  for (std::size_t i = 0; i < kOrder.size(); ++i) {
    samples[i] = c.point(ua + (ub - ua) * kOrder[i] / kCheckSamples);
  }
  // The equal-tangent biarc first, then junctions moved towards either end (a curve whose
  // curvature changes along the piece is followed farther by unequal arcs).
  for (const double ratio : {1.0, 0.8, 1.25, 0.6, 1.0 / 0.6, 0.45, 1.0 / 0.45, 0.3, 1.0 / 0.3}) {
    if (!biarc(P0, T0, P1, T1, ratio, a1, a2)) continue;
    // A biarc arc turning 135 degrees or more over a piece this short is a loop, however close
    // the curve's samples lie to it: a shorter piece instead.
    bool ok = std::abs(a1.sweep_rad) < 0.75 * M_PI && std::abs(a2.sweep_rad) < 0.75 * M_PI;
    for (const Vec3& p : samples) {
      if (!ok) break;
      ok = std::min(distance_to_arc(a1, p), distance_to_arc(a2, p)) <= kSafety * tol;
    }
    if (ok) return true;
  }
  return false;
}

// The span [a, b] as few biarcs as the search finds: from each piece's start, the longest
// piece that fits (grown from the last piece's length by doubling, or halved until it fits,
// then bisected to within 1/16 of its length), so a curve of slowly changing curvature gets
// pieces of the length its tolerance allows rather than of a power-of-two share of the span.
void fit_span_greedy(const PlanarCurve& c, double a, double b, double tol, std::size_t max_arcs,
                     std::vector<FitArc>& out) {
  // In the share t of the span (u = a + t (b - a)): a curve may run backwards in u.
  const auto u = [&](double t) { return t >= 1 ? b : a + t * (b - a); };
  const auto fits = [&](double ta, double tb, FitArc& f1, FitArc& f2) {
    return fit_span(c, u(ta), u(tb), tol, f1, f2);
  };
  double ta = 0, guess = 1;
  FitArc a1, a2, t1, t2;
  while (ta < 1) {
    double lo = std::min(1.0, ta + guess), hi = 1;
    bool bracketed = false;  // hi fails
    if (fits(ta, lo, a1, a2)) {
      while (lo < 1) {
        const double t = std::min(1.0, ta + 2 * (lo - ta));
        if (!fits(ta, t, t1, t2)) {
          hi = t;
          bracketed = true;
          break;
        }
        lo = t, a1 = t1, a2 = t2;
      }
    } else {
      bracketed = true;
      int depth = 0;
      do {
        if (++depth > kMaxDepth) {
          throw Error("biarc fit did not converge: the curve has a feature below the tolerance");
        }
        hi = lo;
        lo = ta + 0.5 * (lo - ta);
      } while (!fits(ta, lo, a1, a2));
    }
    while (bracketed && hi - lo > (lo - ta) / 16) {
      const double m = 0.5 * (lo + hi);
      if (!(m > lo && m < hi)) break;  // lo and hi adjacent doubles: a piece near u's precision
      if (fits(ta, m, t1, t2)) {
        lo = m, a1 = t1, a2 = t2;
      } else {
        hi = m;
      }
    }
    if (out.size() + 2 > max_arcs) throw ArcLimit{max_arcs};
    out.push_back(a1);
    out.push_back(a2);
    guess = lo - ta;
    ta = lo;
  }
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
                               double tolerance_mm, std::size_t max_arcs) {
  if (!(tolerance_mm > 0)) throw InputError("arc tolerance must be > 0 mm");
  std::vector<FitArc> out;
  const int n = std::max(1, pieces);
  const double du = (u1 - u0) / n;
  for (int i = 0; i < n; ++i) {
    fit_span_greedy(curve, u0 + du * i, i + 1 == n ? u1 : u0 + du * (i + 1), tolerance_mm, max_arcs,
                    out);
  }
  return out;
}

namespace {

// A curve whose unit tangent at the ends of [lo, hi] is the one-sided one from inside (the
// chord over a ten-millionth of the range): at a cusp the curve's own (central) one is not.
class OneSidedEnds final : public PlanarCurve {
 public:
  OneSidedEnds(const PlanarCurve& c, double lo, double hi) : c_(c), lo_(lo), hi_(hi) {}
  [[nodiscard]] Vec3 point(double u) const override { return c_.point(u); }
  [[nodiscard]] Vec3 unit_tangent(double u) const override {
    const double h = 1e-7 * (hi_ - lo_);
    Vec3 d;
    if (u <= lo_) {
      d = c_.point(lo_ + h) - c_.point(lo_);
    } else if (u >= hi_) {
      d = c_.point(hi_) - c_.point(hi_ - h);
    } else {
      return c_.unit_tangent(u);
    }
    d.z() = 0;
    const double n = d.norm();
    return n > 0 ? Vec3(d / n) : Vec3::Zero();
  }

 private:
  const PlanarCurve& c_;
  double lo_, hi_;
};

}  // namespace

std::vector<double> cusp_parameters(const PlanarCurve& curve, double u0, double u1, int samples) {
  std::vector<double> out;
  const int m = std::max(2, samples);
  if (!(u1 > u0)) return out;
  const auto u = [&](int i) { return u0 + (u1 - u0) * i / m; };
  std::vector<Vec3> p(static_cast<std::size_t>(m) + 1);
  for (int i = 0; i <= m; ++i) p[static_cast<std::size_t>(i)] = curve.point(u(i));
  for (int i = 0; i + 2 <= m; ++i) {
    const std::size_t k = static_cast<std::size_t>(i);
    const Vec3 a = p[k + 1] - p[k], b = p[k + 2] - p[k + 1];
    const double na = a.head<2>().norm(), nb = b.head<2>().norm();
    if (!(na > 0 && nb > 0) || a.head<2>().dot(b.head<2>()) >= -0.5 * na * nb) continue;
    // Where it moves slowest in [u_i, u_i+2] (the speed by chords a thousandth of a sample
    // apart): golden-section search.
    const double e = 1e-3 * (u(1) - u(0));
    const auto speed = [&](double x) {
      return (curve.point(std::min(u1, x + e)) - curve.point(std::max(u0, x - e))).head<2>().norm();
    };
    double lo = u(i), hi = u(i + 2);
    constexpr double g = 0.6180339887498949;
    double x1 = hi - g * (hi - lo), x2 = lo + g * (hi - lo), f1 = speed(x1), f2 = speed(x2);
    for (int it = 0; it < 60 && hi - lo > 1e-15 * std::max(1.0, std::abs(hi)); ++it) {
      if (f1 <= f2) {
        hi = x2, x2 = x1, f2 = f1, x1 = hi - g * (hi - lo), f1 = speed(x1);
      } else {
        lo = x1, x1 = x2, f1 = f2, x2 = lo + g * (hi - lo), f2 = speed(x2);
      }
    }
    const double c = 0.5 * (lo + hi);
    const double gap = 1e-6 * (u1 - u0);
    if (c > u0 + gap && c < u1 - gap && (out.empty() || c > out.back() + gap)) out.push_back(c);
    ++i;  // the next pair shares this chord: the same cusp
  }
  return out;
}

std::vector<FitArc> fit_biarcs_at_cusps(const PlanarCurve& curve, double u0, double u1, int pieces,
                                        double tolerance_mm, std::size_t max_arcs) {
  const int n = std::max(1, pieces);
  const std::vector<double> cusps = cusp_parameters(curve, u0, u1, 64 * n);
  if (cusps.empty()) return fit_biarcs(curve, u0, u1, n, tolerance_mm, max_arcs);
  std::vector<FitArc> out;
  double a = u0;
  for (std::size_t i = 0; i <= cusps.size(); ++i) {
    const double b = i < cusps.size() ? cusps[i] : u1;
    const OneSidedEnds part(curve, a, b);
    const int k = std::max(1, static_cast<int>(std::lround(n * (b - a) / (u1 - u0))));
    const std::vector<FitArc> arcs = fit_biarcs(part, a, b, k, tolerance_mm, max_arcs - out.size());
    out.insert(out.end(), arcs.begin(), arcs.end());
    a = b;
  }
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

namespace {

// The piece from points[i] to points[j] if every point between lies within tol of it: a line
// when they do, else the arc through points[i], the middle point and points[j], when each
// point between lies within tol of its circle and in order along it.
std::optional<ContourPiece> piece_through(const std::vector<Vec2>& pts, std::size_t i,
                                          std::size_t j, double tol, double bulge, bool bulge_ccw) {
  const Vec2 a = pts[i], c = pts[j];
  const Vec2 ac = c - a;
  const double L = ac.norm();
  if (j == i + 1) return ContourPiece::line(a, c);
  if (L < 1e-12) return std::nullopt;
  const Vec2 u = ac / L;
  bool line_ok = true;
  for (std::size_t k = i + 1; k < j && line_ok; ++k) {
    const Vec2 d = pts[k] - a;
    const double along = d.dot(u);
    const double off = std::abs(u.x() * d.y() - u.y() * d.x());
    line_ok = off <= tol && along >= -tol && along <= L + tol;
  }
  if (line_ok) return ContourPiece::line(a, c);
  // The chords between the points, not only the points, within tol: their middles too (on
  // the centre's side of an arc turning the `bulge_ccw` way, within `bulge`).
  auto chords_within = [&](const ContourPiece& pc) {
    for (std::size_t k = i; k < j; ++k) {
      const Vec2 mid = 0.5 * (pts[k] + pts[k + 1]);
      const double d = pc.distance_mm(mid);
      if (d <= tol) continue;
      const bool inside = pc.is_arc() && (mid - *pc.centre).norm() < pc.radius_mm();
      if (!(inside && pc.ccw == bulge_ccw && d <= bulge)) return false;
    }
    return true;
  };
  const Vec2 b = pts[(i + j) / 2];
  const Vec2 ab = b - a;
  const double cross = ab.x() * ac.y() - ab.y() * ac.x();
  if (std::abs(cross) < 1e-15) return std::nullopt;
  // Circumcentre of a, b, c.
  const double ab2 = ab.squaredNorm(), ac2 = ac.squaredNorm();
  const Vec2 centre = a + Vec2(ac.y() * ab2 - ab.y() * ac2, ab.x() * ac2 - ac.x() * ab2) /
                              (2 * (ab.x() * ac.y() - ab.y() * ac.x()));
  const double r = (a - centre).norm();
  // Nearly collinear points put the centre far off and inexactly: the arc must end at c
  // (its end is computed from the angle, so both ends at the radius to 1e-9 mm).
  if (!(std::abs((c - centre).norm() - r) <= 1e-9) || r > 1e6) return std::nullopt;
  const bool ccw = cross > 0;  // a -> b -> c turns left
  const double s = ccw ? 1.0 : -1.0;
  const double a0 = std::atan2(a.y() - centre.y(), a.x() - centre.x());
  auto param = [&](const Vec2& p) {  // angle travelled from a in the arc's sense, [0, 2 pi)
    double d = s * (std::atan2(p.y() - centre.y(), p.x() - centre.x()) - a0);
    d = std::fmod(d, 2 * M_PI);
    return d < 0 ? d + 2 * M_PI : d;
  };
  const double total = param(c);
  double last = 0;
  // In order along the arc, each point within tol of the circle, and the arc between two
  // consecutive points no longer than their chord allows (pi/2 of it and the tolerance):
  // points that turn back do not make a loop the long way round.
  auto short_enough = [&](double t0, double t1, const Vec2& p0, const Vec2& p1) {
    return (t1 - t0) * r <= 0.5 * M_PI * (p1 - p0).norm() + 2 * tol;
  };
  for (std::size_t k = i + 1; k < j; ++k) {
    if (std::abs((pts[k] - centre).norm() - r) > tol) return std::nullopt;
    const double t = param(pts[k]);
    if (t < last - 1e-12 || t > total + 1e-12) return std::nullopt;
    if (!short_enough(last, t, pts[k - 1], pts[k])) return std::nullopt;
    last = t;
  }
  if (!short_enough(last, total, pts[j - 1], c)) return std::nullopt;
  const ContourPiece arc = ContourPiece::arc(a, c, centre, ccw);
  if (!chords_within(arc)) return std::nullopt;
  return arc;
}

}  // namespace

std::vector<ContourPiece> fit_polyline(const std::vector<Vec2>& points, double tolerance_mm,
                                       double bulge_mm, bool bulge_ccw) {
  if (!(tolerance_mm > 0)) throw InputError("fit tolerance must be > 0 mm");
  std::vector<ContourPiece> out;
  const std::size_t n = points.size();
  std::size_t i = 0;
  while (i + 1 < n) {
    // Grow by doubling while the piece fits, then bisect between the last fit and the miss.
    std::size_t good = i + 1, step = 2;
    std::optional<ContourPiece> best =
        piece_through(points, i, good, tolerance_mm, bulge_mm, bulge_ccw);
    std::size_t bad = n;
    while (true) {
      const std::size_t j = std::min(n - 1, i + step);
      if (j <= good) break;
      if (auto p = piece_through(points, i, j, tolerance_mm, bulge_mm, bulge_ccw)) {
        good = j;
        best = p;
        if (j == n - 1) break;
        step *= 2;
      } else {
        bad = j;
        break;
      }
    }
    while (bad < n && bad > good + 1) {
      const std::size_t mid = (good + bad) / 2;
      if (auto p = piece_through(points, i, mid, tolerance_mm, bulge_mm, bulge_ccw)) {
        good = mid;
        best = p;
      } else {
        bad = mid;
      }
    }
    if (best) out.push_back(*best);  // (a line between coincident points: dropped)
    i = good;
  }
  return out;
}

}  // namespace trochomill

namespace trochomill {

NurbsCurve::NurbsCurve(int degree, std::vector<double> knots, std::vector<Vec3> ctrl,
                       std::vector<double> weights)
    : p_(degree), u_(std::move(knots)), c_(std::move(ctrl)), w_(std::move(weights)) {
  if (p_ < 1 || c_.size() < static_cast<std::size_t>(p_) + 1 ||
      u_.size() != c_.size() + static_cast<std::size_t>(p_) + 1 || w_.size() != c_.size()) {
    throw Error("NurbsCurve: degree, knots, control points and weights do not agree");
  }
}

Vec3 NurbsCurve::point(double u) const {
  u = std::clamp(u, u0(), u1());
  // The knot span: u in [U_k, U_k+1), the last span closed at its end.
  const auto p = static_cast<std::size_t>(p_);
  // The last knot index k in [p, n - 1] with U_k <= u (binary search: curves of many points).
  const auto first = u_.begin() + static_cast<std::ptrdiff_t>(p) + 1,
             last = u_.begin() + static_cast<std::ptrdiff_t>(c_.size());
  const std::size_t k = p + static_cast<std::size_t>(std::upper_bound(first, last, u) - first);
  std::vector<Eigen::Vector3d> d(p + 1);  // (w x, w y, w)
  for (std::size_t j = 0; j <= p; ++j) {
    const std::size_t i = k - p + j;
    d[j] = Eigen::Vector3d(w_[i] * c_[i].x(), w_[i] * c_[i].y(), w_[i]);
  }
  for (std::size_t r = 1; r <= p; ++r) {
    for (std::size_t j = p; j >= r; --j) {
      const std::size_t i = k - p + j;
      const double den = u_[i + p - r + 1] - u_[i];
      const double a = den > 0 ? (u - u_[i]) / den : 0.0;
      d[j] = (1 - a) * d[j - 1] + a * d[j];
    }
  }
  const Eigen::Vector3d& q = d[p];
  return Vec3(q.x() / q.z(), q.y() / q.z(), c_.front().z());
}

Vec3 NurbsCurve::unit_tangent(double u) const {
  const double h = 1e-6 * (u1() - u0());
  const double a = std::max(u0(), u - h), b = std::min(u1(), u + h);
  Vec3 t = point(b) - point(a);
  t.z() = 0;
  const double n = t.norm();
  return n > 0 ? Vec3(t / n) : Vec3::Zero();
}

}  // namespace trochomill
