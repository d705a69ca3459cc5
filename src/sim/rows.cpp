// The plugin libtrochomill_rows.so: the rows of one layer crossing an annular sector,
// vectorised (src/sim/rows.hpp). Highway's dynamic dispatch: this file is compiled once per
// target (foreach_target.h includes it again for each), and the table's functions call the
// best the processor supports.
#undef HWY_TARGET_INCLUDE
#define HWY_TARGET_INCLUDE "sim/rows.cpp"
#include "sim/rows.hpp"

#include <hwy/foreach_target.h>  // must come before highway.h
#include <hwy/highway.h>

#include <cmath>
#include <limits>

HWY_BEFORE_NAMESPACE();
namespace trochomill::sim_detail {
namespace HWY_NAMESPACE {
namespace hn = hwy::HWY_NAMESPACE;

constexpr double kInf = std::numeric_limits<double>::infinity();

// std::min(a, b) and std::max(a, b) lane by lane, ties and signed zeros included: b only
// where it compares below (above) a.
template <class V>
V min_of(V a, V b) {
  return hn::IfThenElse(hn::Lt(b, a), b, a);
}
template <class V>
V max_of(V a, V b) {
  return hn::IfThenElse(hn::Lt(a, b), b, a);
}

void RowChordsImpl(const SlicerCoeffs& sector, double origin, double d, int r0, int n,
                   double centre, bool negate, double R, double r_in, RowChords& out) {
  const hn::ScalableTag<double> df;
  const std::size_t N = hn::Lanes(df);
  const auto inf = hn::Set(df, kInf), ninf = hn::Set(df, -kInf), zero = hn::Zero(df);
  const auto vR2 = hn::Set(df, R * R), vri2 = hn::Set(df, r_in * r_in);
  const auto half = hn::Set(df, 0.5), vd = hn::Set(df, d), vo = hn::Set(df, origin);
  const auto vc = hn::Set(df, centre);
  // Whole vectors are stored: room for the last one's lanes past n.
  out.reserve_rows((static_cast<std::size_t>(n) + N - 1) / N * N);
  for (std::size_t k = 0; k < static_cast<std::size_t>(n); k += N) {
    // The rows' distances: origin + (r + 1/2) d - centre (DexelBoard::u_of, v_of).
    const auto idx = hn::Iota(df, static_cast<double>(r0) + static_cast<double>(k));
    const auto perp = hn::Sub(hn::Add(vo, hn::Mul(hn::Add(idx, half), vd)), vc);
    const auto dy = negate ? hn::Neg(perp) : perp;
    const auto dy2 = hn::Mul(dy, dy);
    const auto inside = hn::Lt(dy2, vR2);
    const auto w = hn::Sqrt(hn::Sub(vR2, dy2));  // NaN outside: those lanes are dropped
    // SectorSlicer::on_line, lines off the centre: the ends of each piece the line's side
    // holds.
    auto lo = inf, hi = ninf;
    for (const SlicerCoeffs::Piece& p : sector.piece) {
      if (!p.valid) continue;
      const auto ps = hn::Set(df, p.s);
      const auto act = hn::Gt(hn::Mul(ps, dy), zero);
      for (int e = 0; e < 2; ++e) {
        const auto sa = hn::Set(df, p.sin[e]), ca = hn::Set(df, p.cos[e]);
        const auto cady = hn::Mul(ca, dy);
        // At a split (or a line on the other side): the line runs off to the end ca dy s gives.
        const auto runs_off = hn::IfThenElse(hn::Gt(hn::Mul(cady, ps), zero), inf, ninf);
        const auto x = std::abs(p.sin[e]) < 1e-300
                           ? runs_off
                           : hn::IfThenElse(hn::Le(hn::Mul(sa, dy), zero), runs_off,
                                            hn::Div(hn::Mul(dy, ca), sa));
        lo = hn::IfThenElse(act, min_of(lo, x), lo);
        hi = hn::IfThenElse(act, max_of(hi, x), hi);
      }
    }
    // Lines through the centre: the range's angles 0 and pi.
    auto lo0 = inf, hi0 = ninf;
    if (sector.has0) lo0 = min_of(lo0, zero), hi0 = max_of(hi0, w);
    if (sector.has_pi) lo0 = min_of(lo0, hn::Neg(w)), hi0 = max_of(hi0, zero);
    const auto through = hn::Eq(dy, zero);
    lo = max_of(hn::IfThenElse(through, lo0, lo), hn::Neg(w));
    hi = min_of(hn::IfThenElse(through, hi0, hi), w);
    const auto chord = hn::And(inside, hn::Lt(lo, hi));
    // annulus_parts: the chord within [r_in, R] of the centre (the row's distance is |dy|).
    const auto ti = hn::IfThenElse(hn::Lt(dy2, vri2), hn::Sqrt(hn::Sub(vri2, dy2)), zero);
    const auto split = hn::Gt(ti, zero);
    const auto a_lo = max_of(hn::Neg(w), lo);
    const auto a_hi = min_of(hn::IfThenElse(split, hn::Neg(ti), w), hi);
    const auto b_lo = max_of(ti, lo);
    const auto b_hi = min_of(w, hi);
    const auto has_a = hn::And(chord, hn::Lt(a_lo, a_hi));
    const auto has_b = hn::And(hn::And(chord, split), hn::Lt(b_lo, b_hi));
    hn::StoreU(perp, df, out.perp.data() + k);
    hn::StoreU(lo, df, out.lo.data() + k);
    hn::StoreU(hi, df, out.hi.data() + k);
    hn::StoreU(hn::IfThenElse(has_a, a_lo, inf), df, out.a_lo.data() + k);
    hn::StoreU(hn::IfThenElse(has_a, a_hi, ninf), df, out.a_hi.data() + k);
    hn::StoreU(hn::IfThenElse(has_b, b_lo, inf), df, out.b_lo.data() + k);
    hn::StoreU(hn::IfThenElse(has_b, b_hi, ninf), df, out.b_hi.data() + k);
  }
}

void RaysMaybeImpl(const double* HWY_RESTRICT rays, int count, int first, double along,
                   RowChords& out) {
  const hn::ScalableTag<double> df;
  const std::size_t N = hn::Lanes(df);
  const auto va = hn::Set(df, along);
  const auto one = hn::Set(df, 1.0);
  // Overlap of [lo, hi] with (p_lo, p_hi): NaN bounds (an unused interval) never overlap.
  const auto overlaps = [](auto lo, auto hi, auto p_lo, auto p_hi) {
    return hn::And(hn::Gt(hi, p_lo), hn::Lt(lo, p_hi));
  };
  const auto n = static_cast<std::size_t>(count), f = static_cast<std::size_t>(first);
  std::size_t k = 0;
  for (; k + N <= n; k += N) {
    decltype(hn::Zero(df)) lo0, hi0, lo1, hi1;
    hn::LoadInterleaved4(df, rays + 4 * k, lo0, hi0, lo1, hi1);
    const auto a_lo = hn::Add(va, hn::LoadU(df, out.a_lo.data() + f + k));
    const auto a_hi = hn::Add(va, hn::LoadU(df, out.a_hi.data() + f + k));
    const auto b_lo = hn::Add(va, hn::LoadU(df, out.b_lo.data() + f + k));
    const auto b_hi = hn::Add(va, hn::LoadU(df, out.b_hi.data() + f + k));
    const auto in_a = hn::Or(overlaps(lo0, hi0, a_lo, a_hi), overlaps(lo1, hi1, a_lo, a_hi));
    const auto in_b = hn::Or(overlaps(lo0, hi0, b_lo, b_hi), overlaps(lo1, hi1, b_lo, b_hi));
    const auto maybe = hn::Or(hn::IsNaN(lo0), hn::Or(in_a, in_b));
    hn::StoreU(hn::IfThenElseZero(maybe, one), df, out.maybe.data() + f + k);
  }
  // The last rays, fewer than a vector: the same test one at a time (reading no further).
  for (; k < n; ++k) {
    const double* r = rays + 4 * k;
    const double a_lo = along + out.a_lo[f + k], a_hi = along + out.a_hi[f + k];
    const double b_lo = along + out.b_lo[f + k], b_hi = along + out.b_hi[f + k];
    const auto ov = [](double lo, double hi, double p_lo, double p_hi) {
      return hi > p_lo && lo < p_hi;
    };
    const bool maybe = std::isnan(r[0]) || ov(r[0], r[1], a_lo, a_hi) ||
                       ov(r[2], r[3], a_lo, a_hi) || ov(r[0], r[1], b_lo, b_hi) ||
                       ov(r[2], r[3], b_lo, b_hi);
    out.maybe[f + k] = maybe ? 1.0 : 0.0;
  }
}

}  // namespace HWY_NAMESPACE
}  // namespace trochomill::sim_detail
HWY_AFTER_NAMESPACE();

#if HWY_ONCE
namespace trochomill::sim_detail {

HWY_EXPORT(RowChordsImpl);
HWY_EXPORT(RaysMaybeImpl);

namespace {

void row_chords_any(const SlicerCoeffs& sector, double origin, double d, int r0, int n,
                    double centre, bool negate, double R, double r_in, RowChords& out) {
  HWY_DYNAMIC_DISPATCH(RowChordsImpl)(sector, origin, d, r0, n, centre, negate, R, r_in, out);
}

void rays_maybe_any(const double* rays, int count, int first, double along, RowChords& out) {
  HWY_DYNAMIC_DISPATCH(RaysMaybeImpl)(rays, count, first, along, out);
}

const RowsTable kTable{&row_chords_any, &rays_maybe_any};

}  // namespace

}  // namespace trochomill::sim_detail

extern "C" __attribute__((visibility("default"))) const trochomill::sim_detail::RowsTable*
trochomill_rows_table() {
  return &trochomill::sim_detail::kTable;
}
#endif  // HWY_ONCE
