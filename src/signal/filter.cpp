// Butterworth band-pass design in second-order sections, causal and zero-phase filtering
// (include/trochomill/signal.hpp; docs/models.md section 10).
#include <fmt/format.h>

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
    z[0] = s[1] * x - s[4] * y + z[1];
    z[1] = s[2] * x - s[5] * y;
    x = y;
  }
  return x;
}

void SosFilter::process(const double* in, double* out, std::size_t n) {
  // Section by section over the whole block (the state stays in registers); the same
  // arithmetic, in the same order per sample, as step().
  if (n == 0) return;
  if (out != in) std::copy(in, in + n, out);
  for (std::size_t k = 0; k < sos_.sections.size(); ++k) {
    const auto& s = sos_.sections[k];
    const double b0 = s[0], b1 = s[1], b2 = s[2], a1 = s[4], a2 = s[5];
    double z0 = z_[k][0], z1 = z_[k][1];
    for (std::size_t i = 0; i < n; ++i) {
      const double x = out[i];
      const double y = b0 * x + z0;
      z0 = b1 * x - a1 * y + z1;
      z1 = b2 * x - a2 * y;
      out[i] = y;
    }
    z_[k] = {z0, z1};
  }
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

void filter_from(const Sos& sos, const std::vector<std::array<double, 2>>& zi, double scale,
                 std::vector<double>& x) {
  std::vector<std::array<double, 2>> z = zi;
  for (auto& v : z) v = {v[0] * scale, v[1] * scale};
  for (std::size_t k = 0; k < sos.sections.size(); ++k) {
    const auto& s = sos.sections[k];
    double z0 = z[k][0], z1 = z[k][1];
    for (double& v : x) {
      const double y = s[0] * v + z0;
      z0 = s[1] * v - s[4] * y + z1;
      z1 = s[2] * v - s[5] * y;
      v = y;
    }
  }
}

}  // namespace

std::vector<double> sosfiltfilt(const Sos& sos, const std::vector<double>& x) {
  const std::size_t pad = 3 * (2 * sos.sections.size() + 1);
  if (x.size() <= pad) {
    throw InputError(
        fmt::format("zero-phase filtering needs more than {} samples, got {}", pad, x.size()));
  }
  // Odd extension: 2 x[0] - x[pad..1] before, 2 x[n-1] - x[n-2..n-1-pad] after.
  const std::size_t n = x.size();
  std::vector<double> e(n + 2 * pad);
  for (std::size_t i = 0; i < pad; ++i) e[i] = 2 * x[0] - x[pad - i];
  std::copy(x.begin(), x.end(), e.begin() + static_cast<std::ptrdiff_t>(pad));
  for (std::size_t i = 0; i < pad; ++i) e[pad + n + i] = 2 * x[n - 1] - x[n - 2 - i];
  const auto zi = step_states(sos);
  filter_from(sos, zi, e.front(), e);
  std::reverse(e.begin(), e.end());
  filter_from(sos, zi, e.front(), e);
  std::reverse(e.begin(), e.end());
  return {e.begin() + static_cast<std::ptrdiff_t>(pad),
          e.begin() + static_cast<std::ptrdiff_t>(pad + n)};
}

}  // namespace trochomill
