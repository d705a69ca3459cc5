// The signal readers: the first byte chooses the reader (WAV or FLAC through libsndfile, CSV
// with and without a given rate, raw float32 / int16); the rest is the file. Every input is a
// signal of finite samples or an InputError.
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstdlib>

#include "fuzz_common.hpp"
#include "trochomill/error.hpp"
#include "trochomill/signal.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace trochomill;
  if (size < 1) return 0;
  const unsigned mode = data[0] % 6;
  static const char* const kExt[] = {".wav", ".flac", ".csv", ".csv", ".f32", ".s16"};
  const auto file = fuzz::scratch_file(kExt[mode]);
  fuzz::write_bytes(file, data + 1, size - 1);
  SignalReadOptions opt;
  if (mode == 3 || mode >= 4) opt.rate_hz = 1000.0;
  if (mode == 4) opt.format = SampleFormat::f32;
  if (mode == 5) opt.format = SampleFormat::s16;
  opt.channel = (data[0] / 6) % 3;
  try {
    const Signal s = read_signal(file.string(), opt);
    for (double v : s.samples) {
      if (!std::isfinite(v)) std::abort();  // the reader promises finite samples
    }
  } catch (const InputError&) {
  }
  return 0;
}
