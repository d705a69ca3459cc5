// The plugin libtrochomill_sndfile.so (sndfile_plugin.hpp): sound files through libsndfile.
#include "sndfile_plugin.hpp"

#include <fmt/format.h>
#include <sndfile.h>

#include <cerrno>
#include <cmath>
#include <cstring>
#include <string>
#include <vector>

#include "trochomill/error.hpp"

namespace trochomill::signal_detail {
namespace {

Signal read_sndfile(const std::string& path, const SignalReadOptions& o) {
  SF_INFO info{};
  SNDFILE* f = sf_open(path.c_str(), SFM_READ, &info);
  if (f == nullptr) {
    throw InputError(
        fmt::format("{}: cannot read as a sound file: {}", path, sf_strerror(nullptr)));
  }
  struct Closer {
    SNDFILE* f;
    ~Closer() { sf_close(f); }
  } closer{f};
  if (info.channels < 1 || info.frames <= 0) throw InputError(fmt::format("{}: no samples", path));
  if (o.channel < 0 || o.channel >= info.channels) {
    throw InputError(
        fmt::format("{}: channel {} does not exist (0..{})", path, o.channel, info.channels - 1));
  }
  if (o.rate_hz && std::abs(*o.rate_hz - info.samplerate) > 1e-9) {
    throw InputError(fmt::format("{}: {} {} Hz contradicts the file's {} Hz", path,
                                 option_name("rate_hz"), *o.rate_hz, info.samplerate));
  }
  const auto ch = static_cast<std::size_t>(info.channels);
  std::vector<double> buf(static_cast<std::size_t>(info.frames) * ch);
  const sf_count_t got = sf_readf_double(f, buf.data(), info.frames);
  if (got != info.frames) {
    throw InputError(
        fmt::format("{}: truncated: {} of {} frames readable", path, got, info.frames));
  }
  Signal s;
  s.rate_hz = info.samplerate;
  s.samples.resize(static_cast<std::size_t>(got));
  for (std::size_t i = 0; i < s.samples.size(); ++i) {
    s.samples[i] = buf[i * ch + static_cast<std::size_t>(o.channel)];
  }
  return s;
}

void write_wav(const std::string& path, const Signal& s) {
  SF_INFO info{};
  info.samplerate = static_cast<int>(std::lround(s.rate_hz));
  info.channels = 1;
  info.format = SF_FORMAT_WAV | SF_FORMAT_FLOAT;
  if (std::abs(info.samplerate - s.rate_hz) > 1e-9) {
    throw InputError(fmt::format("WAV needs a whole-number rate, got {} Hz", s.rate_hz));
  }
  SNDFILE* f = sf_open(path.c_str(), SFM_WRITE, &info);
  if (f == nullptr) {
    throw IoError(fmt::format("cannot write '{}': {}", path, sf_strerror(nullptr)));
  }
  // No PEAK chunk: it carries the writing time, and the same signal must give the same bytes.
  sf_command(f, SFC_SET_ADD_PEAK_CHUNK, nullptr, SF_FALSE);
  const sf_count_t n = static_cast<sf_count_t>(s.samples.size());
  errno = 0;
  const sf_count_t put = sf_writef_double(f, s.samples.data(), n);
  const int err = errno;
  const std::string why = put != n ? sf_strerror(f) : std::string();
  const int rc = sf_close(f);
  if (put != n || rc != 0) {
    throw IoError(
        fmt::format("cannot write '{}': {}", path,
                    err != 0 ? std::strerror(err) : (why.empty() ? "write failed" : why)));
  }
}

const SndfileTable kTable{&read_sndfile, &write_wav};

}  // namespace
}  // namespace trochomill::signal_detail

extern "C" __attribute__((visibility("default"))) const trochomill::signal_detail::SndfileTable*
trochomill_sndfile_table() {
  return &trochomill::signal_detail::kTable;
}
