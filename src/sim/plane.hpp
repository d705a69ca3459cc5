// Plane geometry shared by the time-stepped simulation and the envelope sweep: angle
// ranges, sectors and annuli cut by lines (src/sim/, not public).
#pragma once

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <optional>

#include "trochomill/sim.hpp"
#include "trochomill/sim/dexel.hpp"
#include "trochomill/units.hpp"

namespace trochomill::sim_detail {

inline constexpr double kInf = std::numeric_limits<double>::infinity();

// Whether the angle range [a0, a1] contains alpha modulo 2 pi.
inline bool contains_angle(double a0, double a1, double alpha) {
  const double m = std::ceil((a0 - alpha) / kTwoPi);
  return alpha + m * kTwoPi <= a1;
}

// Whether a point at angle th (rad) lies in a sector [a0, a1] narrower than pi,
// contains_angle(a0, a1, th), without the point's arc tangent where it lies clearly on one
// side of an edge: rho sin(th - a0) and rho sin(a1 - th) are its cross products with the
// edges' directions, both positive inside and one negative outside. Within `margin` of an
// edge (rad: far beyond the rounding of the products and of contains_angle's reduction of
// angles that large) the arc tangent decides, so the answer is contains_angle's to the bit.
class SectorSides {
 public:
  SectorSides(double a0, double a1, bool use)
      : use_(use && a1 - a0 < 0.5 * kPi),
        c0_(std::cos(a0)),
        s0_(std::sin(a0)),
        c1_(std::cos(a1)),
        s1_(std::sin(a1)),
        margin_(1e-9 + 1e-13 * std::max(std::abs(a0), std::abs(a1))) {}
  // (dx, dy) from the centre (mm), rho its length; exact() is contains_angle's answer.
  template <class Exact>
  bool inside(double dx, double dy, double rho, Exact&& exact) const {
    if (use_) {
      const double e0 = c0_ * dy - s0_ * dx, e1 = s1_ * dx - c1_ * dy, m = margin_ * rho;
      if (e0 > m && e1 > m) return true;
      if (e0 < -m || e1 < -m) return false;
    }
    return exact();
  }

 private:
  bool use_;
  double c0_, s0_, c1_, s1_, margin_;
};

// A thin sector's constants (SectorSlicer's, which row_chords takes for many lines at once): its
// pieces between the multiples of pi.
struct SlicerCoeffs {
  struct Piece {
    bool valid = false;
    double s = 0;  // sine at the piece's middle
    double sin[2]{}, cos[2]{};
  };
  bool has0 = false, has_pi = false;  // whether the range holds the angles 0 and pi
  Piece piece[2];
};

// The offsets x (along the line) of the points of the thin sector {t (cos a, sin a): 0 <= t
// <= r, a in [a0, a1]} (a1 - a0 < pi) on lines at signed distance dy from the centre, parallel
// to the first axis: x = dy cot a where sin a has the sign of dy, clipped to the disc's chord.
// The angles' sines and cosines are taken once per sector, the lines then cost no trigonometry.
class SectorSlicer {
 public:
  SectorSlicer(double a0, double a1) {
    c_.has0 = contains_angle(a0, a1, 0.0);
    c_.has_pi = contains_angle(a0, a1, kPi);
    // Split at the multiples of pi (sin a = 0); each piece keeps lines on its sine's side.
    const double cut = (std::floor(a0 / kPi) + 1) * kPi;
    set(c_.piece[0], a0, std::min(a1, cut));
    set(c_.piece[1], cut, a1);
  }

  [[nodiscard]] std::optional<Interval> on_line(double dy, double r) const {
    if (dy * dy >= r * r) return std::nullopt;
    const double w = std::sqrt(r * r - dy * dy);
    double lo = kInf, hi = -kInf;
    if (dy == 0) {
      if (c_.has0) lo = std::min(lo, 0.0), hi = std::max(hi, w);
      if (c_.has_pi) lo = std::min(lo, -w), hi = std::max(hi, 0.0);
    } else {
      for (const SlicerCoeffs::Piece& p : c_.piece) {
        if (!p.valid || p.s * dy <= 0) continue;
        for (int e = 0; e < 2; ++e) {
          const double sa = p.sin[e], ca = p.cos[e];
          double x = 0;
          if (std::abs(sa) < 1e-300 || sa * dy <= 0) {  // at a split: the line runs off
            x = (ca * dy * p.s > 0) ? kInf : -kInf;
          } else {
            x = dy * ca / sa;
          }
          lo = std::min(lo, x), hi = std::max(hi, x);
        }
      }
    }
    lo = std::max(lo, -w);
    hi = std::min(hi, w);
    if (lo < hi) return Interval{lo, hi};
    return std::nullopt;
  }

  // The constants (row_chords takes them for many lines at once).
  [[nodiscard]] const SlicerCoeffs& coeffs() const noexcept { return c_; }

 private:
  static void set(SlicerCoeffs::Piece& p, double p0, double p1) {
    p.valid = p1 > p0;
    if (!p.valid) return;
    p.s = std::sin(0.5 * (p0 + p1));
    p.sin[0] = std::sin(p0), p.cos[0] = std::cos(p0);
    p.sin[1] = std::sin(p1), p.cos[1] = std::cos(p1);
  }
  SlicerCoeffs c_;
};

// The parts of [lo, hi] (offsets along a line at distance p from the centre) whose distance
// from the centre lies in [r_in, r_out]: up to two intervals, returned through `out`.
inline int annulus_parts(double p, double lo, double hi, double r_in, double r_out,
                         std::array<Interval, 2>& out) {
  const double pp = p * p;
  if (pp >= r_out * r_out) return 0;
  const double to = std::sqrt(r_out * r_out - pp);
  const double ti = pp < r_in * r_in ? std::sqrt(r_in * r_in - pp) : 0.0;
  int n = 0;
  auto add = [&](double a, double b) {
    a = std::max(a, lo), b = std::min(b, hi);
    if (a < b) out[static_cast<std::size_t>(n++)] = {a, b};
  };
  if (ti > 0) {
    add(-to, -ti);
    add(ti, to);
  } else {
    add(-to, to);
  }
  return n;
}

}  // namespace trochomill::sim_detail
