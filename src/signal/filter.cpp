// Butterworth band-pass design in second-order sections, causal and zero-phase filtering
// (include/trochomill/signal.hpp; docs/models.md section 10).
#include <fmt/format.h>
#if defined(__SSE2__)
#include <xmmintrin.h>
#endif

#include <algorithm>
#include <cmath>
#include <complex>

#include "trochomill/error.hpp"
#include "trochomill/signal.hpp"
#include "trochomill/units.hpp"

namespace trochomill {

using cplx = std::complex<double>;

Sos butter_bandpass(int order, double lo_hz, double hi_hz, double rate_hz) {
  if (order < 1 || order > 12) {
    throw InputError(fmt::format("filter order must be 1..12, got {}", order));
  }
  if (!(rate_hz > 0)) throw InputError(fmt::format("sample rate must be > 0 Hz, got {}", rate_hz));
  if (!(lo_hz > 0 && lo_hz < hi_hz && hi_hz < 0.5 * rate_hz)) {
    throw InputError(fmt::format("band {:g}-{:g} Hz: need 0 < low < high < rate / 2 = {:g} Hz",
                                 lo_hz, hi_hz, 0.5 * rate_hz));
  }
  // Analog prototype: the order's Butterworth poles on the unit circle's left half.
  const int n = order;
  std::vector<cplx> proto;
  for (int k = 0; k < n; ++k) {
    proto.push_back(std::polar(1.0, kPi * (2.0 * k + n + 1) / (2.0 * n)));
  }
  // Pre-warped band edges (rad/s) for the bilinear transform with fs = rate.
  const double fs2 = 2 * rate_hz;
  const double wl = fs2 * std::tan(kPi * lo_hz / rate_hz),
               wh = fs2 * std::tan(kPi * hi_hz / rate_hz);
  const double bw = wh - wl, w0 = std::sqrt(wl * wh);
  // Low-pass to band-pass: each pole p -> p bw / 2 +- sqrt((p bw / 2)^2 - w0^2); n zeros at
  // s = 0; gain bw^n.
  std::vector<cplx> poles;
  for (const cplx& p : proto) {
    const cplx q = p * (0.5 * bw), r = std::sqrt(q * q - w0 * w0);
    poles.push_back(q + r);
    poles.push_back(q - r);
  }
  // Bilinear transform: z = (fs2 + s) / (fs2 - s); the n zeros at s = 0 go to z = 1 and the
  // n at infinity to z = -1; gain k bw^n prod(fs2 - zeros) / prod(fs2 - poles).
  std::vector<cplx> zp;
  cplx gain = std::pow(bw, n);
  for (int k = 0; k < n; ++k) gain *= fs2;  // the zeros at s = 0
  for (const cplx& p : poles) {
    zp.push_back((fs2 + p) / (fs2 - p));
    gain /= (fs2 - p);
  }
  // Sections: one conjugate pole pair each (the upper-half-plane pole of every pair, ordered
  // by radius so the sharpest sections come last), zeros {+1, -1}: b = g (1, 0, -1).
  std::vector<cplx> upper;
  for (const cplx& p : zp) {
    if (p.imag() > 0) upper.push_back(p);
  }
  if (static_cast<int>(upper.size()) != n) {
    throw Error(fmt::format("butter_bandpass: {} complex pole pairs for order {}; this is a bug",
                            upper.size(), n));
  }
  std::sort(upper.begin(), upper.end(),
            [](const cplx& a, const cplx& b) { return std::abs(a) < std::abs(b); });
  Sos sos;
  for (int k = 0; k < n; ++k) {
    const cplx p = upper[static_cast<std::size_t>(k)];
    const double g = k == 0 ? gain.real() : 1.0;
    sos.sections.push_back({g, 0.0, -g, 1.0, -2 * p.real(), std::norm(p)});
  }
  return sos;
}

Sos butter_lowpass(int order, double cutoff_hz, double rate_hz) {
  if (order < 1 || order > 12) {
    throw InputError(fmt::format("filter order must be 1..12, got {}", order));
  }
  if (!(rate_hz > 0)) throw InputError(fmt::format("sample rate must be > 0 Hz, got {}", rate_hz));
  if (!(cutoff_hz > 0 && cutoff_hz < 0.5 * rate_hz)) {
    throw InputError(fmt::format("cutoff {:g} Hz: need 0 < cutoff < rate / 2 = {:g} Hz", cutoff_hz,
                                 0.5 * rate_hz));
  }
  // Analog poles wc p_k (pre-warped wc); bilinear transform; n zeros at z = -1; unit DC gain
  // per section.
  const int n = order;
  const double fs2 = 2 * rate_hz, wc = fs2 * std::tan(kPi * cutoff_hz / rate_hz);
  Sos sos;
  std::vector<cplx> upper;
  double real_pole = 0;
  bool has_real = false;
  for (int k = 0; k < n; ++k) {
    const cplx s = wc * std::polar(1.0, kPi * (2.0 * k + n + 1) / (2.0 * n));
    const cplx z = (fs2 + s) / (fs2 - s);
    if (std::abs(z.imag()) < 1e-14) {
      real_pole = z.real();
      has_real = true;
    } else if (z.imag() > 0) {
      upper.push_back(z);
    }
  }
  std::sort(upper.begin(), upper.end(),
            [](const cplx& a, const cplx& b) { return std::abs(a) < std::abs(b); });
  if (has_real) {  // (1 + z^-1) / (1 - p z^-1), gain (1 - p) / 2 at DC = 1
    const double g = 0.5 * (1 - real_pole);
    sos.sections.push_back({g, g, 0.0, 1.0, -real_pole, 0.0});
  }
  for (const cplx& p : upper) {  // (1 + z^-1)^2 / (1 - 2 Re p z^-1 + |p|^2 z^-2)
    const double a1 = -2 * p.real(), a2 = std::norm(p), g = (1 + a1 + a2) / 4;
    sos.sections.push_back({g, 2 * g, g, 1.0, a1, a2});
  }
  return sos;
}

double sos_gain(const Sos& sos, double f_hz, double rate_hz) {
  const cplx z1 = std::polar(1.0, -kTwoPi * f_hz / rate_hz);  // z^-1
  const cplx z2 = z1 * z1;
  cplx h = 1.0;
  for (const auto& s : sos.sections) {
    h *= (s[0] + s[1] * z1 + s[2] * z2) / (s[3] + s[4] * z1 + s[5] * z2);
  }
  return std::abs(h);
}

SosFilter::SosFilter(Sos sos) : sos_(std::move(sos)), z_(sos_.sections.size(), {0.0, 0.0}) {}

void SosFilter::reset() { std::fill(z_.begin(), z_.end(), std::array<double, 2>{0.0, 0.0}); }

double SosFilter::step(double x) {
  for (std::size_t k = 0; k < sos_.sections.size(); ++k) {
    const auto& s = sos_.sections[k];
    auto& z = z_[k];
    const double y = s[0] * x + z[0];
    z[0] = s[1] * x + z[1] - s[4] * y;
    z[1] = s[2] * x - s[5] * y;
    x = y;
  }
  return x;
}

namespace {

// Subnormal numbers flushed to zero while a filter runs over a block (x86's FTZ and DAZ
// flags, restored after): where the input rests at zero (a force while the tool is out of the
// cut) the sections' states decay through the subnormal range, where each operation costs
// about a hundred cycles (calibrate's model filter on the Bergmann cycle ran 4x slower). Only
// values below 2.2e-308 change. Not in SosFilter::step: per sample the flags cost more.
class FlushSubnormals {
 public:
#if defined(__SSE2__)
  FlushSubnormals() : csr_(_mm_getcsr()) { _mm_setcsr(csr_ | 0x8040); }
  ~FlushSubnormals() { _mm_setcsr(csr_); }
  FlushSubnormals(const FlushSubnormals&) = delete;
  FlushSubnormals& operator=(const FlushSubnormals&) = delete;

 private:
  unsigned csr_;
#endif
};

// One cascade over a block, sample by sample through all sections (as step() does), so the
// out-of-order core overlaps section k of sample i + 1 with section k + 1 of sample i: the
// recurrences, not the arithmetic, bound the speed. Each section's first state adds the
// input's term and the second state before it takes the output's term (b1 x + z2 - a1 y, where
// scipy writes b1 x - a1 y + z2): the output reaches the next state through a multiply and a
// subtraction, three dependent operations a sample with the output's addition, not four.
// Up to 12 sections (the design limit).
struct Cascade {
  double c[12][5];  // b0, b1, b2, a1, a2
  double z[12][2];
  std::size_t n = 0;
  Cascade(const Sos& sos, const std::vector<std::array<double, 2>>& state)
      : n(sos.sections.size()) {
    for (std::size_t k = 0; k < n; ++k) {
      const auto& s = sos.sections[k];
      c[k][0] = s[0], c[k][1] = s[1], c[k][2] = s[2], c[k][3] = s[4], c[k][4] = s[5];
      z[k][0] = state[k][0], z[k][1] = state[k][1];
    }
  }
  double step(double x) {
    for (std::size_t k = 0; k < n; ++k) {
      const double y = c[k][0] * x + z[k][0];
      z[k][0] = c[k][1] * x + z[k][1] - c[k][3] * y;
      z[k][1] = c[k][2] * x - c[k][4] * y;
      x = y;
    }
    return x;
  }
  void save(std::vector<std::array<double, 2>>& state) const {
    for (std::size_t k = 0; k < n; ++k) state[k] = {z[k][0], z[k][1]};
  }
};

// Two cascades of the same length over two inputs in one loop, the two in the two lanes of
// a vector register (GCC/Clang vector extension: each lane computes exactly what the scalar
// Cascade::step computes, no fused multiply-add, so the results are bit-identical), forward
// or from the end backward. Both inputs are read before either output is written, so an
// output may be its own input or the other's.
using v2d = double __attribute__((vector_size(16)));
void run_pair(Cascade& a, const double* xa, double* ya, Cascade& b, const double* xb, double* yb,
              std::size_t n, bool backward) {
  const FlushSubnormals flush;
  const std::size_t ns = a.n;
  v2d c[12][5], z[12][2];
  for (std::size_t k = 0; k < ns; ++k) {
    for (int q = 0; q < 5; ++q) c[k][q] = v2d{a.c[k][q], b.c[k][q]};
    z[k][0] = v2d{a.z[k][0], b.z[k][0]};
    z[k][1] = v2d{a.z[k][1], b.z[k][1]};
  }
  for (std::size_t j = 0; j < n; ++j) {
    const std::size_t i = backward ? n - 1 - j : j;
    v2d x = {xa[i], xb[i]};
    for (std::size_t k = 0; k < ns; ++k) {
      const v2d y = c[k][0] * x + z[k][0];
      z[k][0] = c[k][1] * x + z[k][1] - c[k][3] * y;
      z[k][1] = c[k][2] * x - c[k][4] * y;
      x = y;
    }
    ya[i] = x[0];
    yb[i] = x[1];
  }
  for (std::size_t k = 0; k < ns; ++k) {  // the states at the end, for a stream's next block
    a.z[k][0] = z[k][0][0], a.z[k][1] = z[k][1][0];
    b.z[k][0] = z[k][0][1], b.z[k][1] = z[k][1][1];
  }
}

// Three cascades of one filter over three signals in one loop, in place, the three in lanes
// of a vector (as run_pair: each lane computes exactly what Cascade::step computes; the fourth
// lane idles), forward or from the end backward.
using v4d = double __attribute__((vector_size(32)));
void run_three(const std::array<Cascade, 3>& cs, const std::array<double*, 3>& x, std::size_t n,
               bool backward) {
  const FlushSubnormals flush;
  const std::size_t ns = cs[0].n;
  v4d c[12][5], z[12][2];
  for (std::size_t k = 0; k < ns; ++k) {
    for (int q = 0; q < 5; ++q) c[k][q] = v4d{cs[0].c[k][q], cs[1].c[k][q], cs[2].c[k][q], 0.0};
    for (int q = 0; q < 2; ++q) z[k][q] = v4d{cs[0].z[k][q], cs[1].z[k][q], cs[2].z[k][q], 0.0};
  }
  for (std::size_t j = 0; j < n; ++j) {
    const std::size_t i = backward ? n - 1 - j : j;
    v4d v = {x[0][i], x[1][i], x[2][i], 0.0};
    for (std::size_t k = 0; k < ns; ++k) {
      const v4d y = c[k][0] * v + z[k][0];
      z[k][0] = c[k][1] * v + z[k][1] - c[k][3] * y;
      z[k][1] = c[k][2] * v - c[k][4] * y;
      v = y;
    }
    x[0][i] = v[0];
    x[1][i] = v[1];
    x[2][i] = v[2];
  }
}

// One cascade over a block in run_pair's loop, its twin in the other lane on the same input
// and its output dropped: the pair's loop (its states in vector registers) runs a cascade in
// about half the time of the scalar loop above, bit for bit the same (run_pair's lanes
// compute what Cascade::step computes).
void run_one(Cascade& c, const double* in, double* out, std::size_t n) {
  Cascade twin = c;
  constexpr std::size_t kBlock = 1024;
  double drop[kBlock];
  for (std::size_t at = 0; at < n; at += kBlock) {
    const std::size_t m = std::min(kBlock, n - at);
    run_pair(c, in + at, out + at, twin, in + at, drop, m, false);
  }
}

}  // namespace

void SosFilter::process(const double* in, double* out, std::size_t n) {
  if (sos_.sections.size() > 12) throw Error("SosFilter: more than 12 sections");
  Cascade c(sos_, z_);
  run_one(c, in, out, n);
  c.save(z_);
}

void SosFilter::process_pair(SosFilter& a, SosFilter& b, const double* in, double* out_a,
                             double* out_b, std::size_t n) {
  if (a.sos_.sections.size() != b.sos_.sections.size()) {
    a.process(in, out_a, n);
    b.process(in, out_b, n);
    return;
  }
  if (a.sos_.sections.size() > 12) throw Error("SosFilter: more than 12 sections");
  Cascade ca(a.sos_, a.z_), cb(b.sos_, b.z_);
  run_pair(ca, in, out_a, cb, in, out_b, n, false);
  ca.save(a.z_);
  cb.save(b.z_);
}

std::vector<double> sosfilt(const Sos& sos, const std::vector<double>& x) {
  SosFilter f(sos);
  std::vector<double> y(x.size());
  f.process(x.data(), y.data(), x.size());
  return y;
}

namespace {

// Steady-state section states for a unit step at the cascade's input (scipy's sosfilt_zi):
// section k sees a step scaled by the DC gains before it. For b = (b0, b1, b2), a = (1, a1,
// a2) and a step of height u: y = u sum(b) / sum(a), z1 = u (b1 + b2) - (a1 + a2) y,
// z2 = u b2 - a2 y.
std::vector<std::array<double, 2>> step_states(const Sos& sos) {
  std::vector<std::array<double, 2>> zi;
  double u = 1;
  for (const auto& s : sos.sections) {
    const double y = u * (s[0] + s[1] + s[2]) / (s[3] + s[4] + s[5]);
    zi.push_back({u * (s[1] + s[2]) - (s[4] + s[5]) * y, u * s[2] - s[5] * y});
    u = y;
  }
  return zi;
}

// The step states for a step of height k (scipy's zi * x[0]).
std::vector<std::array<double, 2>> scaled(std::vector<std::array<double, 2>> z, double k) {
  for (auto& v : z) v = {v[0] * k, v[1] * k};
  return z;
}

// The zero-phase filters' odd extension of x by `pad` samples at each end (2 x[0] - x[pad..1]
// before, 2 x[n-1] - x[n-2..n-1-pad] after; scipy's sosfiltfilt), into e. Refuses a signal
// of `pad` samples or fewer.
void odd_extension(const std::vector<double>& x, std::size_t pad, std::vector<double>& e) {
  const std::size_t n = x.size();
  if (n <= pad) {
    throw InputError(
        fmt::format("zero-phase filtering needs more than {} samples, got {}", pad, n));
  }
  e.resize(n + 2 * pad);
  for (std::size_t i = 0; i < pad; ++i) e[i] = 2 * x[0] - x[pad - i];
  std::copy(x.begin(), x.end(), e.begin() + static_cast<std::ptrdiff_t>(pad));
  for (std::size_t i = 0; i < pad; ++i) e[pad + n + i] = 2 * x[n - 1] - x[n - 2 - i];
}

void filter_from(const Sos& sos, const std::vector<std::array<double, 2>>& zi, double scale,
                 std::vector<double>& x) {
  Cascade c(sos, scaled(zi, scale));
  run_one(c, x.data(), x.data(), x.size());
}

}  // namespace

std::vector<double> sosfiltfilt(const Sos& sos, const std::vector<double>& x) {
  const std::size_t pad = 3 * (2 * sos.sections.size() + 1), n = x.size();
  std::vector<double> e;
  odd_extension(x, pad, e);
  const auto zi = step_states(sos);
  filter_from(sos, zi, e.front(), e);
  std::reverse(e.begin(), e.end());
  filter_from(sos, zi, e.front(), e);
  std::reverse(e.begin(), e.end());
  return {e.begin() + static_cast<std::ptrdiff_t>(pad),
          e.begin() + static_cast<std::ptrdiff_t>(pad + n)};
}

void sosfiltfilt_three(const Sos& sos, std::array<std::vector<double>, 3>& xyz) {
  const std::size_t n = xyz[0].size();
  if (xyz[1].size() != n || xyz[2].size() != n || sos.sections.size() > 12) {
    for (auto& v : xyz) v = sosfiltfilt(sos, v);
    return;
  }
  // As sosfiltfilt: the odd extension, forward from the step states scaled by the first
  // value, backward (from the end, no reversal) by the last, the padding cut off.
  const std::size_t pad = 3 * (2 * sos.sections.size() + 1), m = n + 2 * pad;
  const auto zi = step_states(sos);
  std::array<std::vector<double>, 3> e;
  std::array<double*, 3> ptr{};
  for (std::size_t a = 0; a < 3; ++a) {
    odd_extension(xyz[a], pad, e[a]);
    ptr[a] = e[a].data();
  }
  run_three({Cascade(sos, scaled(zi, e[0].front())), Cascade(sos, scaled(zi, e[1].front())),
             Cascade(sos, scaled(zi, e[2].front()))},
            ptr, m, false);
  run_three({Cascade(sos, scaled(zi, e[0].back())), Cascade(sos, scaled(zi, e[1].back())),
             Cascade(sos, scaled(zi, e[2].back()))},
            ptr, m, true);
  for (std::size_t a = 0; a < 3; ++a) {
    std::copy(e[a].begin() + static_cast<std::ptrdiff_t>(pad),
              e[a].begin() + static_cast<std::ptrdiff_t>(pad + n), xyz[a].begin());
  }
}

void sosfilt_pair(const Sos& a, const Sos& b, const std::vector<double>& x, std::vector<double>& ya,
                  std::vector<double>& yb) {
  std::vector<std::array<double, 2>> za(a.sections.size(), {0.0, 0.0}),
      zb(b.sections.size(), {0.0, 0.0});
  if (a.sections.size() != b.sections.size()) {  // different orders: each on its own
    ya = sosfilt(a, x);
    yb = sosfilt(b, x);
    return;
  }
  Cascade ca(a, za), cb(b, zb);
  ya.resize(x.size());
  yb.resize(x.size());
  run_pair(ca, x.data(), ya.data(), cb, x.data(), yb.data(), x.size(), false);
}

void sosfiltfilt_pair(const Sos& a, const Sos& b, const std::vector<double>& x,
                      std::vector<double>& ya, std::vector<double>& yb) {
  const std::size_t pad = 3 * (2 * std::max(a.sections.size(), b.sections.size()) + 1);
  const std::size_t pa = 3 * (2 * a.sections.size() + 1), pb = 3 * (2 * b.sections.size() + 1);
  if (pa != pb) {  // different orders: each on its own
    ya = sosfiltfilt(a, x);
    yb = sosfiltfilt(b, x);
    return;
  }
  // Odd extension in fa; forward in place (fa) and into fb; backward in place, from the end
  // (no reversal); then the padding is cut off. Two buffers: large signals allocate (and
  // page-fault) little.
  const std::size_t n = x.size(), m = n + 2 * pad;
  std::vector<double> fa, fb(m);
  odd_extension(x, pad, fa);
  const auto zia = step_states(a), zib = step_states(b);
  {
    const double x0 = fa.front();
    Cascade ca(a, scaled(zia, x0)), cb(b, scaled(zib, x0));
    run_pair(ca, fa.data(), fa.data(), cb, fa.data(), fb.data(), m, false);
  }
  {
    Cascade ca(a, scaled(zia, fa.back())), cb(b, scaled(zib, fb.back()));
    run_pair(ca, fa.data(), fa.data(), cb, fb.data(), fb.data(), m, true);
  }
  for (auto* v : {&fa, &fb}) {
    v->erase(v->begin(), v->begin() + static_cast<std::ptrdiff_t>(pad));
    v->resize(n);
  }
  ya.swap(fa);
  yb.swap(fb);
}

}  // namespace trochomill
