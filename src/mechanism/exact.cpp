// The exact chip model over a trochoid cycle (semi-closed form); see docs/models.md
// section 9 and include/trochomill/mechanism.hpp.
//
// At trochoid angle theta the tool circle (centre c, radius R) cuts the stock left by the
// previous tooth (the circle about p = c one f_z of path earlier) and by the previous cycle
// (the region swept along c(theta') - (0, s), bounded ahead of the tool by its envelope
// E(theta') = c(theta') - (0, s) + R n(theta'), n the outward unit normal). The chip is
// largest either straight ahead of p (h = |c - p|, where the previous tooth bounds it) or at
// a kink where the previous tooth's circle meets the envelope (h = R - |Q - c|). The kinks
// and the engaged arc's ends (tool circle against the envelope) are roots of
// |E(theta') - centre|^2 = R^2 (a sign scan over theta' in theta +- pi, the last three
// cycles' envelopes in one pass, each crossing polished by Newton from the cubic through its
// samples and a Chebyshev step; regula falsi where that fails); an arc or a kink counts only
// if it lies outside every earlier position's disc (nearest-point distance to the past path,
// coarse samples then Newton).
#include <algorithm>
#include <array>
#include <cmath>
#include <vector>

#include "common/roots.hpp"
#include "common/sincos.hpp"
#include "mechanism/internal.hpp"
#include "trochomill/units.hpp"

namespace trochomill::mech {
namespace {

struct V2 {
  double x = 0, y = 0;
};
V2 operator-(V2 a, V2 b) { return {a.x - b.x, a.y - b.y}; }
V2 operator+(V2 a, V2 b) { return {a.x + b.x, a.y + b.y}; }
V2 operator*(double k, V2 a) { return {k * a.x, k * a.y}; }
double dot(V2 a, V2 b) { return a.x * b.x + a.y * b.y; }
double norm(V2 a) { return std::sqrt(a.x * a.x + a.y * a.y); }

struct Tables;

// sin and cos of the model's angles: tens of pairs a point, so from the table (within
// 2.2e-16 of libm's, several times faster).
detail::SinCos sincos(double t) { return detail::sincos_table()(t); }

struct Curve {
  double a, b, s, R;
  const Tables* tab = nullptr;
  [[nodiscard]] V2 c(double t) const {
    const detail::SinCos q = sincos(t);
    return {-a * q.c, b * q.s + s * t / kTwoPi};
  }
  [[nodiscard]] V2 d1(double t) const {
    const detail::SinCos q = sincos(t);
    return {a * q.s, b * q.c + s / kTwoPi};
  }
  // Envelope of the previous cycle and its first and second derivatives in theta': with
  // T = c', T^ = T / L and k = T.T2 / L^2, T^' = (T2 - k T) / L and
  // T^'' = (T3 - k' T - 2 k T2 + k^2 T) / L, k' = (|T2|^2 + T.T3) / L^2 - 2 k^2; E' and E''
  // are T and T2 plus R times those rotated like n.
  void envelope2(double t, V2& e, V2& de, V2& dde) const {
    const detail::SinCos q = sincos(t);
    const double sn = q.s, cs = q.c;
    const V2 T{a * sn, b * cs + s / kTwoPi}, T2{a * cs, -b * sn}, T3{-a * sn, -b * cs};
    const double iL = 1 / norm(T), iL2 = iL * iL;  // one division, then products
    const V2 n{-T.y * iL, T.x * iL};  // left of the motion: outward for the clockwise orbit
    const double k = dot(T, T2) * iL2;
    const V2 dT{(T2.x - k * T.x) * iL, (T2.y - k * T.y) * iL};
    const double kd = (dot(T2, T2) + dot(T, T3)) * iL2 - 2 * k * k;
    const V2 ddT{(T3.x - kd * T.x - 2 * k * T2.x + k * k * T.x) * iL,
                 (T3.y - kd * T.y - 2 * k * T2.y + k * k * T.y) * iL};
    e = {-a * cs + R * n.x, b * sn + s * t / kTwoPi - s + R * n.y};
    de = {T.x - R * dT.y, T.y + R * dT.x};
    dde = {T2.x - R * ddT.y, T2.y + R * ddT.x};
  }
  // Without the second derivative (inlined, its arithmetic drops out).
  void envelope(double t, V2& e, V2& de) const {
    V2 dde;
    envelope2(t, e, de, dde);
  }
};

// Envelope and path on fixed grids (built once per model), so the scans below need no
// trigonometry: the envelope over [-pi, 3 pi], the path over [-2 pi, 2 pi], at least 96 and
// 144 samples per turn and fine enough that neighbours are at most R / 4 and R / 6 apart
// along the orbit (a wide orbit would otherwise hide crossings between samples).
struct Tables {
  double env_dt, path_dt;
  int env_m0, path_m0;
  const std::vector<double>&ex, &ey, &px, &py;
  [[nodiscard]] V2 env_at(int m) const {
    const auto i = static_cast<std::size_t>(m - env_m0);
    return {ex[i], ey[i]};
  }
  [[nodiscard]] V2 path_at(int m) const {
    const auto i = static_cast<std::size_t>(m - path_m0);
    return {px[i], py[i]};
  }
};

// Envelopes of the last kEnvelopes cycles (a wall cusp is bounded by two of them): the j-th
// (j = 1, 2, ...) is the first shifted by (j - 1) s back, so its roots are the first's for the
// query point shifted forward.
constexpr int kEnvelopes = 3;
// A root and its point on the (unshifted) envelope.
struct EnvRoot {
  double t;
  V2 e;
};
using RootSets = std::array<std::vector<EnvRoot>, kEnvelopes>;

// All roots in (theta - pi, theta + pi) of |E(t) - q_j|^2 = R^2, q_j = q + (0, (j - 1) s),
// for every envelope j: one sign scan of the table for all of them (plus the minimum of every
// dip between samples), each bracket polished by Newton or regula falsi; written to out[j - 1]
// (cleared first: the callers reuse their buffers, the model runs thousands of times a cycle).
void scan_roots(const Curve& cv, V2 q, double theta, RootSets& out) {
  // Samples on the table's grid within theta +- pi.
  const Tables& tb = *cv.tab;
  const int m_lo = static_cast<int>(std::ceil((theta - kPi) / tb.env_dt));
  const int m_hi = static_cast<int>(std::floor((theta + kPi) / tb.env_dt));
  const auto nk = static_cast<std::size_t>(m_hi - m_lo + 1);
  thread_local std::vector<double> gbuf;
  gbuf.resize(kEnvelopes * nk);
  {
    // One pass for the three envelopes (they share x, and y up to the shift): a loop the
    // compiler vectorises.
    const double* ex = &tb.ex[static_cast<std::size_t>(m_lo - tb.env_m0)];
    const double* ey = &tb.ey[static_cast<std::size_t>(m_lo - tb.env_m0)];
    const double R2 = cv.R * cv.R, s1 = cv.s, s2 = 2 * cv.s;
    double* g1 = gbuf.data();
    double* g2 = g1 + nk;
    double* g3 = g2 + nk;
    static_assert(kEnvelopes == 3);
    for (std::size_t k = 0; k < nk; ++k) {
      const double dx = ex[k] - q.x, dy = ey[k] - q.y;
      const double base = dx * dx - R2, dy2 = dy - s1, dy3 = dy - s2;
      g1[k] = base + dy * dy;
      g2[k] = base + dy2 * dy2;
      g3[k] = base + dy3 * dy3;
    }
  }
  for (int j = 1; j <= kEnvelopes; ++j) {
    std::vector<EnvRoot>& res = out[static_cast<std::size_t>(j - 1)];
    res.clear();
    const double* gs = gbuf.data() + static_cast<std::size_t>(j - 1) * nk;
    const V2 qj = q + V2{0, (j - 1) * cv.s};
    auto g = [&](double t) {
      V2 e, de;
      cv.envelope(t, e, de);
      const V2 r = e - qj;
      return dot(r, r) - cv.R * cv.R;
    };
    // Newton from `t` (the cubic's root below) with g' = 2 (E - q) . E' and g'' = 2 (|E'|^2 +
    // (E - q) . E'') (the envelope gives E' and E''), kept in the bracket; regula falsi if a
    // step leaves it or it has not converged in 8 steps. Once the Newton step s is small, the
    // root is t - s - c2 s^2 (c2 = g'' / 2 g', the series of the inverse; Chebyshev's step)
    // with an error of about 2 c2^2 s^3: taken when four times that is under 1e-12 rad, with
    // the root's point from E's series to the second order (its error ~ s^3 |E^(3)| / 6, some
    // 1e-13 mm). From the cubic's start (within ~1e-6 rad) that is one evaluation a root.
    auto solve = [&](double lo, double hi, double glo, double ghi, double t) -> EnvRoot {
      for (int it = 0; it < 8; ++it) {
        V2 e, de, dde;
        cv.envelope2(t, e, de, dde);
        const V2 r = e - qj;
        const double gt = dot(r, r) - cv.R * cv.R, dg = 2 * dot(r, de);
        if (gt == 0) return {t, e};
        if ((gt < 0) == (glo < 0)) {
          lo = t;
          glo = gt;
        } else {
          hi = t;
          ghi = gt;
        }
        const double step = dg != 0 ? gt / dg : 0.0;
        const double tn = t - step;
        if (!(tn > lo && tn < hi)) break;
        if (std::abs(step) < 1e-10) return {tn, e - step * de};  // ~1e-9 mm along the envelope
        const double c2 = (dot(de, de) + dot(r, dde)) / dg;      // g'' / 2 g'
        const double corr = step + c2 * step * step;
        const double tc = t - corr;
        if (std::abs(step) < 1e-5 && 8 * c2 * c2 * std::abs(step * step * step) < 1e-12 &&
            tc > lo && tc < hi) {
          return {tc, e - corr * de + 0.5 * corr * corr * dde};
        }
        t = tn;
      }
      const double tr = detail::regula_falsi(g, lo, hi, glo, ghi, 1e-12);
      V2 e, de;
      cv.envelope(tr, e, de);
      return {tr, e};
    };
    auto ts = [&](std::size_t k) { return (m_lo + static_cast<int>(k)) * tb.env_dt; };
    // w[k] >= 0 clears sample k of both tests below: g[k - 1] and g[k] both negative (no sign
    // change; a dip needs g[k] >= 0), or g[k - 1] >= 0 and g[k] at least half the second
    // difference (no sign change, no dip). A loop without branches (vectorised), so the tests
    // run only where the envelope crosses or grazes the circle.
    thread_local std::vector<double> wbuf;
    wbuf.resize(nk);
    double* w = wbuf.data();  // a local pointer: the loops below need not reload it
    for (std::size_t k = 1; k + 1 < nk; ++k) {
      const double a = gs[k - 1], b = gs[k], c = gs[k + 1];
      const double slack = b - 0.5 * std::abs(c - 2 * b + a);
      const double lo = a < slack ? a : slack, hi = a > b ? a : b;
      w[k] = hi < 0 ? 1.0 : lo;
    }
    if (nk >= 2) w[nk - 1] = (gs[nk - 2] < 0) != (gs[nk - 1] < 0) ? -1.0 : 1.0;
    // Newton's start for a sign change between samples k - 1 and k: the root of the cubic
    // through the samples k - 2 .. k + 1 (a few Newton steps on the polynomial from the
    // secant point, kept in the interval), within ~1e-6 rad where g is smooth, so one or two
    // evaluations of the envelope finish it; the secant point where there are no neighbours.
    auto start = [&](std::size_t k) {
      const double g0 = gs[k - 1], g1 = gs[k];
      double u = g0 / (g0 - g1);
      if (k >= 2 && k + 1 < nk) {
        // p(u) = g0 + u (d1 + (u - 1) (d2 / 2 + (u + 1) d3 / 6)), Newton form on nodes 0, 1, -1, 2.
        const double gm = gs[k - 2], g2 = gs[k + 1];
        const double d1 = g1 - g0, d2 = g1 - 2 * g0 + gm;
        const double c2 = 0.5 * d2, c3 = (g2 - 3 * g1 + 3 * g0 - gm) / 6;
        for (int it = 0; it < 3; ++it) {
          const double pu = g0 + u * (d1 + (u - 1) * (c2 + (u + 1) * c3));
          const double dp = d1 + (2 * u - 1) * c2 + (3 * u * u - 1) * c3;
          if (dp == 0) break;
          u = std::clamp(u - pu / dp, 0.0, 1.0);
        }
      }
      return ts(k - 1) + u * tb.env_dt;
    };
    for (std::size_t k = 1;; ++k) {
      // To the next sample to look at: four at a time, then one by one.
      while (k + 4 <= nk && std::min(std::min(w[k], w[k + 1]), std::min(w[k + 2], w[k + 3])) >= 0) {
        k += 4;
      }
      while (k < nk && w[k] >= 0) ++k;
      if (k >= nk) break;
      if ((gs[k - 1] < 0) != (gs[k] < 0)) {
        res.push_back(solve(ts(k - 1), ts(k), gs[k - 1], gs[k], start(k)));
      } else if (k + 1 < nk && ((gs[k] >= 0) & (gs[k] < gs[k - 1]) & (gs[k] <= gs[k + 1]) &
                                (gs[k] < 0.5 * std::abs(gs[k + 1] - 2 * gs[k] + gs[k - 1])))) {
        // A dip between samples that may cross zero (the envelope grazing the circle, e.g. a
        // wall cusp; a parabola through the samples dips at most an eighth of the second
        // difference below them, so a value above half of it cannot hide a crossing): find
        // its minimum; if negative, it holds two roots. (The tests are joined without
        // short-circuits: one branch, rarely taken, instead of several hard to predict.)
        // The minimum is a root of g' = 2 (E - q) . E' (regula falsi when g' changes sign over
        // the two intervals, as it does for a single valley; golden section otherwise).
        const double lo = ts(k - 1), hi = ts(k + 1);
        auto dg = [&](double t) {
          V2 e, de;
          cv.envelope(t, e, de);
          return dot(e - qj, de);
        };
        const double tm = detail::bracketed_minimum(g, dg, lo, hi, 1e-10), gm = g(tm);
        if (gm < 0) {
          res.push_back(solve(ts(k - 1), tm, gs[k - 1], gm,
                              (gs[k - 1] * tm - gm * ts(k - 1)) / (gs[k - 1] - gm)));
          res.push_back(solve(tm, ts(k + 1), gm, gs[k + 1],
                              (gm * ts(k + 1) - gs[k + 1] * tm) / (gm - gs[k + 1])));
        }
      }
    }
  }
}

// Distance from x to the path of all positions up to the previous tooth pass (parameter
// `recent`, the centre p): every such position is c(t) - j (0, s) with t in [theta - 2 pi,
// theta), j >= 0 cycles back (j >= 1 where t > recent), and for each t the best j is the
// one that brings its y nearest x's. Coarse samples over t, then Newton on the nearest with
// its j fixed (kept at or before `recent` when j = 0).
// Callers only compare the distance with a threshold `below`: a sample under it settles the
// answer (the true minimum is no larger), so the scan stops there and returns it.
double dist_to_past(const Curve& cv, V2 x, double theta, double recent, double below) {
  const Tables& tb = *cv.tab;
  const double below2 = below * below;
  const double lo = theta - kTwoPi, inv_s = 1.0 / cv.s;
  const int m_lo = static_cast<int>(std::ceil(lo / tb.path_dt));
  const int m_hi = static_cast<int>(std::ceil(theta / tb.path_dt)) - 1;
  thread_local std::vector<double> dds_buf, js_buf;
  const auto nk = static_cast<std::size_t>(std::max(0, m_hi - m_lo + 1));
  dds_buf.resize(nk);
  js_buf.resize(nk);
  double* dds = dds_buf.data();  // local pointers: the loop need not reload them
  double* js = js_buf.data();
  double best = 1e300;
  for (std::size_t k = 0; k < nk; ++k) {
    const int m = m_lo + static_cast<int>(k);
    const double t = m * tb.path_dt;
    const V2 q = tb.path_at(m);
    const double jy = (q.y - x.y) * inv_s + 0.5;  // nearest whole number of cycles back
    double j = jy > 1 ? static_cast<double>(static_cast<long>(jy)) : 0.0;
    if (j == 0 && t > recent) j = 1;  // after the previous tooth pass: not yet
    const V2 r = q - V2{0, j * cv.s} - x;
    const double dd = dot(r, r);  // squared while scanning
    if (dd < below2) return std::sqrt(dd);
    dds[k] = dd;
    js[k] = j;
    best = std::min(best, dd);
  }
  best = std::sqrt(best);
  // Refine every sampled local minimum that could hide the true nearest point: between
  // samples L apart along the path a minimum lies at most ~L^2 / (8 rho) below the nearer
  // sample (rho ~ R here); the margin L^2 / R covers it with room. Newton on |c(t) - (0, j s)
  // - x|^2 with that sample's j.
  const double L = tb.path_dt * (std::max(cv.a, cv.b) + cv.s / kTwoPi);
  const double margin = L * L / cv.R;
  double result = best;
  const double limit2 = (best + margin) * (best + margin);
  for (std::size_t k = 0; k < nk; ++k) {
    if (dds[k] > limit2) continue;
    if ((k > 0 && dds[k - 1] < dds[k]) || (k + 1 < nk && dds[k + 1] < dds[k])) continue;
    const double bj = js[k];
    double t = (m_lo + static_cast<int>(k)) * tb.path_dt;
    for (int it = 0; it < 8; ++it) {  // minimise |c(t) - (0, j s) - x|^2: f = (q - x).c'
      const detail::SinCos sc = sincos(t);
      const double sn = sc.s, cs = sc.c;
      const V2 q{-cv.a * cs - x.x, cv.b * sn + cv.s * t / kTwoPi - bj * cv.s - x.y};
      const V2 d1{cv.a * sn, cv.b * cs + cv.s / kTwoPi}, d2{cv.a * cs, -cv.b * sn};
      const double f = dot(q, d1), df = dot(d1, d1) + dot(q, d2);
      if (df <= 0) break;
      const double step = std::clamp(f / df, -0.05, 0.05);
      const double tn = bj == 0 ? std::min(t - step, recent) : t - step;
      if (std::abs(tn - t) < 1e-12) break;
      t = tn;
    }
    result = std::min(result, norm(cv.c(t) - V2{0, bj * cv.s} - x));
  }
  return result;
}

}  // namespace

ExactModel::ExactModel(double a_mm, double b_mm, double step_mm, double radius_mm, double fz_mm,
                       double feed_mm_per_s, double edge_speed_mm_per_s)
    : a_(a_mm),
      b_(b_mm),
      s_(step_mm),
      R_(radius_mm),
      fz_(fz_mm),
      feed_mm_per_s_(feed_mm_per_s),
      edge_speed_mm_per_s_(edge_speed_mm_per_s) {
  const Curve cv{a_, b_, s_, R_};
  // Arc length of one turn of the orbit plus the tool's circumference, over R.
  const double turn = kTwoPi * (std::max(a_, b_) + R_) / R_;
  env_dt_ = kTwoPi / std::max(96.0, std::ceil(4 * turn));
  path_dt_ = kTwoPi / std::max(144.0, std::ceil(6 * turn));
  env_m0_ = static_cast<int>(std::floor(-kPi / env_dt_)) - 2;
  const int env_m1 = static_cast<int>(std::ceil(3 * kPi / env_dt_)) + 2;
  for (int m = env_m0_; m <= env_m1; ++m) {
    V2 e, de;
    cv.envelope(m * env_dt_, e, de);
    env_x_.push_back(e.x);
    env_y_.push_back(e.y);
  }
  path_m0_ = static_cast<int>(std::floor(-kTwoPi / path_dt_)) - 2;
  const int path_m1 = static_cast<int>(std::ceil(kTwoPi / path_dt_)) + 2;
  for (int m = path_m0_; m <= path_m1; ++m) {
    const V2 q = cv.c(m * path_dt_);
    path_x_.push_back(q.x);
    path_y_.push_back(q.y);
  }
}

ChipPoint ExactModel::at(double theta) const {
  // The cycle is periodic in phase: work at theta in [0, 2 pi) (the tables cover it).
  theta -= kTwoPi * std::floor(theta / kTwoPi);
  const Tables tb{env_dt_, path_dt_, env_m0_, path_m0_, env_x_, env_y_, path_x_, path_y_};
  Curve cv{a_, b_, s_, R_};
  cv.tab = &tb;
  ChipPoint out;
  const V2 c = cv.c(theta);
  const V2 v = cv.d1(theta);
  // One f_z of path back (midpoint speed: error O(f_z^3 kappa^2)).
  const double d0 = fz_ / norm(v);
  const double dth = fz_ / norm(cv.d1(theta - 0.5 * d0));
  const double th_p = theta - dth;
  const V2 p = cv.c(th_p);
  const V2 cp = c - p;
  const double d = norm(cp);
  const double tol = 1e-9 * R_;

  // Split the tool circle at its crossings with the previous cycle's envelope and with the
  // previous tooth's circle; an arc is engaged when its midpoint lies outside both the
  // previous tooth's disc and every earlier position's disc.
  struct Root {
    double t;
    int j;
    V2 e;  // its point on the j-th envelope
  };
  auto env_at = [&](double t, int j) {
    V2 q, dq;
    cv.envelope(t, q, dq);
    return V2{q.x, q.y - (j - 1) * s_};
  };
  using Roots = std::array<std::vector<Root>, kEnvelopes>;
  // Buffers kept per thread: the same numbers, without a dozen allocations a point.
  thread_local Roots tool_roots, tooth_roots;
  thread_local RootSets found;
  thread_local std::vector<double> ang;
  auto roots_for = [&](V2 q, Roots& out_j) {
    scan_roots(cv, q, theta, found);
    for (int j = 1; j <= kEnvelopes; ++j) {
      auto& rj = out_j[static_cast<std::size_t>(j - 1)];
      rj.clear();
      for (const EnvRoot& r : found[static_cast<std::size_t>(j - 1)]) {
        rj.push_back({r.t, j, V2{r.e.x, r.e.y - (j - 1) * s_}});
      }
    }
  };
  ang.clear();
  V2 e;
  roots_for(c, tool_roots);
  for (const auto& rj : tool_roots) {
    for (const Root& r : rj) {
      e = r.e;
      ang.push_back(std::atan2(e.y - c.y, e.x - c.x));
    }
  }
  const double back = std::atan2(-cp.y, -cp.x), beta = std::acos(std::min(1.0, d / (2 * R_)));
  ang.push_back(back - beta);
  ang.push_back(back + beta);
  for (auto& x : ang) x = x - kTwoPi * std::floor(x / kTwoPi);
  std::sort(ang.begin(), ang.end());
  struct Arc {
    double a0, a1;
  };
  thread_local std::vector<Arc> engaged;
  engaged.clear();
  for (std::size_t k = 0; k < ang.size(); ++k) {
    const double a0 = ang[k], a1 = k + 1 < ang.size() ? ang[k + 1] : ang[0] + kTwoPi;
    if (a1 - a0 < 1e-12) continue;
    const double mid = 0.5 * (a0 + a1);
    const detail::SinCos sc = sincos(mid);
    const V2 m = c + R_ * V2{sc.c, sc.s};
    if (norm(m - p) < R_ || dist_to_past(cv, m, theta, th_p, R_) < R_) continue;
    out.psi_rad += a1 - a0;
    engaged.push_back({a0, a1});
  }
  if (out.psi_rad <= 0) return out;
  // A chip candidate counts only on an engaged arc: the tool circle's point in its
  // direction must be in the stock (else the ray meets removed material first and the
  // radial distance R - |q - c| overstates the chip there).
  auto on_engaged_arc = [&](V2 q) {
    double a = std::atan2(q.y - c.y, q.x - c.x);
    a -= kTwoPi * std::floor(a / kTwoPi);
    for (const Arc& arc : engaged) {
      if ((a >= arc.a0 - 1e-9 && a <= arc.a1 + 1e-9) ||
          (a + kTwoPi >= arc.a0 - 1e-9 && a + kTwoPi <= arc.a1 + 1e-9)) {
        return true;
      }
    }
    return false;
  };

  // The chip: straight ahead of p where the previous tooth bounds it (h = d), else at the
  // kinks where the previous tooth's circle meets the earlier positions' boundary.
  V2 contact{};
  const V2 ahead = p + R_ * V2{cp.x / d, cp.y / d};
  if (dist_to_past(cv, ahead, theta, th_p, R_ - tol) >= R_ - tol) {
    out.h_mm = d;
    contact = ahead;
  } else {
    roots_for(p, tooth_roots);
    for (const auto& rj : tooth_roots) {
      for (const Root& r : rj) {
        e = r.e;
        if (!on_engaged_arc(e)) continue;
        if (dist_to_past(cv, e, theta, th_p, R_ - 1e-7 * R_) < R_ - 1e-7 * R_) continue;  // buried
        const double h = R_ - norm(e - c);
        if (h > out.h_mm) {
          out.h_mm = h;
          contact = e;
        }
      }
    }
  }
  // Where the earlier surface alone bounds the chip (a wall cusp the previous cycle left):
  // the envelope point nearest the centre between two crossings with the tool circle. Not
  // needed when the previous tooth bounds the chip straight ahead: no chip exceeds |c - p|.
  auto ray_tooth = [&](V2 u) {  // far crossing of the ray from c along u with p's circle
    const V2 o = p - c;
    const double t = dot(o, u), q = R_ * R_ - (dot(o, o) - t * t);
    return q >= 0 ? t + std::sqrt(q) : 0.0;
  };
  const bool tooth_bound = out.h_mm == d;
  for (const auto& rj : tool_roots) {
    for (std::size_t k = 0; k + 1 < rj.size() && !tooth_bound; ++k) {
      const int j = rj[k].j;
      const double lo = rj[k].t, hi = rj[k + 1].t;
      // The nearest point: a root of d/dt |E - c|^2 / 2 = (E - c) . E' (negative at the
      // first crossing, positive at the second when the dip is a single valley); golden
      // section where it is not.
      const V2 shift{0, (j - 1) * s_};
      auto slope = [&](double t) {
        V2 q, dq;
        cv.envelope(t, q, dq);
        return dot(q - shift - c, dq);
      };
      auto dist_c = [&](double t) { return norm(env_at(t, j) - c); };
      // Newton on the slope (its derivative |E'|^2 + (E - c) . E'') from the table's sample
      // nearest c between the crossings, kept in the bracket; the bracketed search where a
      // step leaves it, the slope's derivative is not positive, or 8 steps do not converge.
      // (The distance is stationary there: 1e-9 rad in t moves it by ~1e-17 mm.)
      const V2 cq = c + shift;  // c against the unshifted envelope
      double tm = 0.5 * (lo + hi);
      {
        const int m0 = static_cast<int>(std::ceil(lo / env_dt_)),
                  m1 = static_cast<int>(std::floor(hi / env_dt_));
        double best = 1e300;
        for (int m = m0; m <= m1; ++m) {
          const V2 r = tb.env_at(m) - cq;
          const double dd = dot(r, r);
          if (dd < best) {
            best = dd;
            tm = m * env_dt_;
          }
        }
      }
      bool newton = false;
      for (int it = 0; it < 8; ++it) {
        V2 q, dq, ddq;
        cv.envelope2(tm, q, dq, ddq);
        const V2 r = q - cq;
        const double f = dot(r, dq), df = dot(dq, dq) + dot(r, ddq);
        if (!(df > 0)) break;
        const double tn = tm - f / df;
        if (!(tn > lo && tn < hi)) break;
        const double step = tn - tm;
        tm = tn;
        if (std::abs(step) < 1e-9) {
          newton = true;
          break;
        }
      }
      if (!newton) tm = detail::bracketed_minimum(dist_c, slope, lo, hi, 1e-10);
      e = env_at(tm, j);
      const double rho = norm(e - c);
      if (rho >= R_ || !on_engaged_arc(e) ||
          dist_to_past(cv, e, theta, th_p, R_ - 1e-7 * R_) < R_ - 1e-7 * R_) {
        continue;
      }
      const V2 u{(e.x - c.x) / rho, (e.y - c.y) / rho};
      const double h = R_ - std::max(rho, ray_tooth(u));
      if (h > out.h_mm) {
        out.h_mm = h;
        contact = e;
      }
    }
  }
  if (out.h_mm <= 0) {
    out.h_mm = 0;
    return out;
  }
  // Kinematic angle change at the contact: the feed's radial component over the edge speed.
  const double cl = norm(contact - c);
  const V2 u{(contact.x - c.x) / cl, (contact.y - c.y) / cl};
  const double v_feed = feed_mm_per_s_ / norm(v);  // d1 scaled to the feed speed
  out.kappa_rad = std::atan2(v_feed * dot(v, u), edge_speed_mm_per_s_);
  return out;
}

}  // namespace trochomill::mech
