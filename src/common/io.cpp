// The I/O toolkit (io.hpp): atomic output, file reading, CSV, string helpers.
#include "trochomill/io.hpp"

#include <fmt/format.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <atomic>
#include <cerrno>
#include <charconv>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <limits>
#include <random>
#include <sstream>

#include "trochomill/error.hpp"

namespace trochomill {

namespace fs = std::filesystem;

namespace {

// The pending temporary files: a slot is claimed (0 -> 1), its path copied, then published
// (1 -> 2); a signal handler unlinks the published ones. Lock-free atomics only.
constexpr int kPendingSlots = 32;
constexpr std::size_t kPendingPathMax = 4096;
std::atomic<int> g_pending_state[kPendingSlots];
char g_pending_path[kPendingSlots][kPendingPathMax];

}  // namespace

PendingFile::PendingFile(const fs::path& path) {
  const std::string& p = path.native();
  if (p.size() >= kPendingPathMax) return;
  for (int i = 0; i < kPendingSlots; ++i) {
    int free = 0;
    if (g_pending_state[i].compare_exchange_strong(free, 1)) {
      std::memcpy(g_pending_path[i], p.c_str(), p.size() + 1);
      g_pending_state[i].store(2);
      slot_ = i;
      return;
    }
  }
}

PendingFile::~PendingFile() {
  if (slot_ >= 0) g_pending_state[slot_].store(0);
}

void remove_pending_files() noexcept {
  for (int i = 0; i < kPendingSlots; ++i) {
    if (g_pending_state[i].load() == 2) (void)::unlink(g_pending_path[i]);
  }
}

namespace {

// Runs a writer on a temporary file; on failure removes it and names the target in the
// message (the writer names the file it wrote, the temporary one).
void run_writer(const std::function<void(const fs::path&)>& write, const fs::path& tmp,
                const fs::path& path) {
  std::error_code ec;
  try {
    write(tmp);
  } catch (const Error& e) {
    fs::remove(tmp, ec);
    const std::string what = replace_all(e.what(), tmp.string(), path.string());
    if (dynamic_cast<const InputError*>(&e) != nullptr) throw InputError(what);
    throw IoError(what);
  } catch (...) {
    fs::remove(tmp, ec);
    throw;
  }
}

std::string unique_suffix() {
  // A unique name per call: the random suffix avoids clashes between processes and threads.
  std::random_device rd;
  return ".tmp." + std::to_string(rd());
}

}  // namespace

void write_file_atomic(const fs::path& path, const std::function<void(const fs::path&)>& write) {
  std::error_code ec;
  // A link stays a link: its target is written (a dangling link: the file it names).
  fs::path target = path;
  if (fs::is_symlink(fs::symlink_status(path, ec))) {
    target = fs::weakly_canonical(path, ec);
    if (ec) throw IoError("cannot write '" + path.string() + "': " + ec.message());
  }
  const fs::file_status st = fs::status(target, ec);
  if (fs::is_directory(st)) {
    throw IoError("cannot write '" + path.string() + "': it is a directory");
  }
  if (fs::exists(st) && !fs::is_regular_file(st)) {
    // A FIFO or a device cannot be replaced: the output is made in the temporary directory
    // and written through to it.
    const fs::path tmp = fs::temp_directory_path() / ("trochomill" + unique_suffix());
    const PendingFile pending(tmp);
    run_writer(write, tmp, path);
    {
      std::ifstream in(tmp, std::ios::binary);
      std::ofstream out(target, std::ios::binary);
      if (!in || !out) {
        fs::remove(tmp, ec);
        throw IoError("cannot write '" + path.string() + "': " + std::strerror(errno));
      }
      out << in.rdbuf();
      out.flush();
      if (!out) {
        fs::remove(tmp, ec);
        throw IoError("cannot write '" + path.string() + "': " + std::strerror(errno));
      }
    }
    fs::remove(tmp, ec);
    return;
  }
  const fs::path dir = target.has_parent_path() ? target.parent_path() : fs::path(".");
  if (!fs::is_directory(dir, ec)) {
    throw IoError("cannot write '" + path.string() + "': directory '" + dir.string() +
                  "' does not exist");
  }
  const fs::path tmp = target.string() + unique_suffix();
  const PendingFile pending(tmp);
  run_writer(write, tmp, path);
  fs::rename(tmp, target, ec);
  if (ec) {
    std::error_code ignored;
    fs::remove(tmp, ignored);
    throw IoError("cannot write '" + path.string() + "': " + ec.message());
  }
}

void write_text_atomic(
    const fs::path& path,
    const std::function<void(const std::function<void(std::string_view)>&)>& produce) {
  write_file_atomic(path, [&](const fs::path& tmp) {
    std::ofstream out(tmp, std::ios::binary | std::ios::trunc);
    if (!out) throw IoError("cannot write '" + path.string() + "': " + std::strerror(errno));
    produce([&](std::string_view piece) {
      out.write(piece.data(), static_cast<std::streamsize>(piece.size()));
      if (!out) throw IoError("cannot write '" + path.string() + "': " + std::strerror(errno));
    });
    out.flush();
    if (!out) throw IoError("cannot write '" + path.string() + "': " + std::strerror(errno));
  });
}

void write_file_atomic(const fs::path& path, std::string_view content) {
  write_text_atomic(path,
                    [&](const std::function<void(std::string_view)>& sink) { sink(content); });
}

std::string read_file(const fs::path& path) {
  std::error_code ec;
  if (fs::is_directory(path, ec)) {
    throw IoError("cannot read '" + path.string() + "': it is a directory");
  }
  std::ifstream in(path, std::ios::binary);
  if (!in) {
    throw IoError("cannot read '" + path.string() + "': " + std::strerror(errno));
  }
  // A regular file is read straight into a string of its size (one copy in memory: a 100 MB
  // program takes 100 MB, not the 2-3 times a growing stream buffer and its copy take).
  const auto size = fs::is_regular_file(path, ec) ? fs::file_size(path, ec) : std::uintmax_t{0};
  if (!ec && size > 0) {
    std::string text(static_cast<std::size_t>(size), '\0');
    in.read(text.data(), static_cast<std::streamsize>(size));
    text.resize(static_cast<std::size_t>(in.gcount()));
    if (in.bad()) throw IoError("cannot read '" + path.string() + "': read failed");
    // A file that grew while read: the rest follows.
    if (in.peek() != std::char_traits<char>::eof()) {
      std::ostringstream rest;
      rest << in.rdbuf();
      text += rest.str();
    }
    return text;
  }
  std::ostringstream ss;
  ss << in.rdbuf();
  if (in.bad()) throw IoError("cannot read '" + path.string() + "': read failed");
  return ss.str();
}

std::string read_text_file(const fs::path& path) {
  try {
    return read_file(path);
  } catch (const IoError& e) {
    throw InputError(e.what());
  }
}

void append_fixed(std::string& out, double v, int decimals) {
  if (decimals < 0 || decimals > 9 || !std::isfinite(v) || !(std::abs(v) < 1e9)) {
    out += fmt::format("{:.{}f}", v, decimals);
    return;
  }
  static constexpr std::array<std::uint64_t, 10> kPow10{
      1, 10, 100, 1000, 10000, 100000, 1000000, 10000000, 100000000, 1000000000};
  const std::uint64_t scale = kPow10[static_cast<std::size_t>(decimals)];
  // |v| = m 2^e exactly, m < 2^53; |v| scale = m scale 2^e (< 2^83 before the shift).
  int exp = 0;
  const double frac = std::frexp(std::abs(v), &exp);
  const auto m = static_cast<std::uint64_t>(std::ldexp(frac, 53));
  const int e = exp - 53;
  __extension__ typedef unsigned __int128 U;
  U q = 0;
  if (m != 0) {
    const U num = static_cast<U>(m) * scale;
    if (e >= 0) {
      q = num << e;  // |v| < 1e9: e <= -23 in practice; kept exact for any e that fits
    } else if (-e < 127) {
      const int sh = -e;
      q = num >> sh;
      const U rem = num - (q << sh), half = static_cast<U>(1) << (sh - 1);
      if (rem > half || (rem == half && (q & 1) != 0)) ++q;  // ties to even
    }
  }
  if (std::signbit(v)) out += '-';
  const auto q64 = static_cast<std::uint64_t>(q);  // |v| scale < 1e18 + 1: 64 bits hold it
  const std::uint64_t whole = q64 / scale, part = q64 % scale;
  char buf[32];
  out.append(buf, std::to_chars(buf, buf + sizeof buf, whole).ptr);
  if (decimals == 0) return;
  out += '.';
  char digits[10];
  std::uint64_t p = part;
  for (int k = decimals - 1; k >= 0; --k) {
    digits[k] = static_cast<char>('0' + p % 10);
    p /= 10;
  }
  out.append(digits, static_cast<std::size_t>(decimals));
}

std::string memory_text(double bytes) {
  if (bytes >= 0.995e7) return fmt::format("{:.2f} GB", bytes / 1e9);
  if (bytes >= 0.995e4) return fmt::format("{:.2f} MB", bytes / 1e6);
  return fmt::format("{:.2f} kB", bytes / 1e3);
}

std::string trim(std::string_view s, std::string_view chars) {
  const auto b = s.find_first_not_of(chars);
  if (b == std::string_view::npos) return {};
  const auto e = s.find_last_not_of(chars);
  return std::string(s.substr(b, e - b + 1));
}

std::string replace_all(std::string s, std::string_view from, std::string_view to) {
  if (from.empty()) return s;
  for (std::size_t p = 0; (p = s.find(from, p)) != std::string::npos; p += to.size()) {
    s.replace(p, from.size(), to);
  }
  return s;
}

namespace {
std::size_t edit_distance(std::string_view a, std::string_view b) {
  std::vector<std::size_t> prev(b.size() + 1), cur(b.size() + 1);
  for (std::size_t j = 0; j <= b.size(); ++j) prev[j] = j;
  for (std::size_t i = 1; i <= a.size(); ++i) {
    cur[0] = i;
    for (std::size_t j = 1; j <= b.size(); ++j) {
      const std::size_t sub = prev[j - 1] + (a[i - 1] == b[j - 1] ? 0 : 1);
      cur[j] = std::min({prev[j] + 1, cur[j - 1] + 1, sub});
    }
    std::swap(prev, cur);
  }
  return prev[b.size()];
}
}  // namespace

std::string did_you_mean(std::string_view word, const std::vector<std::string>& candidates) {
  std::string best;
  std::size_t best_d = std::numeric_limits<std::size_t>::max();
  const std::size_t limit = std::max<std::size_t>(2, word.size() / 3);
  for (const auto& c : candidates) {
    // The distance is at least the difference in length: a candidate that far off cannot be
    // suggested, so the quadratic distance is not computed (long garbage keys stay cheap).
    const std::size_t gap =
        word.size() > c.size() ? word.size() - c.size() : c.size() - word.size();
    if (gap > limit) continue;
    const std::size_t d = edit_distance(word, c);
    if (d < best_d) {
      best_d = d;
      best = c;
    }
  }
  if (best_d <= limit) return fmt::format("; did you mean '{}'?", best);
  std::string all;
  for (const auto& c : candidates) all += (all.empty() ? "" : ", ") + c;
  return fmt::format(" (known: {})", all);
}

std::vector<std::string> split_trimmed(std::string_view s, char sep) {
  std::vector<std::string> out;
  std::size_t start = 0;
  for (;;) {
    const auto p = s.find(sep, start);
    out.push_back(trim(s.substr(start, p == std::string_view::npos ? s.npos : p - start)));
    if (p == std::string_view::npos) return out;
    start = p + 1;
  }
}

namespace {

std::vector<std::string> fields_of(std::string_view line, bool detect) {
  char sep = ',';
  if (detect) {
    sep = line.find(',') != std::string_view::npos   ? ','
          : line.find(';') != std::string_view::npos ? ';'
                                                     : '\t';
  }
  std::vector<std::string> out;
  std::size_t start = 0;
  for (;;) {
    const auto p = line.find(sep, start);
    const std::string_view f =
        line.substr(start, p == std::string_view::npos ? line.npos : p - start);
    out.push_back(trim(f, detect ? " \t\r\"" : " \t\r"));
    if (p == std::string_view::npos) return out;
    start = p + 1;
  }
}

bool parse_number(const std::string& f, double& v) {
  char* end = nullptr;
  v = std::strtod(f.c_str(), &end);
  return !f.empty() && *end == '\0';
}

}  // namespace

CsvTable parse_csv(std::string_view text, std::string_view source, const CsvOptions& o) {
  // A binary file is said to be one, not echoed back: a control byte other than tab, CR and
  // LF names its line and column.
  {
    std::size_t line = 1, column = 1;
    for (const char ch : text) {
      const auto c = static_cast<unsigned char>(ch);
      if (c == '\n') {
        ++line;
        column = 1;
        continue;
      }
      if ((c < 0x20 && c != '\t' && c != '\r') || c == 0x7f) {
        throw InputError(fmt::format(
            "{}:{}:{}: byte 0x{:02x} is not text: a CSV table is text (numbers separated by "
            "commas, semicolons or tabs)",
            source, line, column, c));
      }
      ++column;
    }
  }
  CsvTable t;
  std::vector<std::size_t> index;  // selected field of each output column
  bool first = true;
  std::size_t width = 0, ln = 0, start = 0;
  while (start < text.size()) {
    auto nl = text.find('\n', start);
    if (nl == std::string_view::npos) nl = text.size();
    std::string_view line = text.substr(start, nl - start);
    start = nl + 1;
    ++ln;
    if (!line.empty() && line.back() == '\r') line.remove_suffix(1);
    if (line.find_first_not_of(" \t") == std::string_view::npos || line[0] == '#') continue;
    const std::vector<std::string> f = fields_of(line, o.detect_separator);
    if (first) {
      first = false;
      width = f.size();
      double v = 0;
      if (!o.columns.empty() || !parse_number(f.empty() ? std::string() : f[0], v)) {
        t.header = f;
        for (const auto& w : o.columns) {
          const auto it = std::find(t.header.begin(), t.header.end(), w);
          if (it == t.header.end()) {
            std::string have;
            for (const auto& h : t.header) have += (have.empty() ? "" : ", ") + h;
            throw InputError(
                fmt::format("{}:{}: no column '{}' (the header has: {})", source, ln, w, have));
          }
          index.push_back(static_cast<std::size_t>(it - t.header.begin()));
        }
        continue;
      }
    }
    if (o.columns.empty()) {
      if (o.same_width && f.size() != width) {
        throw InputError(
            fmt::format("{}:{}: {} columns, the first row has {}", source, ln, f.size(), width));
      }
      index.resize(f.size());
      for (std::size_t k = 0; k < f.size(); ++k) index[k] = k;
    }
    std::vector<double> row;
    row.reserve(index.size());
    for (std::size_t k = 0; k < index.size(); ++k) {
      const std::size_t c = index[k];
      if (c >= f.size()) {
        throw InputError(fmt::format("{}:{}: {} fields, column '{}' is field {}", source, ln,
                                     f.size(), o.columns[k], c + 1));
      }
      double v = 0;
      if (!parse_number(f[c], v) || !std::isfinite(v)) {
        throw InputError(
            o.columns.empty()
                ? fmt::format("{}:{}:{}: '{}' is not a finite number", source, ln, c + 1, f[c])
                : fmt::format("{}:{}:{}: '{}' in column '{}' is not a number", source, ln, c + 1,
                              f[c], o.columns[k]));
      }
      row.push_back(v);
    }
    t.rows.push_back(std::move(row));
    t.line_of_row.push_back(ln);
  }
  if (!o.columns.empty() && t.header.empty()) {
    throw InputError(fmt::format("{}: empty file (no header line)", source));
  }
  return t;
}

std::size_t peak_memory_bytes() {
  std::ifstream in("/proc/self/status");
  for (std::string line; std::getline(in, line);) {
    if (line.rfind("VmHWM:", 0) == 0) {
      return static_cast<std::size_t>(std::strtoull(line.c_str() + 6, nullptr, 10)) * 1024;
    }
  }
  return 0;
}

double default_memory_limit_bytes() {
  return 0.75 * static_cast<double>(sysconf(_SC_PHYS_PAGES)) *
         static_cast<double>(sysconf(_SC_PAGE_SIZE));
}

double process_base_bytes() {
  std::ifstream in("/proc/self/status");
  for (std::string line; std::getline(in, line);) {
    if (line.rfind("VmRSS:", 0) == 0) {
      const double rss = static_cast<double>(std::strtoull(line.c_str() + 6, nullptr, 10)) * 1024;
      return std::max(20e6, rss);
    }
  }
  return 20e6;
}

}  // namespace trochomill
