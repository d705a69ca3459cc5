// The live monitor's input: samples from a stream (stdin) in raw or CSV form, decoded in
// bounded blocks (signal.hpp).
#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <string>
#include <vector>

#include "trochomill/error.hpp"
#include "trochomill/signal.hpp"

namespace trochomill {

void monitor_stream(std::FILE* in, SampleFormat f, LiveMonitor& live,
                    const std::function<void(const LiveWindow&)>& out) {
  if (f != SampleFormat::f32 && f != SampleFormat::s16 && f != SampleFormat::csv) {
    throw InputError(option_name("stream") + " reads " + option_name("format") +
                     " f32, s16 or csv");
  }
  if (f == SampleFormat::csv) {
    std::string line;
    long line_no = 0;
    for (int c = 0;;) {
      line.clear();
      while ((c = std::fgetc(in)) != EOF && c != '\n') line += static_cast<char>(c);
      if (c == EOF && line.empty()) break;
      ++line_no;
      if (!line.empty() && line.back() == '\r') line.pop_back();
      if (line.empty() || line[0] == '#') continue;
      char* end = nullptr;
      const double v = std::strtod(line.c_str(), &end);
      if (end == line.c_str() || !std::isfinite(v)) {
        throw InputError(fmt::format("stdin:{}: '{}' is not a finite number", line_no, line));
      }
      live.push(&v, 1, out);
      if (c == EOF) break;
    }
    return;
  }
  const std::size_t w = f == SampleFormat::f32 ? 4 : 2;
  std::vector<unsigned char> buf(w * 4096);
  std::vector<double> x;
  std::size_t have = 0;
  long long total = 0;
  for (;;) {
    const std::size_t got = std::fread(buf.data() + have, 1, buf.size() - have, in);
    have += got;
    const std::size_t n = have / w;
    x.resize(n);
    decode_raw(buf.data(), n, f, x.data());
    for (std::size_t i = 0; i < n; ++i) {
      if (!std::isfinite(x[i])) {
        throw InputError(
            fmt::format("stdin: sample {} is not finite", total + static_cast<long long>(i)));
      }
    }
    live.push(x.data(), n, out);
    total += static_cast<long long>(n);
    std::copy(buf.begin() + static_cast<std::ptrdiff_t>(n * w),
              buf.begin() + static_cast<std::ptrdiff_t>(have), buf.begin());
    have -= n * w;
    if (got == 0) break;
  }
  if (have != 0) {
    throw InputError(
        fmt::format("stdin: {} trailing byte(s) after {} samples: truncated", have, total));
  }
}

std::vector<std::size_t> spectrum_peaks(const Spectrum& sp, std::size_t count) {
  std::vector<std::size_t> peaks;
  for (std::size_t k = 1; k + 1 < sp.psd.size(); ++k) {
    if (sp.psd[k] > sp.psd[k - 1] && sp.psd[k] >= sp.psd[k + 1]) peaks.push_back(k);
  }
  // Stable: equal peaks keep the order of frequency (as the sort always did on this data).
  std::stable_sort(peaks.begin(), peaks.end(),
                   [&](std::size_t a, std::size_t b) { return sp.psd[a] > sp.psd[b]; });
  peaks.resize(std::min(count, peaks.size()));
  return peaks;
}

}  // namespace trochomill
