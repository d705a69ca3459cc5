// The interpreter's values: numbers, #n and #<name> parameters (LinuxCNC's predefined ones
// and Fanuc's system variables), [expressions] with LinuxCNC's precedence (or Fanuc's), unary
// functions.
#include <fmt/format.h>

#include <algorithm>
#include <array>
#include <charconv>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <optional>
#include <string>
#include <string_view>

#include "interp.hpp"
#include "ngc_lexer.hpp"
#include "trochomill/gcode.hpp"
#include "trochomill/units.hpp"

namespace trochomill::gcode_detail {

double Interpreter::read_number(std::size_t& i) {
  const std::string& s = line_.text;
  const std::size_t at = i;
  bool neg = false;
  if (i < s.size() && (s[i] == '+' || s[i] == '-')) {
    neg = s[i] == '-';
    ++i;
  }
  const char* b = s.data() + i;
  const char* e = s.data() + s.size();
  double v = 0;
  auto [ptr, ec] = std::from_chars(b, e, v, std::chars_format::fixed);
  if (ec == std::errc::result_out_of_range) {
    if (word_ != 0) {
      fail(word_at_, fmt::format("'{}' has a number too large to represent", upper(word_)));
    }
    fail(at, "a number too large to represent");
  }
  if (ec != std::errc() || ptr == b) {
    if (word_ != 0 && at == word_at_ + 1) {
      fail(word_at_, fmt::format("'{}' needs a number after it", upper(word_)));
    }
    if (i < s.size()) {
      fail(i, fmt::format("expected a number, found {}", ngc::shown(s[i])));
    }
    fail(i, "expected a number at the end of the line");
  }
  i = static_cast<std::size_t>(ptr - s.data());
  return neg ? -v : v;
}

double Interpreter::checked(double v, std::size_t at) const {
  if (std::isnan(v) && !fanuc_) fail(at, "the calculation gives 'not a number'");
  if (std::isinf(v)) fail(at, "the calculation gives infinity");
  return v;
}

// A real value: number, #parameter, [expression], unary function, or -value / +value.
double Interpreter::read_value(std::size_t& i) {
  const std::string& s = line_.text;
  if (i >= s.size()) fail(i, "expected a value at the end of the line");
  // Brackets, signs and # nest by recursion: bounded, so no line can exhaust the stack.
  struct Depth {
    int& d;
    explicit Depth(int& x) : d(++x) {}
    ~Depth() { --d; }
  } depth(depth_);
  if (depth_ > kMaxNesting) {
    fail(i, fmt::format("the expression nests deeper than {} levels", kMaxNesting));
  }
  const std::size_t at = i;
  const char c = s[i];
  const char c1 = i + 1 < s.size() ? s[i + 1] : '\0';
  double v;
  if (c == '[') {
    v = read_expression(i);
  } else if (c == '#') {
    v = read_parameter(i);
  } else if ((c == '+' || c == '-') && c1 != '\0' && !(c1 >= '0' && c1 <= '9') && c1 != '.') {
    ++i;
    v = read_value(i);
    if (c == '-') v = -v;
  } else if (c >= 'a' && c <= 'z') {
    if (word_ != 0 && at == word_at_ + 1 && !function_follows(i)) {
      fail(word_at_, fmt::format("'{}' needs a number after it", upper(word_)));
    }
    v = read_function(i);
  } else {
    v = read_number(i);
  }
  return checked(v, at);
}

// An expression "[ ... ]" with LinuxCNC's precedence, left to right within a level.
double Interpreter::read_expression(std::size_t& i) {
  const std::size_t open = i;
  ++i;  // '['
  double v = read_binary(i, 1);
  if (i >= line_.text.size() || line_.text[i] != ']') {
    if (i >= line_.text.size()) fail(open, "'[' is not closed on this line");
    fail(i, fmt::format("expected an operator or ']', found {}", ngc::shown(line_.text[i])));
  }
  ++i;
  return v;
}

// LinuxCNC: ** > * / MOD > + - > comparisons > AND OR XOR. Fanuc (Macro B): * / AND MOD >
// + - OR XOR > comparisons, AND OR XOR bitwise on whole numbers.
int Interpreter::precedence(Op op) const {
  if (fanuc_) {
    switch (op) {
      case Op::pow:
        return 6;
      case Op::mul:
      case Op::div:
      case Op::mod:
      case Op::and_:
        return 5;
      case Op::add:
      case Op::sub:
      case Op::or_:
      case Op::xor_:
        return 4;
      case Op::none:
        return 0;
      default:
        return 3;
    }
  }
  switch (op) {
    case Op::pow:
      return 6;
    case Op::mul:
    case Op::div:
    case Op::mod:
      return 5;
    case Op::add:
    case Op::sub:
      return 4;
    case Op::eq:
    case Op::ne:
    case Op::gt:
    case Op::ge:
    case Op::lt:
    case Op::le:
      return 3;
    case Op::and_:
    case Op::or_:
    case Op::xor_:
      return 2;
    case Op::none:
      break;
  }
  return 0;
}

// The operator at i (without consuming it), and its length.
Interpreter::Op Interpreter::peek_op(std::size_t i, std::size_t& len) const {
  const std::string_view s = std::string_view(line_.text).substr(i);
  struct Name {
    std::string_view text;
    Op op;
  };
  static constexpr std::array<Name, 15> kOps{{{"**", Op::pow},
                                              {"*", Op::mul},
                                              {"/", Op::div},
                                              {"mod", Op::mod},
                                              {"+", Op::add},
                                              {"-", Op::sub},
                                              {"eq", Op::eq},
                                              {"ne", Op::ne},
                                              {"gt", Op::gt},
                                              {"ge", Op::ge},
                                              {"lt", Op::lt},
                                              {"le", Op::le},
                                              {"and", Op::and_},
                                              {"or", Op::or_},
                                              {"xor", Op::xor_}}};
  for (const Name& n : kOps) {
    if (s.substr(0, n.text.size()) == n.text) {
      len = n.text.size();
      return n.op;
    }
  }
  len = 0;
  return Op::none;
}

double Interpreter::read_binary(std::size_t& i, int min_prec) {
  double left = read_value(i);
  for (;;) {
    std::size_t len = 0;
    const Op op = peek_op(i, len);
    if (op == Op::none || precedence(op) < min_prec) return left;
    const std::size_t at = i;
    i += len;
    const double right = read_binary(i, precedence(op) + 1);
    left = checked(apply(op, left, right, at), at);
  }
}

double Interpreter::apply(Op op, double a, double b, std::size_t at) const {
  if (fanuc_) {
    // A vacant variable (NaN here) is "null": equal only to another null, 0 elsewhere.
    const bool na = std::isnan(a), nb = std::isnan(b);
    if (op == Op::eq && (na || nb)) return na && nb ? 1 : 0;
    if (op == Op::ne && (na || nb)) return na && nb ? 0 : 1;
    if (na) a = 0;
    if (nb) b = 0;
    if (op == Op::and_ || op == Op::or_ || op == Op::xor_) {
      if (std::abs(a) > 2e9 || std::abs(b) > 2e9 || a != std::floor(a) || b != std::floor(b)) {
        fail(at, "AND, OR and XOR take whole numbers (Fanuc: bit by bit)");
      }
      const auto x = static_cast<long long>(a), y = static_cast<long long>(b);
      return static_cast<double>(op == Op::and_ ? (x & y) : op == Op::or_ ? (x | y) : (x ^ y));
    }
  }
  switch (op) {
    case Op::pow:
      if (a < 0 && std::floor(b) != b) fail(at, "a negative number to a non-integer power");
      return std::pow(a, b);
    case Op::mul:
      return a * b;
    case Op::div:
      if (b == 0) fail(at, "division by zero");
      return a / b;
    case Op::mod: {
      if (b == 0) fail(at, "MOD by zero");
      double r = std::fmod(a, b);
      if (r < 0) r += std::abs(b);
      return r;
    }
    case Op::add:
      return a + b;
    case Op::sub:
      return a - b;
    case Op::eq:
      return std::abs(a - b) < kTolEqual ? 1 : 0;
    case Op::ne:
      return std::abs(a - b) >= kTolEqual ? 1 : 0;
    case Op::gt:
      return a > b ? 1 : 0;
    case Op::ge:
      return a >= b ? 1 : 0;
    case Op::lt:
      return a < b ? 1 : 0;
    case Op::le:
      return a <= b ? 1 : 0;
    case Op::and_:
      return (a != 0 && b != 0) ? 1 : 0;
    case Op::or_:
      return (a != 0 || b != 0) ? 1 : 0;
    case Op::xor_:
      return ((a != 0) != (b != 0)) ? 1 : 0;
    case Op::none:
      break;
  }
  return a;
}

// A function name and '[' at i (else the letter is the next word: "X F100").
bool Interpreter::function_follows(std::size_t i) const {
  const std::string& s = line_.text;
  std::size_t j = i;
  while (j < s.size() && s[j] >= 'a' && s[j] <= 'z') ++j;
  return j > i + 1 && j < s.size() && s[j] == '[';
}

double Interpreter::read_function(std::size_t& i) {
  const std::string& s = line_.text;
  const std::size_t at = i;
  std::size_t j = i;
  while (j < s.size() && s[j] >= 'a' && s[j] <= 'z') ++j;
  const std::string_view name = std::string_view(s).substr(i, j - i);
  static constexpr std::array<std::string_view, 14> kNames{"abs", "acos", "asin", "atan",  "cos",
                                                           "exp", "fix",  "fup",  "ln",    "round",
                                                           "sin", "sqrt", "tan",  "exists"};
  if (std::find(kNames.begin(), kNames.end(), name) == kNames.end()) {
    fail(at, fmt::format("unknown function '{}' (ABS ACOS ASIN ATAN COS EXISTS EXP FIX FUP LN "
                         "ROUND SIN SQRT TAN)",
                         name));
  }
  i = j;
  if (i >= s.size() || s[i] != '[') {
    fail(i, fmt::format("{} needs its argument in [ ]", name));
  }
  if (name == "exists") {
    // EXISTS[#<name>]: 1 when the named parameter is defined.
    ++i;
    if (s.compare(i, 2, "#<") != 0) fail(i, "EXISTS needs a named parameter: EXISTS[#<name>]");
    const std::size_t close = s.find('>', i);
    if (close == std::string::npos) fail(i, "the parameter name has no closing '>'");
    const std::string pname = s.substr(i + 2, close - i - 2);
    i = close + 1;
    if (i >= s.size() || s[i] != ']') fail(i, "expected ']' after EXISTS's parameter");
    ++i;
    return find_named(pname) != nullptr ? 1 : 0;
  }
  if (name == "atan" && fanuc_) {
    // Fanuc writes ATAN[y]/[x] or ATAN[y,x].
    const std::size_t comma = line_.text.find(',', i);
    const std::size_t close = line_.text.find(']', i);
    if (comma != std::string::npos && comma < close) {
      ++i;
      const double yy = zero_if_vacant(read_binary(i, 1));
      ++i;  // ','
      const double xx = zero_if_vacant(read_binary(i, 1));
      if (i >= s.size() || s[i] != ']') fail(i, "ATAN is written ATAN[y,x]");
      ++i;
      return std::atan2(yy, xx) * 180.0 / kPi;
    }
  }
  const double x = zero_if_vacant(read_expression(i));
  if (name == "atan") {
    // ATAN[y]/[x]: degrees, the quadrant from both signs.
    if (i >= s.size() || s[i] != '/') fail(i, "ATAN is written ATAN[y]/[x]");
    ++i;
    if (i >= s.size() || s[i] != '[') fail(i, "ATAN is written ATAN[y]/[x]");
    const double xx = read_expression(i);
    return std::atan2(x, zero_if_vacant(xx)) * 180.0 / kPi;
  }
  if (name == "abs") return std::abs(x);
  if (name == "acos" || name == "asin") {
    if (x < -1 || x > 1) fail(at, fmt::format("{} of {:g}, outside -1 .. 1", name, x));
    return (name == "acos" ? std::acos(x) : std::asin(x)) * 180.0 / kPi;
  }
  if (name == "cos") return std::cos(x * kPi / 180.0);
  if (name == "sin") return std::sin(x * kPi / 180.0);
  if (name == "tan") return std::tan(x * kPi / 180.0);
  if (name == "exp") return std::exp(x);
  if (name == "fix") return std::floor(x);
  if (name == "fup") return std::ceil(x);
  if (name == "ln") {
    if (x <= 0) fail(at, fmt::format("LN of {:g}, which is not > 0", x));
    return std::log(x);
  }
  if (name == "round") {
    if (std::abs(x) > 2e9) fail(at, fmt::format("ROUND of {:g}, beyond +-2e9", x));
    return static_cast<double>(static_cast<int>(x + (x < 0 ? -0.5 : 0.5)));
  }
  // sqrt
  if (x < 0) fail(at, fmt::format("SQRT of {:g}, which is negative", x));
  return std::sqrt(x);
}

// '#' then a number/expression (numbered) or <name>.
double Interpreter::read_parameter(std::size_t& i) {
  const std::size_t at = i;
  ++i;
  if (i < line_.text.size() && line_.text[i] == '<') {
    const std::string name = read_name(i);
    return named_value(name, at);
  }
  const int index = parameter_index(read_value(i), at);
  if (fanuc_) return fanuc_variable(index);
  if (index >= 5420 && index <= 5428) {
    // The current position in the active system: X Y Z, then A B C (degrees), U V W.
    if (comp_.on()) {
      fail(at, fmt::format("#{} (the current position) cannot be read with cutter radius "
                           "compensation on (#<_x> #<_y> #<_z> give the tool centre)",
                           index));
    }
    if (index <= 5422) return cur_pos_[index - 5420] / unit_;
    const int k = index - 5423;
    return xpos_[static_cast<std::size_t>(k)] / (k >= 3 ? unit_ : 1.0);
  }
  return params_[static_cast<std::size_t>(index)];
}

// Fanuc's system variables that describe the position; #0 is always vacant.
double Interpreter::fanuc_variable(int index) const {
  if (index >= 4001 && index <= 4130) return fanuc_modal(index);
  if (index >= 5001 && index <= 5003) return cur_pos_[index - 5001] / unit_;
  if (index >= 5041 && index <= 5043) return comp_.current()[index - 5041] / unit_;
  if (index >= 5021 && index <= 5023) return to_machine_tip(cur_pos_)[index - 5021] / unit_;
  return params_[static_cast<std::size_t>(index)];
}

// Fanuc's modal information #4001 .. #4130 (read only): the G code of each group the program
// set (#4001 motion, #4002 plane, #4003 G90/G91, #4005 feed mode, #4006 units, #4007 cutter
// compensation, #4008 length offset, #4009 canned cycle, #4010 return level, #4014 work
// system: 54 .. 59, 54.1), and F (#4109, program units), S (#4119), T (#4120) and the active
// H and D; any other is vacant.
double Interpreter::fanuc_modal(int index) const {
  const double vacant = std::numeric_limits<double>::quiet_NaN();
  const double motion = motion_ < 0 ? 80 : (motion_ >= 730 ? 80 : motion_ / 10.0);
  switch (index) {
    case 4001:
      return motion;
    case 4002:
      return plane_ == Plane::xy ? 17 : plane_ == Plane::zx ? 18 : 19;
    case 4003:
      return absolute_ ? 90 : 91;
    case 4005:
      return feed_mode_ == FeedMode::inverse_time ? 93 : feed_mode_ == FeedMode::per_rev ? 95 : 94;
    case 4006:
      return unit_ == 1.0 ? 21 : 20;
    case 4007:
      return !comp_.on() ? 40 : comp_.on_left() ? 41 : 42;
    case 4008:
      return tool_z_ != 0 ? 43 : 49;
    case 4009:
      return motion_ >= 730 ? motion_ / 10.0 : 80;
    case 4010:
      return retract_r_ ? 99 : 98;
    case 4014:
      return system_ <= 6   ? 53 + system_
             : system_ <= 9 ? 59 + 0.1 * (system_ - 6)
             : haas_        ? 154
                            : 54.1;
    case 4109:
      return feed_ / unit_;
    case 4119:
      return speed_;
    case 4120:
      return tool_selected_;
    default:
      return vacant;
  }
}

int Interpreter::parameter_index(double v, std::size_t at) const {
  if (fanuc_ && std::isnan(v)) fail(at, "a variable number that is vacant (#0)");
  if (fanuc_ && v == 0) return 0;  // #0: vacant, read only
  const double r = std::round(v);
  if (std::abs(v - r) > 1e-4) fail(at, fmt::format("parameter number {:g} is not whole", v));
  // Haas keeps G154 P1 .. P99's offsets at #14001 + 20 (P - 1), P1 .. P20 also at Fanuc's
  // #7001 + 20 (P - 1) (G110 .. G129): one store, the extra systems' (sys_param).
  if (haas_ && r >= 14001 && r < 14001 + 20 * 99) return static_cast<int>(r) - 14001 + 7001;
  if (r < 1 || r >= static_cast<double>(params_.size())) {
    fail(at, fmt::format("parameter number {:g} is outside 1 .. {}", r, params_.size() - 1));
  }
  return static_cast<int>(r);
}

// At '<': the name up to '>' (blanks already removed, lower case).
std::string Interpreter::read_name(std::size_t& i) {
  const std::size_t close = line_.text.find('>', i);
  if (close == std::string::npos) fail(i, "the parameter name has no closing '>'");
  if (close == i + 1) fail(i, "an empty parameter name");
  std::string name = line_.text.substr(i + 1, close - i - 1);
  i = close + 1;
  return name;
}

double* Interpreter::find_named(const std::string& name) {
  if (!name.empty() && name[0] == '_') {
    auto it = globals_.find(name);
    return it == globals_.end() ? nullptr : &it->second;
  }
  for (auto& [k, v] : frames_.back().locals) {
    if (k == name) return &v;
  }
  return nullptr;
}

double Interpreter::named_value(const std::string& name, std::size_t at) {
  if (name == "_feed" && prog_.info.feed_read_at.empty()) {
    prog_.info.feed_read_at =
        fmt::format("{}:{}:{}", sources_[cur_.source].name, cur_.line_no, col_of(at));
  }
  if (const auto v = predefined(name)) return *v;
  if (const double* p = find_named(name)) return *p;
  fail(at, fmt::format("named parameter #<{}> is not defined", name));
}

// LinuxCNC's read-only named parameters (the ones that describe motion).
std::optional<double> Interpreter::predefined(const std::string& name) const {
  if (name.empty() || name[0] != '_') return std::nullopt;
  const double u = unit_;
  if (name == "_x") return comp_.current().x() / u;
  if (name == "_y") return comp_.current().y() / u;
  if (name == "_z") return comp_.current().z() / u;
  if (name == "_abs_x" || name == "_abs_y" || name == "_abs_z") {
    const Vec3 m = to_machine_tip(cur_pos_);
    return (name == "_abs_x" ? m.x() : name == "_abs_y" ? m.y() : m.z()) / u;
  }
  // A B C (degrees) and U V W: the position of the axes besides X Y Z, in the active system
  // (_a ..) and in machine coordinates (_abs_a ..).
  const bool abs_extra = name.size() == 6 && name.compare(0, 5, "_abs_") == 0;
  if (name.size() == 2 || abs_extra) {
    const auto at = std::string_view("abcuvw").find(name.back());
    if (at != std::string_view::npos) {
      const int k = static_cast<int>(at);
      const double p = xpos_[at];
      return (abs_extra ? xmachine(k, p) : p) / (k >= 3 ? u : 1.0);
    }
  }
  if (name == "_value") return value_;
  if (name == "_value_returned") return value_returned_ ? 1 : 0;
  if (name == "_line") return static_cast<double>(cur_.line_no);
  if (name == "_metric") return u == 1 ? 1 : 0;
  if (name == "_imperial") return u == 1 ? 0 : 1;
  if (name == "_absolute") return absolute_ ? 1 : 0;
  if (name == "_incremental") return absolute_ ? 0 : 1;
  if (name == "_inverse_time") return feed_mode_ == FeedMode::inverse_time ? 1 : 0;
  if (name == "_units_per_minute") return feed_mode_ == FeedMode::per_minute ? 1 : 0;
  if (name == "_units_per_rev") return feed_mode_ == FeedMode::per_rev ? 1 : 0;
  if (name == "_feed") return feed_ / u;  // program units
  if (name == "_rpm") return speed_;
  if (name == "_current_tool") return tool_loaded_;
  if (name == "_selected_tool") return tool_selected_;
  if (name == "_tool_offset") return tool_z_ / u;
  if (name == "_coord_system") {
    static constexpr std::array<int, 9> kCodes{540, 550, 560, 570, 580, 590, 591, 592, 593};
    return system_ <= 9 ? kCodes[static_cast<std::size_t>(system_ - 1)] : 541;
  }
  if (name == "_plane") return plane_ == Plane::xy ? 170 : plane_ == Plane::zx ? 180 : 190;
  if (name == "_motion_mode") return motion_ < 0 ? 800 : motion_;
  if (name == "_ijk_absolute_mode") return arc_absolute_ ? 1 : 0;
  if (name == "_retract_r_plane") return retract_r_ ? 1 : 0;
  if (name == "_retract_old_z") return retract_r_ ? 0 : 1;
  if (name == "_call_level") return static_cast<double>(frames_.size() - 1);
  if (name == "_spindle_on") return spindle_on_ ? 1 : 0;
  if (name == "_spindle_rpm_mode") return css_ ? 0 : 1;
  if (name == "_spindle_css_mode") return css_ ? 1 : 0;
  if (name == "_ccomp") return 400;
  return std::nullopt;
}

void Interpreter::set_named(const std::string& name, double v, std::uint32_t column) {
  if (predefined(name)) {
    fail_at(column,
            fmt::format("#<{}> is read-only (one of LinuxCNC's predefined parameters)", name));
  }
  if (double* p = find_named(name)) {
    *p = v;
  } else if (name[0] == '_') {
    globals_.emplace(name, v);
  } else {
    frames_.back().locals.emplace_back(name, v);
  }
}

}  // namespace trochomill::gcode_detail
