// Small numeric helpers shared by the modules (not installed).
#pragma once

namespace trochomill::detail {

/// A root of f in [lo, hi] where f(lo) = flo and f(hi) = fhi differ in sign: regula falsi
/// with the Illinois modification (superlinear, never leaves the bracket), until the
/// bracket is narrower than `tol` or f is exactly zero.
template <typename F>
double regula_falsi(F&& f, double lo, double hi, double flo, double fhi, double tol) {
  double r = 0.5 * (lo + hi);
  int side = 0;
  for (int it = 0; it < 200 && hi - lo > tol; ++it) {
    r = (flo * hi - fhi * lo) / (flo - fhi);
    if (!(r > lo && r < hi)) r = 0.5 * (lo + hi);
    const double fr = f(r);
    if (fr == 0) break;
    if ((fr < 0) == (flo < 0)) {
      lo = r;
      flo = fr;
      if (side == -1) fhi *= 0.5;
      side = -1;
    } else {
      hi = r;
      fhi = fr;
      if (side == 1) flo *= 0.5;
      side = 1;
    }
  }
  return r;
}

/// A minimum of f in [lo, hi] given its derivative df: where df goes from negative to
/// positive over the bracket (a single valley) a root of df by regula falsi, otherwise a
/// golden-section search on f; either to a bracket narrower than `tol`.
template <typename F, typename DF>
double bracketed_minimum(F&& f, DF&& df, double lo, double hi, double tol) {
  const double dlo = df(lo), dhi = df(hi);
  if (dlo < 0 && dhi > 0) return regula_falsi(df, lo, hi, dlo, dhi, tol);
  for (int it = 0; it < 200 && hi - lo > tol; ++it) {
    const double m1 = lo + 0.381966 * (hi - lo), m2 = lo + 0.618034 * (hi - lo);
    if (f(m1) < f(m2)) {
      hi = m2;
    } else {
      lo = m1;
    }
  }
  return 0.5 * (lo + hi);
}

}  // namespace trochomill::detail
