// Reading and writing signals: libsndfile (WAV, FLAC, AIFF, OGG; in the plugin
// sndfile_plugin.hpp describes), CSV, raw float32 / int16
// little-endian (include/trochomill/signal.hpp).
#include "trochomill/io.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <bit>
#include <cerrno>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <fstream>
#include <iostream>
#include <iterator>
#include <sstream>

#include "sndfile_plugin.hpp"
#include "trochomill/common/plugin.hpp"
#include "trochomill/error.hpp"
#include "trochomill/signal.hpp"

namespace trochomill {

SampleFormat parse_sample_format(const std::string& name) {
  if (name == "auto") return SampleFormat::automatic;
  if (name == "sndfile" || name == "wav" || name == "flac" || name == "aiff") {
    return SampleFormat::sndfile;
  }
  if (name == "csv") return SampleFormat::csv;
  if (name == "f32") return SampleFormat::f32;
  if (name == "s16") return SampleFormat::s16;
  throw InputError(fmt::format(
      "unknown sample format '{}': allowed: auto, wav (any libsndfile format), csv, f32, s16",
      name));
}

namespace {

std::string lower_ext(const std::string& path) {
  const auto dot = path.rfind('.');
  if (dot == std::string::npos) return "";
  std::string e = path.substr(dot + 1);
  std::transform(e.begin(), e.end(), e.begin(), [](unsigned char c) { return std::tolower(c); });
  return e;
}

void check_finite(const std::string& path, const std::vector<double>& v) {
  for (std::size_t i = 0; i < v.size(); ++i) {
    if (!std::isfinite(v[i])) {
      throw InputError(fmt::format("{}: sample {} is not finite ({})", path, i, v[i]));
    }
  }
}

// A file's bytes, or stdin's for "-".
std::string read_all(const std::string& path) {
  if (path == "-") {
    return {std::istreambuf_iterator<char>(std::cin), std::istreambuf_iterator<char>()};
  }
  return read_text_file(path);
}

Signal read_raw(const std::string& path, const SignalReadOptions& o, bool f32) {
  if (!o.rate_hz) {
    throw InputError(
        fmt::format("{}: raw samples carry no rate: give {} (Hz)", path, option_name("rate_hz")));
  }
  const std::string bytes = read_all(path);
  const std::size_t w = f32 ? 4 : 2;
  if (bytes.empty()) throw InputError(fmt::format("{}: no samples", path));
  if (bytes.size() % w != 0) {
    throw InputError(
        fmt::format("{}: {} bytes is not a whole number of {}-byte samples "
                    "(truncated?)",
                    path, bytes.size(), w));
  }
  Signal s;
  s.rate_hz = *o.rate_hz;
  const std::size_t n = bytes.size() / w;
  s.samples.resize(n);
  decode_raw(reinterpret_cast<const unsigned char*>(bytes.data()), n,
             f32 ? SampleFormat::f32 : SampleFormat::s16, s.samples.data());
  check_finite(path, s.samples);
  return s;
}

Signal read_csv(const std::string& path, const SignalReadOptions& o) {
  const CsvTable table = parse_csv(read_all(path), path);
  int time_col = -1;
  for (std::size_t k = 0; k < table.header.size(); ++k) {
    const std::string& c = table.header[k];
    if (c == "t" || c == "t_s" || c == "time") time_col = static_cast<int>(k);
  }
  std::vector<double> t, v;
  for (std::size_t i = 0; i < table.rows.size(); ++i) {
    const std::vector<double>& row = table.rows[i];
    // Data columns: all but the time column, counted from 0.
    int data_k = -1;
    double value = 0;
    bool found = false;
    for (std::size_t k = 0; k < row.size(); ++k) {
      if (static_cast<int>(k) == time_col) continue;
      if (++data_k == o.channel) {
        value = row[k];
        found = true;
      }
    }
    if (!found) {
      throw InputError(
          fmt::format("{}:{}: no data column {} (0-based, the time column not "
                      "counted)",
                      path, table.line_of_row[i], o.channel));
    }
    if (time_col >= 0) t.push_back(row[static_cast<std::size_t>(time_col)]);
    v.push_back(value);
  }
  if (v.empty()) throw InputError(fmt::format("{}: no samples", path));
  Signal s;
  if (time_col >= 0) {
    if (v.size() < 2) throw InputError(fmt::format("{}: need two samples to know the rate", path));
    const double dt = (t.back() - t.front()) / static_cast<double>(t.size() - 1);
    if (!(dt > 0)) throw InputError(fmt::format("{}: time does not increase", path));
    for (std::size_t i = 1; i < t.size(); ++i) {
      if (std::abs(t[i] - t[i - 1] - dt) > 1e-6 * dt + 1e-9 * std::abs(t[i])) {
        throw InputError(fmt::format(
            "{}: sample {} is {} s after the previous one, the mean step is {} s: the rate "
            "must be constant",
            path, i, t[i] - t[i - 1], dt));
      }
    }
    s.rate_hz = 1.0 / dt;
    if (o.rate_hz && std::abs(*o.rate_hz - s.rate_hz) > 1e-6 * s.rate_hz) {
      throw InputError(fmt::format("{}: {} {} Hz contradicts the time column ({} Hz)", path,
                                   option_name("rate_hz"), *o.rate_hz, s.rate_hz));
    }
  } else {
    if (!o.rate_hz) {
      throw InputError(fmt::format("{}: no time column (t, t_s or time): give {} (Hz)", path,
                                   option_name("rate_hz")));
    }
    s.rate_hz = *o.rate_hz;
  }
  s.samples = std::move(v);
  return s;
}

const signal_detail::SndfileTable& sndfile() {
  return plugin_table<signal_detail::SndfileTable>("sndfile", signal_detail::kSndfileSymbol,
                                                   "reading or writing a sound file (libsndfile)");
}

Signal read_sndfile(const std::string& path, const SignalReadOptions& o) {
  Signal s = sndfile().read(path, o);
  check_finite(path, s.samples);
  return s;
}

}  // namespace

void decode_raw(const unsigned char* bytes, std::size_t count, SampleFormat f, double* out) {
  if (f == SampleFormat::f32) {
    for (std::size_t i = 0; i < count; ++i) {
      const unsigned char* p = bytes + 4 * i;
      const std::uint32_t u = std::uint32_t{p[0]} | (std::uint32_t{p[1]} << 8) |
                              (std::uint32_t{p[2]} << 16) | (std::uint32_t{p[3]} << 24);
      out[i] = std::bit_cast<float>(u);
    }
  } else if (f == SampleFormat::s16) {
    for (std::size_t i = 0; i < count; ++i) {
      const unsigned char* p = bytes + 2 * i;
      out[i] = static_cast<std::int16_t>(static_cast<std::uint16_t>(p[0] | (p[1] << 8))) / 32768.0;
    }
  } else {
    throw Error("decode_raw: only f32 and s16 are raw formats");
  }
}

Signal read_signal(const std::string& path, const SignalReadOptions& o) {
  if (o.rate_hz && !(*o.rate_hz > 0)) {
    throw InputError(fmt::format("{} must be > 0 Hz, got {}", option_name("rate_hz"), *o.rate_hz));
  }
  SampleFormat f = o.format;
  if (f == SampleFormat::automatic) {
    const std::string e = lower_ext(path);
    if (e == "csv" || e == "txt") {
      f = SampleFormat::csv;
    } else if (e == "f32" || e == "raw") {
      f = SampleFormat::f32;
    } else if (e == "s16" || e == "pcm") {
      f = SampleFormat::s16;
    } else if (path == "-") {
      throw InputError("standard input: give " + option_name("format") + " f32, s16 or csv");
    } else {
      f = SampleFormat::sndfile;
    }
  }
  switch (f) {
    case SampleFormat::csv:
      return read_csv(path, o);
    case SampleFormat::f32:
      return read_raw(path, o, true);
    case SampleFormat::s16:
      return read_raw(path, o, false);
    case SampleFormat::sndfile:
    case SampleFormat::automatic:
      if (path == "-") throw InputError("standard input: sound files must be read from a file");
      return read_sndfile(path, o);
  }
  return {};
}

void write_wav(const std::string& path, const Signal& s) { sndfile().write_wav(path, s); }

}  // namespace trochomill
