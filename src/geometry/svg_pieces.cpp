// The SVG reader's pieces (svg_syntax.hpp): user-space lines, Béziers and elliptical arcs mapped
// into mm (y up) through an element's transform; circles (round after the transform) as exact
// arcs, the rest as biarcs within the arc tolerance (fit_biarcs).
#include <fmt/format.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <vector>

#include "geometry/drawing_limits.hpp"
#include "geometry/svg_syntax.hpp"
#include "trochomill/error.hpp"
#include "trochomill/units.hpp"

namespace trochomill::svg {
namespace {

constexpr double kFarMm = 1e9;  // points beyond 1000 km are absurd (as chain_pieces)
constexpr std::size_t kMaxPieces = 2'000'000;

bool far(const Vec2& p) { return !(std::abs(p.x()) <= kFarMm && std::abs(p.y()) <= kFarMm); }
double cross(const Vec2& a, const Vec2& b) { return a.x() * b.y() - a.y() * b.x(); }
Vec3 lift(const Vec2& p) { return {p.x(), p.y(), 0}; }

// The parameters in (0, 1), increasing, where the cubic Bezier p's derivative vanishes (to a
// millionth of its control polygon's length: a turn that tight is a corner at the tolerances
// drawings are read at). d(t) / 3 = a + 2 (b - a) t + (a - 2 b + c) t^2 with a, b, c the
// polygon's legs; a zero of d is a zero of both components, so it is among the roots of each.
std::vector<double> cusps(const std::array<Vec2, 4>& p) {
  const Vec2 a = p[1] - p[0], b = p[2] - p[1], c = p[3] - p[2];
  const double size = a.norm() + b.norm() + c.norm();
  const auto d = [&](double t) { return a + 2 * t * (b - a) + t * t * (a - 2 * b + c); };
  std::vector<double> roots;
  for (int k = 0; k < 2; ++k) {
    const double A = a[k] - 2 * b[k] + c[k], B = 2 * (b[k] - a[k]), C = a[k];
    if (std::abs(A) <= 1e-12 * size) {
      if (std::abs(B) > 1e-12 * size) roots.push_back(-C / B);
      continue;
    }
    const double disc = B * B - 4 * A * C;
    if (disc < 0) continue;
    // Without cancellation: q = -(B + sign(B) sqrt(disc)) / 2, roots q / A and C / q.
    const double q = -0.5 * (B + std::copysign(std::sqrt(disc), B));
    roots.push_back(q / A);
    if (q != 0) roots.push_back(C / q);
  }
  std::vector<double> out;
  for (const double t : roots) {
    if (t > 1e-9 && t < 1 - 1e-9 && d(t).norm() <= 1e-6 * size) out.push_back(t);
  }
  std::sort(out.begin(), out.end());
  out.erase(std::unique(out.begin(), out.end(), [](double x, double y) { return y - x < 1e-9; }),
            out.end());
  return out;
}

// A cubic Bézier (mm). Where its derivative vanishes (a control point on its end) the
// tangent is the chord over a millionth of the parameter either side.
class Bezier final : public PlanarCurve {
 public:
  explicit Bezier(std::array<Vec2, 4> p) : p_(p) {}
  [[nodiscard]] Vec3 point(double t) const override {
    const double s = 1 - t;
    return lift(s * s * s * p_[0] + 3 * s * s * t * p_[1] + 3 * s * t * t * p_[2] +
                t * t * t * p_[3]);
  }
  [[nodiscard]] Vec3 unit_tangent(double t) const override {
    const double s = 1 - t;
    Vec2 d =
        3 * s * s * (p_[1] - p_[0]) + 6 * s * t * (p_[2] - p_[1]) + 3 * t * t * (p_[3] - p_[2]);
    const double size = (p_[1] - p_[0]).norm() + (p_[2] - p_[1]).norm() + (p_[3] - p_[2]).norm();
    if (!(d.norm() > 1e-9 * size)) {
      const Vec3 q = point(std::min(1.0, t + 1e-6)) - point(std::max(0.0, t - 1e-6));
      d = Vec2(q.x(), q.y());
    }
    const double n = d.norm();
    return n > 0 ? lift(d / n) : Vec3::Zero();
  }

 private:
  std::array<Vec2, 4> p_;
};

}  // namespace

PieceSink::PieceSink(const Affine& m, double tolerance_mm, std::vector<DrawnPiece>& out,
                     std::size_t& fitted, std::string layer, std::string entity)
    : m_(m),
      tol_(tolerance_mm),
      out_(out),
      fitted_(fitted),
      layer_(std::move(layer)),
      entity_(std::move(entity)) {}

void PieceSink::line(const Vec2& p0, const Vec2& p1) { add(ContourPiece::line(m_(p0), m_(p1))); }
void PieceSink::cubic(const Vec2& p0, const Vec2& p1, const Vec2& p2, const Vec2& p3) {
  const std::array<Vec2, 4> p{m_(p0), m_(p1), m_(p2), m_(p3)};
  for (const Vec2& q : p) check(q);
  if (p[0] == p[1] && p[1] == p[2] && p[2] == p[3]) return;
  // A cusp (the derivative vanishing inside, as where a curve folds back on itself) is a
  // corner: the curve is split there (de Casteljau) and each part fitted on its own, its
  // tangent at the cusp the one-sided one of its own end (Bezier::unit_tangent).
  std::array<Vec2, 4> rest = p;
  double t0 = 0;
  for (const double t : cusps(p)) {
    const double u = (t - t0) / (1 - t0);  // t in the part still to fit
    const Vec2 q01 = rest[0] + u * (rest[1] - rest[0]), q12 = rest[1] + u * (rest[2] - rest[1]),
               q23 = rest[2] + u * (rest[3] - rest[2]);
    const Vec2 r0 = q01 + u * (q12 - q01), r1 = q12 + u * (q23 - q12);
    const Vec2 m = r0 + u * (r1 - r0);
    fit(Bezier({rest[0], q01, r0, m}), 0, 1, 2);
    rest = {m, r1, q23, rest[3]};
    t0 = t;
  }
  fit(Bezier(rest), 0, 1, 2);
}
void PieceSink::ellipse(const Vec2& c, const Vec2& a, const Vec2& b, double t0, double t1,
                        const Vec2& p0, const Vec2& p1) {
  const Vec2 cm = m_(c), am = m_.linear(a), bm = m_.linear(b), s = m_(p0), e = m_(p1);
  check(cm);
  check(am);
  check(bm);
  if (s == e) return;  // an arc too short to tell from a full circle
  const double la = am.norm(), lb = bm.norm();
  // A circle in mm (a circle under a uniform scale, or an ellipse squeezed round): an arc.
  if (std::abs(am.dot(bm)) <= 1e-9 * la * lb && std::abs(la - lb) <= 1e-9 * std::max(la, lb)) {
    return add(ContourPiece::arc(s, e, cm, (cross(am, bm) > 0) == (t1 > t0)));
  }
  const int n = std::max(1, static_cast<int>(std::ceil(std::abs(t1 - t0) / (0.5 * kPi))));
  // Decreasing t: the same ellipse with b turned round, at -t (increasing).
  if (t1 >= t0) return fit(EllipseCurve(lift(cm), lift(am), lift(bm)), t0, t1, n);
  fit(EllipseCurve(lift(cm), lift(am), lift(-bm)), -t0, -t1, n);
}

void PieceSink::check(const Vec2& p) {
  if (far(p)) {
    throw Problem{
        fmt::format("a point or radius ({}, {}) mm not finite or beyond 1000 km", p.x(), p.y())};
  }
}
void PieceSink::add(const ContourPiece& p) {
  check(p.start);
  check(p.end);
  if (p.start == p.end && !p.is_arc()) return;  // a zero-length line joins nothing
  if (out_.size() >= kMaxPieces) {
    throw Limit{fmt::format("more than {} lines and arcs: not read", kMaxPieces)};
  }
  out_.push_back({p, layer_, entity_});
  ++added;
}
void PieceSink::fit(const PlanarCurve& c, double u0, double u1, int n) {
  try {
    const std::vector<FitArc> arcs = fit_biarcs(c, u0, u1, n, tol_, kMaxDrawingArcs - fitted_);
    fitted_ += arcs.size();
    for (const FitArc& a : arcs) add(to_piece(a));
  } catch (const ArcLimit&) {
    throw Limit{drawing_detail::too_many_arcs(tol_)};
  } catch (const InputError&) {
    throw;
  } catch (const Error& e) {
    throw Problem{fmt::format("cannot be fitted with arcs within {} mm ({})", tol_, e.what())};
  }
}

}  // namespace trochomill::svg
