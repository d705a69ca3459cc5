// SVG attribute syntax (svg_syntax.hpp): numbers, lengths, transform lists and path data by the
// grammars of SVG 1.1 (https://www.w3.org/TR/SVG11/paths.html#PathDataBNF,
// https://www.w3.org/TR/SVG11/coords.html#TransformAttribute), elliptical arcs by its
// implementation notes (https://www.w3.org/TR/SVG11/implnote.html#ArcImplementationNotes).
#include "geometry/svg_syntax.hpp"

#include <algorithm>
#include <cctype>
#include <charconv>
#include <cmath>
#include <cstring>
#include <vector>

#include "trochomill/units.hpp"

namespace trochomill::svg {
namespace {

bool is_digit(char c) { return c >= '0' && c <= '9'; }
bool starts_number(char c) { return is_digit(c) || c == '+' || c == '-' || c == '.'; }

void skip_wsp(std::string_view s, std::size_t& i) {
  while (i < s.size() && is_wsp(s[i])) ++i;
}

bool same_letters(std::string_view a, std::string_view b) {
  return a.size() == b.size() && std::equal(a.begin(), a.end(), b.begin(), [](char x, char y) {
           return (x | 0x20) == (y | 0x20);  // ASCII letters in either case
         });
}

}  // namespace

bool is_wsp(char c) { return c == ' ' || c == '\t' || c == '\n' || c == '\r' || c == '\f'; }

void skip_comma_wsp(std::string_view s, std::size_t& i) {
  skip_wsp(s, i);
  if (i < s.size() && s[i] == ',') {
    ++i;
    skip_wsp(s, i);
  }
}

double read_number(std::string_view s, std::size_t& i) {
  // number: sign? (digits ("." digits?)? | "." digits) (("e" | "E") sign? digits)?
  std::size_t j = i;
  if (j < s.size() && (s[j] == '+' || s[j] == '-')) ++j;
  const std::size_t int_start = j;
  while (j < s.size() && is_digit(s[j])) ++j;
  bool digits = j > int_start;
  if (j < s.size() && s[j] == '.') {
    const std::size_t frac_start = ++j;
    while (j < s.size() && is_digit(s[j])) ++j;
    digits = digits || j > frac_start;
  }
  if (!digits) throw SyntaxError{i, "a number"};
  bool negative_exponent = false;
  if (j < s.size() && (s[j] == 'e' || s[j] == 'E')) {
    std::size_t k = j + 1;
    if (k < s.size() && (s[k] == '+' || s[k] == '-')) negative_exponent = s[k++] == '-';
    if (k < s.size() && is_digit(s[k])) {  // else the 'e' is not the number's
      while (k < s.size() && is_digit(s[k])) ++k;
      j = k;
    } else {
      negative_exponent = false;
    }
  }
  const std::size_t from = s[i] == '+' ? i + 1 : i;  // from_chars takes no '+'
  double v = 0;
  const auto r = std::from_chars(s.data() + from, s.data() + j, v);
  if (r.ec == std::errc::result_out_of_range && negative_exponent) {
    v = 0;  // below the smallest double: 0
  } else if (r.ec != std::errc() || r.ptr != s.data() + j || !std::isfinite(v)) {
    throw SyntaxError{i, "a finite number"};
  }
  i = j;
  return v;
}

double mm_per_css_unit(std::string_view unit) {
  // CSS absolute units: 1 in = 2.54 cm = 25.4 mm = 96 px = 72 pt = 6 pc = 101.6 Q.
  static constexpr std::pair<const char*, double> kUnits[] = {
      {"", 25.4 / 96}, {"px", 25.4 / 96}, {"mm", 1.0},      {"cm", 10.0},
      {"in", 25.4},    {"pt", 25.4 / 72}, {"pc", 25.4 / 6}, {"q", 0.25},
  };
  for (const auto& [name, mm] : kUnits) {
    if (same_letters(unit, name)) return mm;
  }
  return 0;
}

double read_length(std::string_view s) {
  std::size_t i = 0;
  skip_wsp(s, i);
  const double v = read_number(s, i);
  std::size_t end = s.size();
  while (end > i && is_wsp(s[end - 1])) --end;
  const std::string_view unit = s.substr(i, end - i);
  if (unit == "%") throw SyntaxError{i, "an absolute length (a percentage is not read)"};
  const double mm = mm_per_css_unit(unit);
  if (mm == 0) {
    throw SyntaxError{i, "a unit of mm, cm, in, pt, pc, px, Q or none (px, 96 per in)"};
  }
  return v * mm / (25.4 / 96);
}

Affine read_transform(std::string_view s) {
  Affine m;
  std::size_t i = 0;
  skip_wsp(s, i);
  while (i < s.size()) {
    const std::size_t start = i;
    while (i < s.size() && std::isalpha(static_cast<unsigned char>(s[i]))) ++i;
    const std::string_view name = s.substr(start, i - start);
    skip_wsp(s, i);
    if (name.empty() || i >= s.size() || s[i] != '(') {
      throw SyntaxError{start,
                        "matrix(...), translate(...), scale(...), rotate(...), "
                        "skewX(...) or skewY(...)"};
    }
    ++i;
    skip_wsp(s, i);
    std::vector<double> v;
    while (i < s.size() && s[i] != ')' && v.size() < 6) {
      v.push_back(read_number(s, i));
      skip_comma_wsp(s, i);
    }
    if (i >= s.size() || s[i] != ')') throw SyntaxError{i, "')'"};
    ++i;
    const auto args = [&](std::initializer_list<std::size_t> counts, const char* what) {
      if (std::find(counts.begin(), counts.end(), v.size()) == counts.end()) {
        throw SyntaxError{start, what};
      }
    };
    Affine t;
    if (name == "matrix") {
      args({6}, "matrix(a b c d e f): six numbers");
      t = {v[0], v[1], v[2], v[3], v[4], v[5]};
    } else if (name == "translate") {
      args({1, 2}, "translate(tx [ty]): one or two numbers");
      t.e = v[0];
      t.f = v.size() > 1 ? v[1] : 0;
    } else if (name == "scale") {
      args({1, 2}, "scale(sx [sy]): one or two numbers");
      t.a = v[0];
      t.d = v.size() > 1 ? v[1] : v[0];
    } else if (name == "rotate") {
      args({1, 3}, "rotate(angle [cx cy]): one or three numbers");
      const double a = deg_to_rad(v[0]), c = std::cos(a), sn = std::sin(a);
      t = {c, sn, -sn, c, 0, 0};
      if (v.size() == 3) {  // translate(cx, cy) rotate(a) translate(-cx, -cy)
        t = Affine{1, 0, 0, 1, v[1], v[2]} * t * Affine{1, 0, 0, 1, -v[1], -v[2]};
      }
    } else if (name == "skewX" || name == "skewY") {
      args({1}, "skewX(angle) or skewY(angle): one number");
      (name == "skewX" ? t.c : t.b) = std::tan(deg_to_rad(v[0]));
    } else {
      throw SyntaxError{start, "matrix, translate, scale, rotate, skewX or skewY"};
    }
    m = m * t;
    skip_comma_wsp(s, i);
  }
  return m;
}

void endpoint_arc(const Vec2& p0, double rx, double ry, double phi_rad, bool large, bool sweep,
                  const Vec2& p1, PathSink& sink) {
  if (p0 == p1) return;  // F.6.2: the end points are the same: no arc
  rx = std::abs(rx);
  ry = std::abs(ry);
  if (rx == 0 || ry == 0) return sink.line(p0, p1);  // F.6.2: a radius 0 is a line
  // F.6.5 step 1: the half chord in the ellipse's axes, here divided by the radii (u, v):
  // the equations then hold without squaring the radii (no overflow).
  const double cp = std::cos(phi_rad), sp = std::sin(phi_rad);
  const Vec2 h = 0.5 * (p0 - p1);
  const double x1 = cp * h.x() + sp * h.y(), y1 = -sp * h.x() + cp * h.y();
  double u = x1 / rx, v = y1 / ry;
  // F.6.6: radii too small for the chord are scaled up until the chord is a diameter.
  const double lambda = u * u + v * v;
  if (!(lambda > 0) || !std::isfinite(lambda)) return sink.line(p0, p1);
  if (lambda > 1) {
    const double s = std::sqrt(lambda);
    rx *= s;
    ry *= s;
    u /= s;
    v /= s;
  }
  // Step 2: the centre in those axes, on the side the flags choose.
  const double q = std::max(0.0, (1 - u * u - v * v) / (u * u + v * v));
  const double coef = (large != sweep ? 1 : -1) * std::sqrt(q);
  const double cxp = coef * rx * v, cyp = -coef * ry * u;
  // Step 3: the centre in user space; step 4: the start angle and the sweep.
  const Vec2 c(cp * cxp - sp * cyp + 0.5 * (p0.x() + p1.x()),
               sp * cxp + cp * cyp + 0.5 * (p0.y() + p1.y()));
  const Vec2 a(u - coef * v, v + coef * u), b(-u - coef * v, -v + coef * u);
  const double t0 = std::atan2(a.y(), a.x());
  double dt = std::atan2(a.x() * b.y() - a.y() * b.x(), a.dot(b));
  if (!sweep && dt > 0) dt -= kTwoPi;
  if (sweep && dt < 0) dt += kTwoPi;
  sink.ellipse(c, Vec2(rx * cp, rx * sp), Vec2(-ry * sp, ry * cp), t0, t0 + dt, p0, p1);
}

void read_path(std::string_view d, PathSink& sink) {
  std::size_t i = 0;
  const auto num = [&] {
    const double v = read_number(d, i);
    skip_comma_wsp(d, i);
    return v;
  };
  const auto point = [&](const Vec2& base) {
    const double x = num();
    return Vec2(base.x() + x, base.y() + num());
  };
  const auto flag = [&] {
    if (i >= d.size() || (d[i] != '0' && d[i] != '1')) throw SyntaxError{i, "a flag (0 or 1)"};
    const bool f = d[i++] == '1';
    skip_comma_wsp(d, i);
    return f;
  };
  Vec2 cur = Vec2::Zero(), start = Vec2::Zero();
  Vec2 last_cubic = cur, last_quad = cur;  // the last control points, for S and T
  char prev = 0;                           // the previous command, upper case
  skip_wsp(d, i);
  while (i < d.size()) {
    const char cmd = d[i];
    if (std::strchr("MmLlHhVvCcSsQqTtAaZz", cmd) == nullptr || cmd == '\0') {
      throw SyntaxError{i, prev ? "a path command (M L H V C S Q T A Z, or lower case)"
                                : "a moveto (M or m) to begin"};
    }
    if (!prev && cmd != 'M' && cmd != 'm') throw SyntaxError{i, "a moveto (M or m) to begin"};
    ++i;
    skip_wsp(d, i);
    const bool rel = cmd >= 'a';
    const char up = static_cast<char>(rel ? cmd - 'a' + 'A' : cmd);
    if (up == 'Z') {
      if (cur != start) sink.line(cur, start);
      cur = start;
      prev = 'Z';
      continue;
    }
    bool first = true;
    do {  // the command's argument groups, repeated while numbers follow
      const Vec2 base = rel ? cur : Vec2::Zero();
      char done = up;
      switch (up) {
        case 'M': {
          const Vec2 p = point(base);
          if (first) {
            cur = start = p;
          } else {  // further pairs after a moveto are linetos
            sink.line(cur, p);
            cur = p;
            done = 'L';
          }
          break;
        }
        case 'L': {
          const Vec2 p = point(base);
          sink.line(cur, p);
          cur = p;
          break;
        }
        case 'H':
        case 'V': {
          const double v = num();
          Vec2 p = cur;
          (up == 'H' ? p.x() : p.y()) = (rel ? (up == 'H' ? cur.x() : cur.y()) : 0) + v;
          sink.line(cur, p);
          cur = p;
          break;
        }
        case 'C':
        case 'S': {
          const Vec2 c1 = up == 'C'                      ? point(base)
                          : (prev == 'C' || prev == 'S') ? Vec2(2 * cur - last_cubic)
                                                         : cur;
          const Vec2 c2 = point(base), p = point(base);
          sink.cubic(cur, c1, c2, p);
          last_cubic = c2;
          cur = p;
          break;
        }
        case 'Q':
        case 'T': {
          const Vec2 c = up == 'Q'                      ? point(base)
                         : (prev == 'Q' || prev == 'T') ? Vec2(2 * cur - last_quad)
                                                        : cur;
          const Vec2 p = point(base);
          // The quadratic as the cubic it is: control points 2/3 of the way to its one.
          sink.cubic(cur, cur + 2.0 / 3 * (c - cur), p + 2.0 / 3 * (c - p), p);
          last_quad = c;
          cur = p;
          break;
        }
        case 'A': {
          const double rx = num(), ry = num(), phi = num();
          const bool large = flag(), sweep = flag();
          const Vec2 p = point(base);
          endpoint_arc(cur, rx, ry, deg_to_rad(phi), large, sweep, p, sink);
          cur = p;
          break;
        }
        default:
          break;
      }
      prev = done;
      first = false;
    } while (i < d.size() && starts_number(d[i]));
  }
}

}  // namespace trochomill::svg
