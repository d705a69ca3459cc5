// Welch spectrum and STFT spectrogram with Eigen's FFT (include/trochomill/signal.hpp).
#include <fmt/format.h>

#include <cmath>
#include <complex>
#include <unsupported/Eigen/FFT>

#include "trochomill/error.hpp"
#include "trochomill/signal.hpp"
#include "trochomill/units.hpp"

namespace trochomill {

namespace {

void check(const Signal& s, int nfft) {
  if (nfft < 8 || (nfft & (nfft - 1)) != 0) {
    throw InputError(fmt::format("nfft must be a power of two >= 8, got {}", nfft));
  }
  if (s.samples.size() < static_cast<std::size_t>(nfft)) {
    throw InputError(
        fmt::format("the signal has {} samples, fewer than nfft = {}", s.samples.size(), nfft));
  }
}

std::vector<double> hann(int n) {  // periodic Hann (scipy's default for spectral analysis)
  std::vector<double> w(static_cast<std::size_t>(n));
  for (int i = 0; i < n; ++i) w[static_cast<std::size_t>(i)] = 0.5 - 0.5 * std::cos(kTwoPi * i / n);
  return w;
}

// |X_k| of each frame starting at `hop` steps, detrended by its mean, Hann-windowed.
template <typename F>
void frames(const Signal& s, int nfft, F&& on_frame) {
  const auto n = static_cast<std::size_t>(nfft), hop = n / 2;
  const std::vector<double> w = hann(nfft);
  Eigen::FFT<double> fft;
  std::vector<double> buf(n);
  std::vector<std::complex<double>> out;
  for (std::size_t start = 0; start + n <= s.samples.size(); start += hop) {
    double mean = 0;
    for (std::size_t i = 0; i < n; ++i) mean += s.samples[start + i];
    mean /= static_cast<double>(n);
    for (std::size_t i = 0; i < n; ++i) buf[i] = (s.samples[start + i] - mean) * w[i];
    fft.fwd(out, buf);
    on_frame(start, out);
  }
}

}  // namespace

Spectrum welch(const Signal& s, int nfft) {
  check(s, nfft);
  const auto n = static_cast<std::size_t>(nfft);
  const std::vector<double> w = hann(nfft);
  double wss = 0;
  for (const double v : w) wss += v * v;
  Spectrum sp;
  sp.psd.assign(n / 2 + 1, 0.0);
  int count = 0;
  frames(s, nfft, [&](std::size_t, const std::vector<std::complex<double>>& x) {
    for (std::size_t k = 0; k <= n / 2; ++k) sp.psd[k] += std::norm(x[k]);
    ++count;
  });
  for (std::size_t k = 0; k <= n / 2; ++k) {
    // Density scaling: |X|^2 / (fs sum w^2), doubled except at DC and Nyquist.
    const double one_sided = (k == 0 || k == n / 2) ? 1.0 : 2.0;
    sp.psd[k] *= one_sided / (s.rate_hz * wss * count);
    sp.f_hz.push_back(s.rate_hz * static_cast<double>(k) / nfft);
  }
  return sp;
}

Spectrogram spectrogram(const Signal& s, int nfft) {
  check(s, nfft);
  const auto n = static_cast<std::size_t>(nfft);
  const std::vector<double> w = hann(nfft);
  double wsum = 0;
  for (const double v : w) wsum += v;
  Spectrogram sg;
  for (std::size_t k = 0; k <= n / 2; ++k)
    sg.f_hz.push_back(s.rate_hz * static_cast<double>(k) / nfft);
  frames(s, nfft, [&](std::size_t start, const std::vector<std::complex<double>>& x) {
    sg.t_s.push_back((static_cast<double>(start) + 0.5 * nfft) / s.rate_hz);
    std::vector<double> row(n / 2 + 1);
    for (std::size_t k = 0; k <= n / 2; ++k) {
      // Amplitude scaling: a sine of amplitude A in bin k reads A (2 |X| / sum w).
      const double amp = (k == 0 ? 1.0 : 2.0) * std::abs(x[k]) / wsum;
      row[k] = 20 * std::log10(std::max(amp, 1e-300));
    }
    sg.db.push_back(std::move(row));
  });
  return sg;
}

}  // namespace trochomill
