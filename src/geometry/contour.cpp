// Planar contours of lines and circular arcs: lengths, points, tangents, exact areas and
// distances, chords within a tolerance (geometry.hpp).
#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

#include "trochomill/error.hpp"
#include "trochomill/geometry.hpp"
#include "trochomill/units.hpp"

namespace trochomill {

namespace {

double angle_of(const Vec2& v) { return std::atan2(v.y(), v.x()); }

// The angle from a0 to a, measured in the direction of travel, in [0, 2 pi).
double travelled(double a0, double a, bool ccw) {
  double d = ccw ? a - a0 : a0 - a;
  d = std::fmod(d, kTwoPi);
  if (d < 0) d += kTwoPi;
  return d;
}

}  // namespace

double ContourPiece::radius_mm() const { return centre ? (start - *centre).norm() : 0.0; }

double ContourPiece::sweep_rad() const {
  if (!centre) return 0.0;
  const double a0 = angle_of(start - *centre), a1 = angle_of(end - *centre);
  double d = a1 - a0;
  if (ccw) {
    while (d <= 0) d += kTwoPi;  // start == end: a full circle
  } else {
    while (d >= 0) d -= kTwoPi;
  }
  return d;
}

double ContourPiece::length_mm() const {
  return centre ? radius_mm() * std::abs(sweep_rad()) : (end - start).norm();
}

Vec2 ContourPiece::point_at(double t) const {
  if (t <= 0) return start;
  if (t >= 1) return end;
  if (!centre) return start + t * (end - start);
  const double a = angle_of(start - *centre) + t * sweep_rad(), r = radius_mm();
  return *centre + r * Vec2(std::cos(a), std::sin(a));
}

Vec2 ContourPiece::tangent_at(double t) const {
  if (!centre) {
    const Vec2 d = end - start;
    const double n = d.norm();
    return n > 0 ? Vec2(d / n) : Vec2(1.0, 0.0);
  }
  const double a = angle_of(start - *centre) + std::clamp(t, 0.0, 1.0) * sweep_rad();
  const Vec2 radial(std::cos(a), std::sin(a));
  return ccw ? Vec2(-radial.y(), radial.x()) : Vec2(radial.y(), -radial.x());
}

double ContourPiece::distance_mm(const Vec2& p) const {
  if (!centre) {
    const Vec2 d = end - start;
    const double len2 = d.squaredNorm();
    const double t = len2 > 0 ? std::clamp((p - start).dot(d) / len2, 0.0, 1.0) : 0.0;
    return (p - (start + t * d)).norm();
  }
  const Vec2 q = p - *centre;
  const double r = radius_mm(), rho = q.norm();
  const double to_ends = std::min((p - start).norm(), (p - end).norm());
  if (rho == 0) return r;  // every point of the arc is r away
  const double along = travelled(angle_of(start - *centre), angle_of(q), ccw);
  return along <= std::abs(sweep_rad()) ? std::min(std::abs(rho - r), to_ends) : to_ends;
}

ContourPiece ContourPiece::reversed() const { return {end, start, centre, !ccw}; }

Contour Contour::polyline(const std::vector<Vec2>& points, bool closed) {
  Contour c;
  c.closed = closed;
  for (std::size_t i = 1; i < points.size(); ++i) {
    c.pieces.push_back(ContourPiece::line(points[i - 1], points[i]));
  }
  if (closed && points.size() > 1 && points.back() != points.front()) {
    c.pieces.push_back(ContourPiece::line(points.back(), points.front()));
  }
  return c;
}

Contour Contour::circle(const Vec2& c, double r_mm) {
  Contour k;
  k.closed = true;
  const Vec2 a = c + Vec2(r_mm, 0.0), b = c - Vec2(r_mm, 0.0);
  k.pieces = {ContourPiece::arc(a, b, c, true), ContourPiece::arc(b, a, c, true)};
  return k;
}

double Contour::length_mm() const {
  double s = 0;
  for (const ContourPiece& p : pieces) s += p.length_mm();
  return s;
}

double Contour::signed_area_mm2() const {
  if (!closed) throw std::logic_error("signed_area_mm2 of an open contour");
  double a = 0;
  for (const ContourPiece& p : pieces) {
    a += 0.5 * (p.start.x() * p.end.y() - p.end.x() * p.start.y());  // the chord's share
    if (p.centre) {
      // The circular segment between the chord and the arc, on the arc's side.
      const double th = p.sweep_rad(), r = p.radius_mm();
      a += 0.5 * r * r * (th - std::sin(th));
    }
  }
  return a;
}

Contour Contour::reversed() const {
  Contour c;
  c.closed = closed;
  c.pieces.reserve(pieces.size());
  for (auto it = pieces.rbegin(); it != pieces.rend(); ++it) c.pieces.push_back(it->reversed());
  return c;
}

double Contour::distance_mm(const Vec2& p) const {
  double d = std::numeric_limits<double>::infinity();
  for (const ContourPiece& k : pieces) d = std::min(d, k.distance_mm(p));
  return d;
}

namespace {

// Chords of an arc of radius r and sweep th whose sagitta stays within tol.
std::size_t arc_chords(double r, double th, double tol) {
  const double step = tol < r ? 2.0 * std::acos(1.0 - tol / r) : kPi;
  // At least three chords on a full circle, so that a closed contour keeps its area.
  const double n = std::max(std::ceil(std::abs(th) / step), std::ceil(std::abs(th) / (kTwoPi / 3)));
  return static_cast<std::size_t>(std::max(1.0, n));
}

}  // namespace

std::vector<Vec2> Contour::points(double tolerance_mm) const {
  std::vector<Vec2> out;
  for (const ContourPiece& p : pieces) {
    out.push_back(p.start);
    if (p.centre) {
      const std::size_t n = arc_chords(p.radius_mm(), p.sweep_rad(), tolerance_mm);
      for (std::size_t i = 1; i < n; ++i) {
        out.push_back(p.point_at(static_cast<double>(i) / static_cast<double>(n)));
      }
    }
  }
  if (!closed && !pieces.empty()) out.push_back(pieces.back().end);
  return out;
}

void Contour::check(double gap_mm) const {
  const auto finite = [](const Vec2& v) { return std::isfinite(v.x()) && std::isfinite(v.y()); };
  for (std::size_t i = 0; i < pieces.size(); ++i) {
    const ContourPiece& p = pieces[i];
    if (!finite(p.start) || !finite(p.end) || (p.centre && !finite(*p.centre))) {
      throw InputError(fmt::format("contour piece {}: a coordinate is not finite", i + 1));
    }
    if (p.centre) {
      const double r0 = (p.start - *p.centre).norm(), r1 = (p.end - *p.centre).norm();
      if (!(r0 > 0)) throw InputError(fmt::format("contour piece {}: an arc of radius 0", i + 1));
      if (std::abs(r1 - r0) > gap_mm) {
        throw InputError(fmt::format(
            "contour piece {}: the arc's end is {:.6g} mm from its centre and its start {:.6g} mm "
            "(they may differ by {:.6g} mm)",
            i + 1, r1, r0, gap_mm));
      }
    }
    if (i > 0) {
      const double g = (p.start - pieces[i - 1].end).norm();
      if (g > gap_mm) {
        throw InputError(
            fmt::format("contour piece {} starts {:.6g} mm from where piece {} ends (allowed: "
                        "{:.6g} mm)",
                        i + 1, g, i, gap_mm));
      }
    }
  }
  if (closed && !pieces.empty()) {
    const double g = (pieces.front().start - pieces.back().end).norm();
    if (g > gap_mm) {
      throw InputError(fmt::format(
          "the closed contour's last piece ends {:.6g} mm from its start (allowed: {:.6g} mm)", g,
          gap_mm));
    }
  }
}

double region_area_mm2(const std::vector<Contour>& contours) {
  double a = 0;
  for (const Contour& c : contours) a += c.signed_area_mm2();
  return a;
}

}  // namespace trochomill

namespace trochomill {

std::optional<Vec2> contour_self_crossing(const Contour& contour) {
  std::vector<Vec2> pts = contour.points(1e-4);
  if (contour.closed && !pts.empty()) pts.push_back(pts.front());
  const std::size_t n = pts.size() < 2 ? 0 : pts.size() - 1;  // chords i: pts[i] -> pts[i+1]
  std::vector<std::size_t> order(n);
  for (std::size_t i = 0; i < n; ++i) order[i] = i;
  const auto lo_x = [&](std::size_t i) { return std::min(pts[i].x(), pts[i + 1].x()); };
  const auto hi_x = [&](std::size_t i) { return std::max(pts[i].x(), pts[i + 1].x()); };
  std::sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) {
    return lo_x(a) < lo_x(b) || (lo_x(a) == lo_x(b) && a < b);
  });
  const auto cross = [](const Vec2& a, const Vec2& b) { return a.x() * b.y() - a.y() * b.x(); };
  std::optional<std::pair<std::size_t, Vec2>> first;
  for (std::size_t oi = 0; oi < n; ++oi) {
    const std::size_t i = order[oi];
    for (std::size_t oj = oi + 1; oj < n && lo_x(order[oj]) <= hi_x(i); ++oj) {
      const std::size_t j = order[oj];
      const std::size_t a = std::min(i, j), b = std::max(i, j);
      if (b == a + 1 || (contour.closed && a == 0 && b == n - 1)) continue;  // consecutive
      const Vec2 p = pts[a], r = pts[a + 1] - p, q = pts[b], s = pts[b + 1] - q;
      if (std::min(p.y(), pts[a + 1].y()) > std::max(q.y(), pts[b + 1].y()) ||
          std::max(p.y(), pts[a + 1].y()) < std::min(q.y(), pts[b + 1].y())) {
        continue;
      }
      const double den = cross(r, s);
      if (den == 0) continue;  // parallel chords: a touch along a line is caught by its ends
      const double t = cross(q - p, s) / den, u = cross(q - p, r) / den;
      if (t < 0 || t > 1 || u < 0 || u > 1) continue;
      if (!first || a < first->first) first = {a, p + t * r};
    }
  }
  if (first) return first->second;
  return std::nullopt;
}

}  // namespace trochomill
