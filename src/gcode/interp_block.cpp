// The interpreter's blocks: a line's words read into a Block, its G codes sorted into their
// modal groups, checked (coordinates in range, Fanuc's read-only variables, the words no code
// uses, unsupported codes named); the modal state M70-M73 save and restore.
#include <fmt/format.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <string>
#include <string_view>
#include <utility>

#include "interp.hpp"
#include "ngc_lexer.hpp"
#include "trochomill/gcode.hpp"

namespace trochomill::gcode_detail {

void Interpreter::read_block(std::size_t i) {
  block_.clear();
  const std::string& s = line_.text;
  while (i < s.size()) {
    const char c = s[i];
    const std::size_t at = i;
    if (c == '#') {
      // #n = value or #<name> = value
      ++i;
      std::string name;
      int index = 0;
      if (i < s.size() && s[i] == '<') {
        name = read_name(i);
      } else {
        index = parameter_index(read_value(i), at);
      }
      if (i >= s.size() || s[i] != '=') {
        fail(i, "a parameter on its own is not a word: write #1 = value to set it");
      }
      ++i;
      // Fanuc: the right side is an expression without brackets (#1 = #1 + 1).
      const double v = fanuc_ ? read_binary(i, 1) : read_value(i);
      if (name.empty()) {
        block_.numbered.push_back({index, v, at});
      } else {
        block_.named.push_back({std::move(name), v, col_of(at)});
      }
      continue;
    }
    if ((c == '@' || c == '^') && !fanuc_) {
      // LinuxCNC's polar words (its find_ends): distance @ and angle ^ in the XY plane.
      ++i;
      if (i >= s.size()) fail(at, fmt::format("'{}' needs a number after it", c));
      word_ = c;
      word_at_ = at;
      const double v = read_value(i);
      word_ = 0;
      bool& has = c == '@' ? block_.has_polar_r : block_.has_polar_a;
      if (has) fail(at, fmt::format("two {} words in one block", c));
      has = true;
      (c == '@' ? block_.polar_r : block_.polar_a_deg) = v;
      (c == '@' ? block_.polar_r_col : block_.polar_a_col) = col_of(at);
      continue;
    }
    if (c < 'a' || c > 'z') {
      fail(i, fmt::format("unexpected character {} (expected a word such as G1 or X10)",
                          ngc::shown(c)));
    }
    ++i;
    char letter = c;
    // Sinumerik's radius "CR=5".
    if (c == 'c' && s.compare(i, 2, "r=") == 0) {
      i += 2;
      letter = 'r';
    }
    if (i >= s.size()) fail(at, fmt::format("'{}' needs a number after it", upper(c)));
    word_ = c;
    word_at_ = at;
    const std::size_t value_at = i;
    const double v = read_value(i);
    word_ = 0;
    if (fanuc_) {
      if (std::isnan(v)) continue;  // a word whose variable is vacant is not there
      if (std::string_view("xyzijkrq").find(letter) != std::string_view::npos && !decimal_warned_) {
        const std::string_view lit = std::string_view(s).substr(value_at, i - value_at);
        const bool plain =
            !lit.empty() && lit.find_first_not_of("+-0123456789") == std::string_view::npos;
        if (plain) {
          decimal_warned_ = true;
          warn(
              fmt::format("{}{} has no decimal point: taken as {} {} (calculator-type input); "
                          "a control set to least-increment input reads {:g} {}",
                          upper(letter), lit, lit, unit_name(), v * (unit_ == 1.0 ? 0.001 : 0.0001),
                          unit_name()));
        }
      }
    }
    // Fanuc's G65: every word after it but G, L, N, O and P is an argument, M included
    // (argument specification I: M is #13), I J K up to ten times each (specification II).
    const bool g65 =
        fanuc_ && std::any_of(block_.g.begin(), block_.g.end(),
                              [](const Block::Code& code) { return code.code10 == 650; });
    const bool g65_argument =
        g65 && std::string_view("glnop").find(letter) == std::string_view::npos;
    if ((letter == 'g' || letter == 'm') && !g65_argument) {
      // Every code is below 1000 (G59.3, M199): anything larger is no code (and would not
      // fit the tenths it is compared in).
      if (!(std::abs(v) < 1e4)) fail(at, fmt::format("{}{:g} is not a code", upper(letter), v));
      int code = code10(v);
      // Mach3's straight probe G31 is LinuxCNC's G38.2.
      if (letter == 'g' && mach3_ && code == 310) code = 382;
      if (letter == 'g' && mach3_ && code == 281) {
        fail(at,
             "Mach3's G28.1 (referencing axes on their home switches) is not read: where the "
             "axes go is the machine's homing set-up");
      }
      (letter == 'g' ? block_.g : block_.m).push_back({code, col_of(at)});
      continue;
    }
    if (letter == 'o') fail(at, "an O-word must start its line");
    const auto k = static_cast<std::size_t>(letter - 'a');
    if (g65_argument) {
      block_.arguments.push_back({letter, v, col_of(at)});
      if (block_.has(letter) && (letter == 'i' || letter == 'j' || letter == 'k')) continue;
    }
    if (block_.has(letter)) {
      fail(at, fmt::format("two {} words in one block", upper(letter)));
    }
    block_.present |= 1U << k;
    block_.value[k] = v;
    block_.column[k] = col_of(at);
  }
}

// The block's #i = value settings, after the whole line is read (Fanuc: #3000 raises its
// alarm and the positions are read only, when the setting runs).
void Interpreter::set_numbered() {
  for (const auto& p : block_.numbered) {
    if (fanuc_) check_fanuc_write(p.index, p.at, p.value);
    params_[static_cast<std::size_t>(p.index)] = p.value;
    // A system's offset the program sets itself is given (not assumed the output system's).
    if (p.index >= 5221 && p.index < 5221 + 20 * 9) note_given((p.index - 5201) / 20);
    if (o_numbers_ && p.index >= 7001 && p.index < 7001 + 20 * kExtraSystems) {
      note_given(10 + (p.index - 7001) / 20);
    }
  }
}

void Interpreter::check_fanuc_write(int index, std::size_t at, double v) const {
  if (index == 0) fail(at, "#0 is always vacant: it cannot be set");
  if (index == 3000) {
    fail(at, fmt::format("the program raised alarm #3000 = {:g}{}", v,
                         line_.comment.empty() ? "" : " (" + line_.comment + ")"));
  }
  if (index >= 5001 && index <= 5043) {
    fail(at, fmt::format("#{} is a position the control keeps: read only", index));
  }
  if (index >= 4001 && index <= 4130) {
    fail(at, fmt::format("#{} is modal information the control keeps: read only", index));
  }
}

void Interpreter::check_range(char c) const {
  if (std::abs(block_[c]) * unit_ > kMaxCoordinate) {
    // Under G20 the word is in inches: the message says so, and what it is in mm.
    const std::string in_mm =
        unit_ == 1.0 ? "" : fmt::format(" (inches under G20: {:g} mm)", block_[c] * unit_);
    fail_at(block_.col(c), fmt::format("{}{:g}{} is beyond +-1e6 mm, what trochomill represents",
                                       upper(c), block_[c], in_mm));
  }
}

// The block's words before its codes run: coordinates in range (A B C in degrees).
void Interpreter::check_words() const {
  // M61's Q is a tool number (checked as one there), not a length.
  const bool m61 =
      std::any_of(block_.m.begin(), block_.m.end(), [](const auto& m) { return m.code10 == 610; });
  for (const char c : std::string_view("xyzijkrquvw")) {
    if (block_.has(c) && !(c == 'q' && m61)) check_range(c);
  }
  for (const char c : std::string_view("abc")) {
    if (block_.has(c) && !(std::abs(block_[c]) <= kMaxCoordinate)) {
      fail_at(block_.col(c), fmt::format("{}{:g} is beyond +-1e6 degrees, what trochomill "
                                         "represents",
                                         upper(c), block_[c]));
    }
  }
}

// The block's G codes by modal group; G53 apart, the codes of no effect on the path skipped.
BlockCodes Interpreter::group_codes() const {
  // G codes by modal group (two of one group are an error).
  std::array<int, kGroups> code;
  code.fill(-1);
  std::array<std::uint32_t, kGroups> col{};
  bool g53 = false;
  BlockCodes out;
  for (const auto& [g, column] : block_.g) {
    if (g == 530) {
      g53 = true;
      continue;
    }
    if (g == 610 || g == 611 || g == 640) {
      comp_.refuse(column, fmt::format("{} (path control mode)", code_name('G', g)));
      continue;  // path blending: no effect on the path
    }
    if (g == 960 || g == 970) continue;  // spindle speed modes (set_feed_speed_tool)
    if (g == 150 || g == 160) {
      if (!o_numbers_) unsupported_g(g, column);  // LinuxCNC has @ ^, not G15/G16
      continue;                                   // polar coordinates off / on (polar_words)
    }
    if (g == 1870 || g == 1030) {
      // Haas's smoothness (G187 P E) and block look-ahead (G103 P): no effect on the path.
      if (!haas_) unsupported_g(g, column);
      continue;
    }
    // Fanuc's scaling (G50/G51) and rotation (G68/G69); LinuxCNC has neither.
    if ((g == 500 || g == 510 || g == 680 || g == 690) && !fanuc_) unsupported_g(g, column);
    if (g == 500 || g == 690) {
      (g == 500 ? out.g50 : out.g69) = true;
      (g == 500 ? out.g50_col : out.g69_col) = column;
      continue;
    }
    // Extra coordinate systems: Fanuc's G54.1 P (and Haas's), Haas's G154 P and G110 .. G129.
    if ((g == 541 && !fanuc_) || ((g == 1540 || (g >= 1100 && g <= 1290)) && !haas_)) {
      unsupported_g(g, column);
    }
    // Fanuc's tool centre point control G43.4: read as G43 (set_modes warns).
    if (g == 434 && !fanuc_) unsupported_g(g, column);
    const auto it = std::find_if(kGroupOf.begin(), kGroupOf.end(),
                                 [g = g](const GroupOf& e) { return e.code10 == g; });
    if (it == kGroupOf.end()) unsupported_g(g, column);
    const auto k = static_cast<std::size_t>(it->group);
    if (it->group == kRetract) {
      comp_.refuse(column, fmt::format("{} (canned cycle retract mode)", code_name('G', g)));
    }
    // G80 beside another motion code: the other one is the mode (LinuxCNC reads "G80 G0").
    if (it->group == kMotion && (code[k] == 800 || g == 800) && code[k] != g) {
      if (code[k] < 0 || code[k] == 800) {
        code[k] = g;
        col[k] = column;
      }
      continue;
    }
    if (code[k] >= 0) {
      fail_at(column, fmt::format("two {} codes in one block", kGroupNames[k]));
    }
    code[k] = g;
    col[k] = column;
  }
  out.code = code;
  out.col = col;
  out.g53 = g53;
  return out;
}

// Words no code of the block uses are errors, as in LinuxCNC (a typo must not pass).
void Interpreter::check_unused(int group0, int dwell, int tool_length, bool comp_word) const {
  const bool moved = (block_.has_axis() || full_circle_) && group0 != 100 && group0 != 920 &&
                     group0 != 520 && group0 != 510 && group0 != 680;
  const bool cycle = moved && motion_ >= 730;
  const bool arc = moved && (motion_ == 20 || motion_ == 30);
  // Splines: G5 takes I J P Q, G5.1 I J, G5.2 P (a weight) and L (the order), its block with or
  // without axis words.
  const bool g5 = moved && motion_ == 50, g51 = moved && motion_ == 51;
  // Threading: G33 takes K, G33.1 I K, LinuxCNC's G76 I J K P Q R H E L.
  const bool g33 = moved && (motion_ == 330 || motion_ == 331);
  const bool g76 = moved && motion_ == 760 && !fanuc_;
  const bool g52 =
      motion_ == 52 && (moved || std::any_of(block_.g.begin(), block_.g.end(),
                                             [](const Block::Code& c) { return c.code10 == 52; }));
  if (block_.has_polar() && !moved && group0 != 280 && group0 != 300) {
    fail_at(block_.polar_col(), fmt::format("{} word with no motion to use it (polar coordinates "
                                            "place a G0/G1/G2/G3 or canned cycle's end)",
                                            block_.has_polar_r ? '@' : '^'));
  }
  const auto has_g = [&](int code10) {
    return std::any_of(block_.g.begin(), block_.g.end(),
                       [=](const Block::Code& c) { return c.code10 == code10; });
  };
  // G64 P- Q-: the path blending tolerance and the naive cam tolerance (no effect on the path).
  const bool g64 = has_g(640);
  // P of an extra coordinate system (G54.1, G154, Mach3's G59) and of Haas's G187 and G103; E
  // of G187; D of G96 (the largest spindle speed).
  const bool system_p = has_g(541) || has_g(1540) || (mach3_ && has_g(590));
  const bool haas_p = haas_ && (has_g(1870) || has_g(1030));
  const bool g96 = has_g(960);
  bool m61 = false;
  for (const auto& mc : block_.m) m61 = m61 || mc.code10 == 610;
  auto refuse = [&](char c, const char* users) {
    fail_at(block_.col(c), fmt::format("{} word with no {} to use it", upper(c), users));
  };
  // The M-codes that take words (LinuxCNC): M19 P R Q (spindle orientation), M50-M53 P
  // (override switches), M62-M65 P (digital outputs), M66 P|E L Q (wait for an input), M67/M68
  // E Q (analog outputs), user M-codes M100-M199 P Q (their arguments).
  bool m19 = false, m_p = false, m_q = false, m66 = false, m_e = false;
  for (const auto& mc : block_.m) {
    const int m = mc.code10;
    m19 = m19 || m == 190;
    m66 = m66 || m == 660;
    m_p = m_p || m == 190 || (m >= 500 && m <= 530) || (m >= 620 && m <= 660) || user_m_code(m);
    m_q = m_q || m == 190 || (m >= 660 && m <= 680) || user_m_code(m);
    m_e = m_e || (m >= 660 && m <= 680);
  }
  const bool q_cycle =
      cycle && (motion_ == 730 || motion_ == 830 || motion_ == 760 || (fanuc_ && motion_ == 870));
  if (block_.has('q') && !q_cycle && !m61 && !g64 && !m_q && !g5) {
    refuse('q', "G64, G73, G83, M19, M61, M66, M67, M68 or user M-code");
  }
  if (block_.has('e') && !m_e && !g76 && !(haas_ && has_g(1870))) {
    refuse('e', "G76, M66, M67 or M68");
  }
  const bool m98 = pending_m98_.has_value();
  // LinuxCNC takes no L with G74 (its check lists G73 and G76-G89).
  const bool l_cycle = cycle && (fanuc_ || motion_ != 740);
  if (block_.has('l') && !l_cycle && group0 != 100 && !m98 && !m66 && !g52) {
    refuse('l', "G10, M66 or canned cycle other than G74");
  }
  if (block_.has('r') && !arc && !cycle && group0 != 100 && !m19 && group0 != 680) {
    refuse('r', "G2/G3, canned cycle, G10 or M19");
  }
  const bool g87 = cycle && motion_ == 870 && !fanuc_;
  for (const char c : std::string_view("ijk")) {
    const bool thread = g76 || (g33 && c == 'k') || (moved && motion_ == 331 && c == 'i');
    if (block_.has(c) && !arc && !g87 && !((g5 || g51) && c != 'k') && !thread && group0 != 510) {
      refuse(c, "G2/G3, G5, G5.1, G33, G33.1, G76 or G87");
    }
  }
  if (block_.has('p') && !arc && !cycle && dwell < 0 && group0 != 100 && !m98 && !pending_m99_ &&
      !g64 && !m_p && !g5 && !g52 && group0 != 510 && !system_p && !haas_p) {
    refuse('p', "G2/G3, G4, G10, G64, canned cycle, M19, M50-M53, M62-M66 or user M-code");
  }
  if (block_.has('h') && tool_length != 430 && tool_length != 434 && !g76) {
    refuse('h', "G43 or G76");
  }
  // D alone: LinuxCNC refuses it; Sinumerik's "T1 D1" (its tool offset) is tolerated, as its
  // other words are, and Fanuc's D is an offset register.
  if (block_.has('d') && !comp_word && !g96 &&
      (opt_.dialect == Dialect::linuxcnc || opt_.dialect == Dialect::mach3) && !block_.has('t')) {
    refuse('d', "G41/G42 (or G41.1/G42.1) or G96");
  }
}

void Interpreter::unsupported_g(int g, std::uint32_t column) const {
  const std::string name = code_name('G', g);
  if (g >= 380 && g <= 385) fail_at(column, fmt::format("{} (probing) is not supported", name));
  if (g == 470 && haas_) {
    fail_at(column, "G47 (Haas's text engraving) is not read: its strokes are the control's font");
  }
  if (g == 70 || g == 80) {
    fail_at(column, fmt::format("{} is a lathe mode, not supported", name));
  }
  fail_at(column, fmt::format("unsupported G-code {}", name));
}

void Interpreter::save_modal(ModalSave& m) const {
  m.valid = true;
  m.plane = plane_;
  m.unit = unit_;
  m.absolute = absolute_;
  m.arc_absolute = arc_absolute_;
  m.feed_mode = feed_mode_;
  m.feed = feed_;
  m.speed = speed_;
  m.retract_r = retract_r_;
  m.system = system_;
}

void Interpreter::restore_modal(const ModalSave& m) {
  plane_ = m.plane;
  unit_ = m.unit;
  absolute_ = m.absolute;
  arc_absolute_ = m.arc_absolute;
  feed_mode_ = m.feed_mode;
  if (feed_ != m.feed) ++feed_events_;
  feed_ = m.feed;
  speed_ = m.speed;
  retract_r_ = m.retract_r;
  if (m.system != system_) select_system_n(m.system);
}

}  // namespace trochomill::gcode_detail
