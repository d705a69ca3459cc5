// RS274 subset reader: G0/G1/G2/G3 (I/J/K and R forms, P turns), G17/G18/G19, G20/G21
// (and Sinumerik G70/G71/G700/G710), G90/G91, G90.1/G91.1, F, S, M3/M4/M5, T/M6 tolerated,
// line numbers, ( ) and ; comments, modal state. Every error is
// "name:line:column: what is wrong". The parser walks the text once without allocating per
// line; numbers go through std::from_chars.
#include <fmt/format.h>

#include <algorithm>
#include <array>
#include <charconv>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <map>
#include <optional>

#include "trochomill/error.hpp"
#include "trochomill/gcode.hpp"
#include "trochomill/io.hpp"
#include "trochomill/units.hpp"

namespace trochomill {
namespace {

enum class Plane { xy, zx, yz };

struct Word {
  char letter;
  double value;
  std::size_t column;  // 1-based
};

struct State {
  int motion = -1;  // 0, 1, 2, 3 once set
  Plane plane = Plane::xy;
  double unit = 1.0;  // mm per program unit
  bool absolute = true;
  bool arc_absolute = false;  // G90.1
  double feed = 0;            // mm/min
  bool feed_given = false;    // an F word was read (F0 is then a given zero feed)
  Vec3 pos = Vec3::Zero();
  bool pos_known = false;  // X or Y programmed: the path has started
  bool ended = false;
};

class Reader {
 public:
  Reader(std::string_view text, std::string_view name, const GcodeReadOptions& opt)
      : text_(text), name_(name), opt_(opt) {}

  GcodeProgram run() {
    std::size_t start = 0;
    // A final newline ends the last line; it does not start another (wc -l counts the same).
    while (start < text_.size() && !st_.ended) {
      std::size_t end = text_.find('\n', start);
      if (end == std::string_view::npos) end = text_.size();
      ++line_no_;
      std::string_view line = text_.substr(start, end - start);
      if (!line.empty() && line.back() == '\r') line.remove_suffix(1);
      parse_line(line);
      if (end == text_.size()) break;
      start = end + 1;
    }
    prog_.info.lines = line_no_;
    if (prog_.path.empty()) {
      throw InputError(fmt::format("{}: the program has no motion (no G0/G1/G2/G3 moves)", name_));
    }
    return std::move(prog_);
  }

 private:
  // A character as a message shows it: printable ones quoted, others as a code (no raw bytes
  // from a binary file on the terminal).
  static std::string shown(char c) {
    const auto u = static_cast<unsigned char>(c);
    if (u >= 0x20 && u < 0x7f) return fmt::format("'{}'", c);
    return fmt::format("byte 0x{:02x}", u);
  }

  [[noreturn]] void fail(std::size_t column, const std::string& what) const {
    throw InputError(fmt::format("{}:{}:{}: {}", name_, line_no_, column, what));
  }

  void parse_line(std::string_view line) {
    words_.clear();
    std::size_t i = 0;
    const std::size_t n = line.size();
    auto skip_space = [&] {
      while (i < n && (line[i] == ' ' || line[i] == '\t')) ++i;
    };
    skip_space();
    if (i < n && line[i] == '%') return;  // tape markers
    if (i < n && line[i] == '/') ++i;     // block delete: the block runs (switch off)
    skip_space();
    if (i < n && (line[i] == 'O' || line[i] == 'o' || line[i] == ':') && words_.empty()) {
      // Program number "O1234" (Fanuc) or ":1234": skip the digits, keep the rest.
      std::size_t j = i + 1;
      while (j < n && std::isdigit(static_cast<unsigned char>(line[j]))) ++j;
      if (j > i + 1) i = j;
    }
    while (i < n) {
      const char c = line[i];
      if (c == ' ' || c == '\t') {
        ++i;
        continue;
      }
      if (c == ';') break;
      if (c == '(') {
        const std::size_t close = line.find(')', i);
        if (close == std::string_view::npos) fail(i + 1, "comment '(' is not closed on this line");
        const std::size_t nested = line.find('(', i + 1);
        if (nested != std::string_view::npos && nested < close) {
          fail(nested + 1, "nested '(' inside a comment");
        }
        i = close + 1;
        continue;
      }
      if (!std::isalpha(static_cast<unsigned char>(c))) {
        fail(i + 1,
             fmt::format("unexpected character {} (expected a word such as G1 or X10)", shown(c)));
      }
      const char letter = static_cast<char>(std::toupper(static_cast<unsigned char>(c)));
      const std::size_t col = i + 1;
      ++i;
      // Sinumerik radius form "CR=5.0".
      if (letter == 'C' && i < n && (line[i] == 'R' || line[i] == 'r')) {
        std::size_t j = i + 1;
        while (j < n && line[j] == ' ') ++j;
        if (j < n && line[j] == '=') {
          i = j + 1;
          skip_space();
          words_.push_back(Word{'r', read_number(line, i, col, "CR="), col});
          continue;
        }
      }
      skip_space();
      words_.push_back(Word{letter, read_number(line, i, col, std::string(1, letter)), col});
    }
    if (!words_.empty()) execute();
  }

  double read_number(std::string_view line, std::size_t& i, std::size_t col,
                     const std::string& word) const {
    std::size_t j = i;
    bool neg = false;
    if (j < line.size() && (line[j] == '+' || line[j] == '-')) {
      neg = line[j] == '-';
      ++j;
    }
    const char* b = line.data() + j;
    const char* e = line.data() + line.size();
    double v = 0;
    // The sign is handled above: from_chars does not accept a leading '+'.
    auto [ptr, ec] = std::from_chars(b, e, v, std::chars_format::fixed);
    if (ec == std::errc::result_out_of_range) {
      fail(col, fmt::format("'{}' has a number too large to represent", word));
    }
    if (ec != std::errc() || ptr == b) {
      fail(col, fmt::format("'{}' needs a number after it", word));
    }
    i = static_cast<std::size_t>(ptr - line.data());
    if (i < line.size() && (std::isalpha(static_cast<unsigned char>(line[i])) == 0) &&
        line[i] != ' ' && line[i] != '\t' && line[i] != '(' && line[i] != ';') {
      fail(i + 1,
           fmt::format("unexpected character {} after the number of '{}'", shown(line[i]), word));
    }
    if (!std::isfinite(v)) fail(col, fmt::format("'{}' has a non-finite number", word));
    return neg ? -v : v;
  }

  // Codes are compared in tenths: G90.1 -> 901.
  static int code10(double v) { return static_cast<int>(std::lround(v * 10.0)); }

  void execute() {
    std::optional<double> x, y, z, ii, jj, kk, r, p;
    std::size_t motion_col = 0, axis_col = 0;
    int new_motion = -1;
    for (const Word& w : words_) {
      // Geometry beyond 1e6 mm (1 km; a job's lengths stop at 1e5 mm) is refused: an arc's
      // radius or centre that far makes its length and sampling overflow.
      if (std::strchr("XYZIJKRr", w.letter) != nullptr && std::abs(w.value) * st_.unit > 1e6) {
        fail(w.column, fmt::format("{}{:g} is beyond +-1e6 mm, what trochomill represents",
                                   w.letter, w.value));
      }
      switch (w.letter) {
        case 'G': {
          const int g = code10(w.value);
          switch (g) {
            case 0:
            case 10:
            case 20:
            case 30:
              if (new_motion >= 0) fail(w.column, "two motion codes in one block");
              new_motion = g / 10;
              motion_col = w.column;
              break;
            case 170:
              st_.plane = Plane::xy;
              break;
            case 180:
              st_.plane = Plane::zx;
              break;
            case 190:
              st_.plane = Plane::yz;
              break;
            case 200:
            case 700:
            case 7000:
              st_.unit = 25.4;
              prog_.info.inch_units_seen = true;
              break;
            case 210:
            case 710:
            case 7100:
              st_.unit = 1.0;
              break;
            case 900:
              st_.absolute = true;
              break;
            case 910:
              st_.absolute = false;
              break;
            case 901:
              st_.arc_absolute = true;
              break;
            case 911:
              st_.arc_absolute = false;
              break;
            case 40:
              break;  // dwell: no motion (its time is not modelled)
            case 400:
            case 490:
            case 800:
            case 940:
            case 610:
            case 611:
            case 640:
            case 430:
            case 540:
            case 550:
            case 560:
            case 570:
            case 580:
            case 590:
              break;  // modal settings with no effect on the path
            case 410:
            case 420:
              fail(w.column,
                   "cutter radius compensation (G41/G42) is not supported: the "
                   "programmed path would not be the tool-centre path");
            case 280:
            case 300:
            case 530:
              fail(w.column, fmt::format("G{:g} is not supported: the path would depend on the "
                                         "machine's home or machine coordinates",
                                         w.value));
            case 930:
              fail(w.column, "inverse-time feed (G93) is not supported; use G94 (mm/min)");
            case 950:
              fail(w.column, "feed per revolution (G95) is not supported; use G94 (mm/min)");
            default:
              if (g >= 730 && g <= 890) {
                fail(w.column, fmt::format("canned cycle G{:g} is not supported", w.value));
              }
              fail(w.column, fmt::format("unsupported G-code G{:g}", w.value));
          }
          break;
        }
        case 'M': {
          const int m = code10(w.value);
          switch (m) {
            case 0:
            case 10:
            case 20:
            case 300:
              end_after_block_ = m == 20 || m == 300;
              break;
            case 30:
            case 40:
            case 50:
            case 60:
            case 70:
            case 80:
            case 90:
              break;
            default:
              fail(w.column, fmt::format("unsupported M-code M{:g}", w.value));
          }
          break;
        }
        case 'X':
          x = w.value;
          axis_col = axis_col ? axis_col : w.column;
          break;
        case 'Y':
          y = w.value;
          axis_col = axis_col ? axis_col : w.column;
          break;
        case 'Z':
          z = w.value;
          axis_col = axis_col ? axis_col : w.column;
          break;
        case 'I':
          ii = w.value;
          break;
        case 'J':
          jj = w.value;
          break;
        case 'K':
          kk = w.value;
          break;
        case 'R':
        case 'r':
          r = w.value;
          break;
        case 'P':
          p = w.value;
          break;
        case 'F':
          if (w.value < 0) fail(w.column, "feed F must be >= 0");
          st_.feed = w.value * st_.unit;
          st_.feed_given = true;
          break;
        case 'S':
          if (w.value < 0) fail(w.column, "spindle speed S must be >= 0");
          prog_.info.max_spindle_rpm = std::max(prog_.info.max_spindle_rpm, w.value);
          break;
        case 'N':
        case 'T':
        case 'D':
        case 'H':
          break;
        case 'A':
        case 'B':
        case 'C':
          fail(w.column,
               fmt::format("rotary axis {} is not supported (3-axis programs only)", w.letter));
        default:
          fail(w.column, fmt::format("unsupported word '{}'", w.letter));
      }
    }
    if (new_motion >= 0) st_.motion = new_motion;
    const bool has_axis = x || y || z;
    if (has_axis) {
      if (st_.motion < 0) fail(axis_col, "axis words without a motion mode (G0/G1/G2/G3)");
      motion(x, y, z, ii, jj, kk, r, p, new_motion >= 0 ? motion_col : axis_col);
    } else if (new_motion >= 2) {
      fail(motion_col, "arc without an end point");
    }
    if (end_after_block_) st_.ended = true;
  }

  void motion(std::optional<double> x, std::optional<double> y, std::optional<double> z,
              std::optional<double> ii, std::optional<double> jj, std::optional<double> kk,
              std::optional<double> r, std::optional<double> p, std::size_t col) {
    const double u = st_.unit;
    Vec3 target = st_.pos;
    auto apply = [&](int axis, const std::optional<double>& v) {
      if (!v) return;
      target[axis] = st_.absolute ? *v * u : st_.pos[axis] + *v * u;
    };
    apply(0, x);
    apply(1, y);
    apply(2, z);
    if (target.cwiseAbs().maxCoeff() > 1e6) {
      fail(col, fmt::format("the move reaches X{:g} Y{:g} Z{:g} mm, beyond +-1e6 mm (incremental "
                            "moves add up)",
                            target.x(), target.y(), target.z()));
    }
    ++prog_.info.motion_blocks;
    if (!st_.pos_known) {
      // The machine's position before the program is unknown: a Z-only approach to the
      // clearance plane and the first move in X or Y only establish where the path starts.
      st_.pos = target;
      st_.pos_known = x.has_value() || y.has_value();
      return;
    }
    const Vec3 from = st_.pos;
    if (st_.motion <= 1) {
      if (st_.motion == 1) check_feed(col);
      const double speed = st_.motion == 0 ? opt_.rapid_rate_mm_per_min : st_.feed;
      append(Segment::line(from, target, st_.motion == 0 ? Motion::rapid : Motion::feed, speed),
             col);
      st_.pos = target;
      return;
    }
    check_feed(col);
    // Arc in the active plane: e1, e2 span it, n = e1 x e2 is the normal (G17: XY/Z,
    // G18: ZX/Y, G19: YZ/X); positive angles turn from e1 to e2 (G3).
    int i1 = 0, i2 = 1, in = 2;
    std::optional<double> o1 = ii, o2 = jj;
    if (st_.plane == Plane::zx) {
      i1 = 2;
      i2 = 0;
      in = 1;
      o1 = kk;
      o2 = ii;
    }
    if (st_.plane == Plane::yz) {
      i1 = 1;
      i2 = 2;
      in = 0;
      o1 = jj;
      o2 = kk;
    }
    const double s1 = from[i1], s2 = from[i2], t1 = target[i1], t2 = target[i2];
    const bool ccw = st_.motion == 3;
    double c1, c2;
    if (r) {
      const double rr = *r * u;
      const double dx = t1 - s1, dy = t2 - s2, chord = std::hypot(dx, dy);
      if (chord <= 1e-12) fail(col, "an R-form arc cannot be a full circle (end = start)");
      if (std::abs(rr) * 2 < chord - opt_.arc_radius_tolerance_mm) {
        fail(col, fmt::format("arc radius R{:g} is smaller than half the chord ({:.4f} mm)", *r,
                              0.5 * chord / u));
      }
      const double h = std::sqrt(std::max(0.0, rr * rr - 0.25 * chord * chord));
      // Centre to the left of the chord for a ccw arc of <= 180 deg, right for cw; R < 0 flips.
      double side = ccw ? 1.0 : -1.0;
      if (rr < 0) side = -side;
      c1 = 0.5 * (s1 + t1) - side * h * dy / chord;
      c2 = 0.5 * (s2 + t2) + side * h * dx / chord;
    } else {
      if (!o1 && !o2) {
        fail(col, "arc needs its centre (I/J/K for the active plane) or a radius R");
      }
      const double d1 = o1.value_or(0.0) * u, d2 = o2.value_or(0.0) * u;
      c1 = st_.arc_absolute ? d1 : s1 + d1;
      c2 = st_.arc_absolute ? d2 : s2 + d2;
      const double r0 = std::hypot(s1 - c1, s2 - c2), r1 = std::hypot(t1 - c1, t2 - c2);
      if (std::abs(r0 - r1) > opt_.arc_radius_tolerance_mm) {
        fail(col, fmt::format("arc radius to the end ({:.4f} mm) differs from the radius to the "
                              "start ({:.4f} mm) by more than {:g} mm",
                              r1 / u, r0 / u, opt_.arc_radius_tolerance_mm / u));
      }
      // Move the centre onto the chord's bisector so both radii agree exactly.
      const double mx = 0.5 * (s1 + t1), my = 0.5 * (s2 + t2);
      const double dx = t1 - s1, dy = t2 - s2, L2 = dx * dx + dy * dy;
      if (L2 > 0) {
        const double k = ((c1 - mx) * dx + (c2 - my) * dy) / L2;
        c1 -= k * dx;
        c2 -= k * dy;
      }
    }
    const double rad = std::hypot(s1 - c1, s2 - c2);
    if (rad <= 1e-9) fail(col, "arc radius is zero");
    const double a0 = std::atan2(s2 - c2, s1 - c1), a1 = std::atan2(t2 - c2, t1 - c1);
    double sweep;
    const bool full = std::hypot(t1 - s1, t2 - s2) <= 1e-9;
    if (ccw) {
      sweep = full ? kTwoPi : std::fmod(a1 - a0 + 2 * kTwoPi, kTwoPi);
      if (sweep <= 0) sweep += kTwoPi;
    } else {
      sweep = full ? -kTwoPi : -std::fmod(a0 - a1 + 2 * kTwoPi, kTwoPi);
      if (sweep >= 0) sweep -= kTwoPi;
    }
    if (p) {
      if (*p < 1 || std::abs(*p - std::round(*p)) > 1e-9)
        fail(col, "arc turns P must be a whole number >= 1");
      sweep += (ccw ? 1.0 : -1.0) * kTwoPi * (std::round(*p) - 1.0);
    }
    Vec3 e1 = Vec3::Zero(), e2 = Vec3::Zero(), nrm = Vec3::Zero();
    e1[i1] = 1;
    e2[i2] = 1;
    nrm[in] = 1;
    Vec3 c = Vec3::Zero();
    c[i1] = c1;
    c[i2] = c2;
    c[in] = from[in];
    const Vec3 A = rad * (std::cos(a0) * e1 + std::sin(a0) * e2);
    const Vec3 B = rad * (-std::sin(a0) * e1 + std::cos(a0) * e2);
    const Vec3 V = nrm * ((target[in] - from[in]) / sweep);
    Segment seg = Segment::curve(c, A, B, V, 0.0, sweep, Motion::feed, st_.feed);
    // The curve ends at the programmed end to rounding; snap continuity to it.
    st_.pos = seg.end();
    append(std::move(seg), col);
  }

  void check_feed(std::size_t col) {
    if (!(st_.feed > 0)) {
      fail(col, st_.feed_given ? "feed move at F0: program a feed F > 0 (mm/min)"
                               : "feed move with no feed rate: program F before G1/G2/G3");
    }
    if (prog_.info.min_feed_mm_per_min == 0 || st_.feed < prog_.info.min_feed_mm_per_min) {
      prog_.info.min_feed_mm_per_min = st_.feed;
    }
    prog_.info.max_feed_mm_per_min = std::max(prog_.info.max_feed_mm_per_min, st_.feed);
  }

  void append(Segment seg, std::size_t col) {
    try {
      prog_.path.append(std::move(seg));
    } catch (const Error& e) {
      fail(col, e.what());
    }
  }

  std::string_view text_;
  std::string_view name_;
  GcodeReadOptions opt_;
  State st_;
  GcodeProgram prog_;
  std::vector<Word> words_;
  std::size_t line_no_ = 0;
  bool end_after_block_ = false;
};

}  // namespace

std::vector<std::pair<std::string, std::string>> gcode_header_keys(std::string_view text) {
  // The leading block of comment lines (and '%', O numbers, blank lines): "(k.e = v)" or
  // "; k.e = v", where k.e is a dotted lower-case key.
  std::vector<std::pair<std::string, std::string>> out;
  std::size_t pos = 0;
  while (pos < text.size()) {
    std::size_t eol = text.find('\n', pos);
    if (eol == std::string_view::npos) eol = text.size();
    std::string_view line = text.substr(pos, eol - pos);
    pos = eol + 1;
    while (!line.empty() && (line.back() == '\r' || line.back() == ' ')) line.remove_suffix(1);
    while (!line.empty() && line.front() == ' ') line.remove_prefix(1);
    if (line.empty() || line == "%" || line.front() == 'O') continue;
    std::string_view body;
    if (line.front() == ';') {
      body = line.substr(1);
    } else if (line.front() == '(' && line.back() == ')') {
      body = line.substr(1, line.size() - 2);
    } else {
      break;  // the first block that is not a comment ends the header
    }
    while (!body.empty() && body.front() == ' ') body.remove_prefix(1);
    const std::size_t eq = body.find(" = ");
    if (eq == std::string_view::npos) continue;
    const std::string_view key = body.substr(0, eq);
    const bool dotted =
        key.find('.') != std::string_view::npos && std::all_of(key.begin(), key.end(), [](char c) {
          return (c >= 'a' && c <= 'z') || (c >= '0' && c <= '9') || c == '_' || c == '.';
        });
    if (dotted) out.emplace_back(std::string(key), std::string(body.substr(eq + 3)));
  }
  return out;
}

GcodeProgram read_gcode(std::string_view text, std::string_view source_name,
                        const GcodeReadOptions& options) {
  if (!(options.rapid_rate_mm_per_min > 0)) throw InputError("rapid rate must be > 0 mm/min");
  GcodeProgram prog = Reader(text, source_name, options).run();
  prog.info.header_keys = gcode_header_keys(text);
  return prog;
}

GcodeProgram read_gcode_file(const std::filesystem::path& file, const GcodeReadOptions& options) {
  return read_gcode(read_text_file(file), file.string(), options);
}

namespace {
// Two TOML values alike: the same text, or numbers equal as numbers ("37" and "37.0").
bool same_value(const std::string& a, const std::string& b) {
  if (a == b) return true;
  char* ea = nullptr;
  char* eb = nullptr;
  const double x = std::strtod(a.c_str(), &ea), y = std::strtod(b.c_str(), &eb);
  return ea != a.c_str() && *ea == '\0' && eb != b.c_str() && *eb == '\0' && x == y;
}
}  // namespace

std::vector<std::string> header_mismatches(const Job& job, const GcodeProgram& prog,
                                           const std::string& name) {
  // The sections the models read beside the program's moves (the tool, the slot and its
  // placement, the orbit, the spindle); the others (how the program was formatted, material,
  // measurements, analysis settings) may well differ on purpose.
  static const std::vector<std::string> kProgramSections = {"tool.", "slot.", "path.", "cutting."};
  auto defines_program = [](const std::string& key) {
    return std::any_of(kProgramSections.begin(), kProgramSections.end(),
                       [&](const std::string& s) { return key.rfind(s, 0) == 0; });
  };
  std::vector<std::string> out;
  if (prog.info.header_keys.empty()) return out;  // not written by trochomill
  std::map<std::string, std::string> in_job(job.flat_keys.begin(), job.flat_keys.end());
  std::map<std::string, std::string> in_program(prog.info.header_keys.begin(),
                                                prog.info.header_keys.end());
  for (const auto& [key, v] : in_program) {
    if (!defines_program(key)) continue;
    const auto it = in_job.find(key);
    if (it == in_job.end()) {
      out.push_back(
          fmt::format("{} was written with {} = {}, which the job does not set", name, key, v));
    } else if (!same_value(v, it->second)) {
      out.push_back(
          fmt::format("{} was written with {} = {}, the job has {}", name, key, v, it->second));
    }
  }
  for (const auto& [key, v] : in_job) {
    if (defines_program(key) && in_program.count(key) == 0) {
      out.push_back(fmt::format("{} was written without {} (the job has {})", name, key, v));
    }
  }
  return out;
}

}  // namespace trochomill
