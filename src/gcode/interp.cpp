// The RS274/NGC interpreter: LinuxCNC's language (its documentation and its interpreter's
// behaviour are the reference: docs/gcode.md) turned into trochomill's ToolPath.
//  - values: numbers, #n and #<name> parameters, [expressions] with LinuxCNC's precedence
//    (** > * / MOD > + - > EQ NE GT GE LT LE > AND OR XOR), unary functions;
//  - parameter settings take effect after the whole line is read, before it runs;
//  - O-words: sub/endsub/call/return with arguments and values, if/elseif/else/endif,
//    while/endwhile, do/while, repeat/endrepeat, break/continue, subroutine files;
//  - the block runs in LinuxCNC's order (feed mode, F, S, T, M, then the G groups, stop);
//  - modal state: planes, units, distance modes, feed modes, work offsets (G54-G59.3, G10 L2
//    and L20), G92/G52, tool length (G43/G43.1/G49), G28/G30/G53, canned cycles G73 G81-G86
//    G89 with G98/G99 and L.
// Positions are kept in program coordinates (mm) as the interpreter keeps them; each move is
// turned into the output frame (the job's work coordinate system) when it is emitted.
#include "interp.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <initializer_list>
#include <limits>
#include <optional>
#include <string>
#include <string_view>
#include <system_error>
#include <utility>
#include <vector>

#include "ngc_lexer.hpp"
#include "trochomill/error.hpp"
#include "trochomill/gcode.hpp"
#include "trochomill/io.hpp"

namespace trochomill::gcode_detail {

Interpreter::Interpreter(std::string_view text, std::string_view name, const GcodeReadOptions& opt)
    : InterpState(opt) {
  Source main;
  main.text = text;
  main.name = std::string(name);
  sources_.push_back(std::move(main));
  params_.assign(kMaxParameter, 0.0);
  if (fanuc_) {
    // Fanuc's local and common variables start vacant.
    const double vacant = std::numeric_limits<double>::quiet_NaN();
    params_[0] = vacant;
    for (std::size_t p = 1; p <= 33; ++p) params_[p] = vacant;
    for (std::size_t p = 100; p <= 199; ++p) params_[p] = vacant;
    for (std::size_t p = 500; p <= 999; ++p) params_[p] = vacant;
  }
  frames_.emplace_back();
  init_offsets();
}

GcodeProgram Interpreter::run() {
  if (!opt_.tool_table.empty()) {
    for (const auto& [n, t] : read_tool_table(opt_.tool_table)) tools_[n] = t;
  }
  if (opt_.keep_path) {
    // About a segment a line: room up front spares the copies of a growing path.
    const std::string_view t = sources_[0].text;
    prog_.path.reserve(static_cast<std::size_t>(std::count(t.begin(), t.end(), '\n')) + 1);
  }
  // A program between '%' lines: the first non-blank line '%' opens it, the next one ends it.
  bool percent_open = false, first = true;
  while (!ended_) {
    std::string_view raw;
    if (!next_line(raw)) break;
    if (first) {
      std::string_view t = raw;
      while (!t.empty() && (t.front() == ' ' || t.front() == '\t')) t.remove_prefix(1);
      while (!t.empty() && (t.back() == ' ' || t.back() == '\t' || t.back() == '\r')) {
        t.remove_suffix(1);
      }
      if (t.empty()) continue;
      first = false;
      if (t == "%") {
        percent_open = true;
        continue;
      }
    } else if (percent_open && cur_.source == 0) {
      std::string_view t = raw;
      while (!t.empty() && (t.back() == ' ' || t.back() == '\t' || t.back() == '\r')) {
        t.remove_suffix(1);
      }
      if (t == "%") break;
    }
    run_line(raw);
  }
  if (frames_.size() > 1) {
    fail_at(0, fmt::format("the file ends inside subroutine o<{}> (no endsub reached)",
                           frames_.back().label));
  }
  dequeue();  // compensated moves still waiting run as they are
  prog_.info.lines = std::max(prog_.info.lines, main_lines_);
  if (prog_.path.empty() && prog_.summary.segments == 0) {
    throw InputError(
        fmt::format("{}: the program has no motion (no G0/G1/G2/G3 moves)", sources_[0].name));
  }
  return std::move(prog_);
}

// ---- reading lines ------------------------------------------------------------------------

bool Interpreter::next_line(std::string_view& raw) {
  Source& src = sources_[cur_.source];
  if (cur_.offset >= src.text.size()) {
    if (cur_.source == 0) return false;
    // A subroutine file ran out: only an error when its subroutine has not returned.
    fail_at(0, fmt::format("the file ends inside subroutine o<{}> (no endsub reached)",
                           frames_.back().label));
  }
  std::size_t end = src.text.find('\n', cur_.offset);
  if (end == std::string_view::npos) end = src.text.size();
  raw = src.text.substr(cur_.offset, end - cur_.offset);
  line_offset_ = cur_.offset;
  cur_.offset = end == src.text.size() ? end : end + 1;
  ++cur_.line_no;
  if (cur_.source == 0) main_lines_ = std::max(main_lines_, cur_.line_no);
  return true;
}

void Interpreter::fail_at(std::uint32_t column, const std::string& what) const {
  const Source& src = sources_[cur_.source];
  if (column == 0) throw InputError(fmt::format("{}:{}: {}", src.name, cur_.line_no, what));
  throw InputError(fmt::format("{}:{}:{}: {}", src.name, cur_.line_no, column, what));
}

void Interpreter::warn(const std::string& what) {
  if (prog_.info.warnings.size() < 100) {
    prog_.info.warnings.push_back(
        fmt::format("{}:{}: {}", sources_[cur_.source].name, cur_.line_no, what));
  }
}

void Interpreter::count_block() {
  ++prog_.info.blocks_executed;
  if (prog_.info.blocks_executed > opt_.max_blocks) {
    fail_at(0, fmt::format("stopped after {} blocks: does the program loop without end? "
                           "(the limit is the reader's max_blocks, check-gcode --max-blocks)",
                           opt_.max_blocks));
  }
  if ((prog_.info.blocks_executed & 0xffff) == 0 && opt_.cancel && opt_.cancel()) {
    throw Interrupted("reading the NC program was interrupted");
  }
}

// ---- one line -----------------------------------------------------------------------------

void Interpreter::run_line(std::string_view raw) {
  ngc::normalise(raw, line_);
  if (line_.error_column != 0) fail_at(line_.error_column, line_.error);
  const std::string& s = line_.text;
  std::size_t i = 0;
  if (i < s.size() && s[i] == '/') ++i;  // block delete: the switch is off, the block runs
  if (i < s.size() && s[i] == 'n') {     // line number
    std::size_t j = i + 1;
    while (j < s.size() && ((s[j] >= '0' && s[j] <= '9') || s[j] == '.')) ++j;
    if (j == i + 1) fail(i, "'N' needs a line number after it");
    i = j;
  }
  if (fanuc_) {
    if (i < s.size() && (s[i] == 'o' || s[i] == ':')) {
      // A program number: the start of a (sub)program; the rest of the line runs.
      std::size_t j = i + 1;
      while (j < s.size() && s[j] >= '0' && s[j] <= '9') ++j;
      if (j == i + 1) fail(i, "'O' needs a program number after it");
      i = j;
    }
    if (fanuc_statement(i)) return;
  } else if (i < s.size() && (s[i] == 'o' || s[i] == ':')) {
    if (line_.comment_column != 0 && line_.comment_column < col_of(i)) {
      fail(i, "an O-word must start its line (a comment comes before it)");
    }
    if (o_statement(i)) return;
  }
  if (i >= s.size()) return;  // blank or comment only: (MSG, ...) and the like do not move
  count_block();
  read_block(i);
  // Parameter settings take effect after the whole line is read, before it runs.
  for (const auto& p : block_.numbered) params_[static_cast<std::size_t>(p.index)] = p.value;
  for (const auto& p : block_.named) set_named(p.name, p.value, p.column);
  block_feed_events_ = feed_events_;
  block_feed_before_ = feed_;
  execute();
}

// ---- the block ----------------------------------------------------------------------------

void Interpreter::execute() {
  pending_m98_.reset();
  pending_m99_ = false;
  for (const auto& gc : block_.g) {
    if (gc.code10 == 650) {
      macro_call(gc.column);
      return;
    }
  }
  // Words no milling program of ours uses: refused by name.
  for (const char c : std::string_view("abcuvw")) {
    if (block_.has(c)) {
      fail_at(block_.col(c),
              fmt::format("rotary axis {} is not supported (3-axis programs only)", upper(c)));
    }
  }
  for (const char c : std::string_view("xyzijkrq")) {
    if (block_.has(c)) check_range(c);
  }
  // G codes by modal group (two of one group are an error).
  std::array<int, kGroups> code;
  code.fill(-1);
  std::array<std::uint32_t, kGroups> col{};
  bool g53 = false;
  for (const auto& [g, column] : block_.g) {
    if (g == 530) {
      g53 = true;
      continue;
    }
    if (g == 610 || g == 611 || g == 640) {
      refuse_with_comp(column, fmt::format("{} (path control mode)", code_name('G', g)));
      continue;  // path blending: no effect on the path
    }
    if (g == 970 || g == 150 || g == 160) continue;  // constant spindle speed, polar off
    // G76 is Fanuc's fine boring cycle; LinuxCNC's is lathe threading.
    if (g == 760 && !fanuc_) unsupported_g(g, column);
    const auto it = std::find_if(kGroupOf.begin(), kGroupOf.end(),
                                 [g = g](const GroupOf& e) { return e.code10 == g; });
    if (it == kGroupOf.end()) unsupported_g(g, column);
    const auto k = static_cast<std::size_t>(it->group);
    if (it->group == kRetract) {
      refuse_with_comp(column, fmt::format("{} (canned cycle retract mode)", code_name('G', g)));
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
  const int motion = code[kMotion], group0 = code[kGroup0], plane = code[kPlane],
            units = code[kUnits], distance = code[kDistance], arc_distance = code[kArcDistance],
            feed_mode = code[kFeedMode], tool_length = code[kToolLength], system = code[kSystem],
            retract = code[kRetract], comp = code[kComp], dwell = code[kDwell];
  const std::uint32_t motion_col = col[kMotion], group0_col = col[kGroup0], comp_col = col[kComp],
                      tool_length_col = col[kToolLength], system_col = col[kSystem];
  // Feed mode, F, S, T, M, then the G groups in LinuxCNC's order.
  if (feed_mode >= 0) {
    feed_mode_ = feed_mode == 930   ? FeedMode::inverse_time
                 : feed_mode == 950 ? FeedMode::per_rev
                                    : FeedMode::per_minute;
  }
  inverse_f_ = -1;
  if (block_.has('f')) {
    if (block_['f'] < 0) fail_at(block_.col('f'), "feed F must be >= 0");
    if (feed_mode_ == FeedMode::inverse_time) {
      inverse_f_ = block_['f'];
    } else {
      feed_ = block_['f'] * unit_;  // a unit change later keeps the feed (as LinuxCNC)
      feed_given_ = true;
      ++feed_events_;
    }
  }
  if (block_.has('s')) {
    if (block_['s'] < 0) fail_at(block_.col('s'), "spindle speed S must be >= 0");
    speed_ = block_['s'];
    prog_.info.max_spindle_rpm = std::max(prog_.info.max_spindle_rpm, speed_);
  }
  if (block_.has('t')) {
    if (block_['t'] < 0 || block_['t'] != std::floor(block_['t'])) {
      fail_at(block_.col('t'), "tool number T must be a whole number >= 0");
    }
    tool_selected_ = block_['t'];
  }
  bool stop = false, pause = false;
  for (const auto& [m, column] : block_.m) {
    switch (m) {
      case 0:
      case 10:
      case 600:
        pause = true;  // the program goes on when the operator resumes
        break;
      case 20:
      case 300:
        stop = true;
        break;
      case 30:
      case 40:
        spindle_on_ = true;
        spindle_dir_ = m == 30 ? 1 : -1;
        break;
      case 50:
        spindle_on_ = false;
        spindle_dir_ = 0;
        break;
      case 60:
        refuse_with_comp(column, "M6 (a tool change)");
        tool_loaded_ = tool_selected_;
        break;
      case 70:
      case 80:
      case 90:
      case 480:
      case 490:
      case 500:
      case 510:
      case 520:
      case 530:
      case 620:
      case 630:
      case 640:
      case 650:
      case 660:
      case 670:
      case 680:
        // Outputs wait for motion to stop, which a compensated path cannot (LinuxCNC).
        refuse_with_comp(column, fmt::format("{} (a motion output)", code_name('M', m)));
        break;
      case 980: {
        if (!fanuc_) {
          fail_at(column,
                  "M98 is Fanuc's subprogram call: read the program with the fanuc "
                  "dialect, or call an o-word subroutine");
        }
        if (!block_.has('p')) fail_at(column, "M98 needs the program number in P");
        double prog = block_['p'], times = block_.has('l') ? block_['l'] : 1;
        if (prog < 0 || prog != std::floor(prog) || prog > 99999999) {
          fail_at(block_.col('p'), "M98 P must be a program number");
        }
        if (!block_.has('l') && prog > 9999) {  // P<times 4 digits><program 4 digits>
          times = std::floor(prog / 10000);
          prog = std::fmod(prog, 10000);
        }
        if (times < 0 || times != std::floor(times) || times > 9999) {
          fail_at(column, "M98's repeat count L must be a whole number 0 .. 9999");
        }
        pending_m98_ = std::make_pair(prog, times);
        break;
      }
      case 990:
        if (!fanuc_) {
          fail_at(column,
                  "M99 is Fanuc's subprogram return: read the program with the fanuc "
                  "dialect, or end an o-word subroutine with endsub");
        }
        pending_m99_ = true;
        m99_p_ = block_.has('p') ? block_['p'] : -1;
        break;
      case 610:
        if (!block_.has('q')) fail_at(column, "M61 needs the tool number in Q");
        tool_loaded_ = block_['q'];
        break;
      case 700:
        save_modal(saved_);
        break;
      case 710:
        saved_.valid = false;
        break;
      case 720:
        if (!saved_.valid) fail_at(column, "M72 without a state saved by M70");
        restore_modal(saved_);
        break;
      case 730:
        if (frames_.size() < 2) fail_at(column, "M73 is for subroutines (it restores at return)");
        save_modal(frames_.back().restore_modal ? sub_saved_.back() : push_sub_saved());
        frames_.back().restore_modal = true;
        break;
      default:
        if (m >= 1000 && m <= 1990 && m % 10 == 0) {
          warn(fmt::format("{} (a user M-code) was ignored: it runs a program of the machine's",
                           code_name('M', m)));
          break;
        }
        fail_at(column, fmt::format("unsupported M-code {}", code_name('M', m)));
    }
  }
  if (dwell >= 0 && !block_.has('p')) fail_at(block_.g.front().column, "G4 needs P (seconds)");
  if (plane >= 0) {
    if (plane != 170) refuse_with_comp(block_.g.front().column, "a plane change (G18/G19)");
    plane_ = plane == 170 ? Plane::xy : plane == 180 ? Plane::zx : Plane::yz;
  }
  if (units >= 0) {
    unit_ = (units == 200 || units == 700 || units == 7000) ? 25.4 : 1.0;
    if (unit_ != 1.0) prog_.info.inch_units_seen = true;
  }
  if (comp == 400) {
    comp_stop();
  } else if (comp >= 0) {
    comp_start(comp, comp_col);
  }
  if (tool_length >= 0) {
    refuse_with_comp(tool_length_col, "a tool length offset change (G43/G43.1/G49)");
    tool_length_offset(tool_length);
  }
  if (system >= 0) {
    refuse_with_comp(system_col, "a coordinate system change (G54-G59.3)");
    select_system(system);
  }
  if (distance >= 0) absolute_ = distance == 900;
  if (arc_distance >= 0) arc_absolute_ = arc_distance == 901;
  if (retract >= 0) retract_r_ = retract == 990;
  if (group0 >= 0) {
    if (group0 != 100) {
      refuse_with_comp(group0_col, fmt::format("{}", code_name('G', group0)));
    }
    non_modal(group0, group0_col);
  }
  if (motion >= 0) {
    if (motion == 800) {
      motion_ = -1;
      cycle_il_flag_ = false;
    } else {
      motion_ = motion;
    }
  }
  const bool axis_used_by_group0 =
      group0 == 100 || group0 == 280 || group0 == 300 || group0 == 520 || group0 == 920;
  if (block_.has_axis() && !axis_used_by_group0) {
    if (motion == 800) {
      fail_at(motion_col, "G80 cancels the motion mode: it cannot take axis words");
    }
    if (motion_ < 0) {
      const char first = block_.has('x') ? 'x' : block_.has('y') ? 'y' : 'z';
      fail_at(block_.col(first), "axis words without a motion mode (G0/G1/G2/G3)");
    }
    ++prog_.info.motion_blocks;
    if (motion_ >= 730) {
      refuse_with_comp(motion >= 0        ? motion_col
                       : block_.g.empty() ? 0
                                          : block_.g.front().column,
                       "a canned cycle");
      canned_cycle(motion_, motion >= 0 ? motion_col
                                        : block_.col(block_.has('x')   ? 'x'
                                                     : block_.has('y') ? 'y'
                                                                       : 'z'));
    } else {
      move(g53, motion >= 0 ? motion_col
                            : block_.col(block_.has('x')   ? 'x'
                                         : block_.has('y') ? 'y'
                                                           : 'z'));
    }
  } else if (motion >= 20 && motion <= 30 && !axis_used_by_group0) {
    fail_at(motion_col, "arc without an end point");
  } else if (g53) {
    fail_at(block_.g.front().column, "G53 needs axis words (a move in machine coordinates)");
  }
  if (motion_ < 730) {
    cycle_il_flag_ = false;
    cycle_motion_ = -1;  // the next cycle is a first one (its Z and R again)
  }
  check_unused(group0, dwell, tool_length, comp > 400);
  if (stop || pause) {
    comp_flush_at_stop(block_.m.front().column);
    if (stop) comp_side_ = CompSide::off, comp_first_ = true;
  }
  if (stop) end_program();
  if (pending_m98_ && !ended_) subprogram_call();
  if (pending_m99_ && !ended_) subprogram_return();
}

// ---- O-words ------------------------------------------------------------------------------

// At 'o' (or ':'): an O-word statement (true) or a Fanuc/plain program number (false, the
// rest of the line is a block).
bool Interpreter::o_statement(std::size_t i) {
  const std::string& s = line_.text;
  const std::size_t at = i;
  ++i;
  std::string label;
  bool computed = false;
  if (i < s.size() && s[i] == '<') {
    label = read_name(i);
  } else if (i < s.size() && s[i] == '[') {
    const double v = read_expression(i);
    label = fmt::format("{:g}", v);
    computed = true;
  } else {
    const std::size_t j0 = i;
    while (i < s.size() && s[i] >= '0' && s[i] <= '9') ++i;
    if (i == j0) fail(at, "'O' needs a number or <name> after it");
    label = s.substr(j0, i - j0);
    // Strip leading zeros: o0100 and o100 are one label.
    const std::size_t nz = label.find_first_not_of('0');
    label = nz == std::string::npos ? "0" : label.substr(nz);
  }
  const std::size_t kw_at = i;
  std::size_t j = i;
  while (j < s.size() && s[j] >= 'a' && s[j] <= 'z') ++j;
  const std::string_view kw = std::string_view(s).substr(i, j - i);
  OKind kind = OKind::none;
  for (const OKeyword& k : kOKeywords) {
    if (kw == k.name) kind = k.kind;
  }
  if (kind == OKind::none) {
    if (kw.empty() && (j >= s.size() || s[at] == ':')) return true;  // program number "O1234"
    if (kw.empty() && s[at] == 'o') {
      // "O1000 G0 X1": a program number before a block (Fanuc): the block runs.
      line_.text.erase(0, j);
      line_.column.erase(line_.column.begin(),
                         line_.column.begin() + static_cast<std::ptrdiff_t>(j));
      run_after_program_number();
      return true;
    }
    fail(kw_at, fmt::format("unknown O-word keyword '{}' (sub endsub call return if elseif "
                            "else endif while endwhile do repeat endrepeat break continue)",
                            kw));
  }
  // The statements that jump by label are found by the index of O-word lines, which knows
  // written labels only: a computed label calls, and ':' (Fanuc's program number) is no
  // statement.
  if (s[at] == ':') {
    fail(at, "':' starts a program number (Fanuc's O); an O-word statement starts with O");
  }
  if (computed && kind != OKind::call) {
    fail(at, fmt::format("a computed O label (o[...]) is for call only, not {}", kw));
  }
  i = j;
  count_block();
  o_word(kind, label, i, at);
  return true;
}

void Interpreter::run_after_program_number() {
  std::size_t i = 0;
  if (line_.text.empty()) return;
  count_block();
  read_block(i);
  for (const auto& p : block_.numbered) params_[static_cast<std::size_t>(p.index)] = p.value;
  for (const auto& p : block_.named) set_named(p.name, p.value, p.column);
  execute();
}

// An optional [condition] / [value] after a keyword.
std::optional<double> Interpreter::o_value(std::size_t& i) {
  if (i >= line_.text.size()) return std::nullopt;
  if (line_.text[i] != '[') {
    fail(i, fmt::format("expected [expression] here, found {}", ngc::shown(line_.text[i])));
  }
  return read_expression(i);
}

double Interpreter::o_required(std::size_t& i, std::string_view what) {
  if (i >= line_.text.size()) fail(i, fmt::format("{} needs [expression]", what));
  return *o_value(i);
}

void Interpreter::o_end(std::size_t i) {
  if (i < line_.text.size()) {
    fail(i, fmt::format("unexpected {} after the O-word", ngc::shown(line_.text[i])));
  }
}

// The O-word lines of a source (built once).
void Interpreter::index(Source& src) {
  if (src.indexed) return;
  src.indexed = true;
  ngc::Line l;
  std::size_t off = 0, no = 0;
  const std::string_view t = src.text;
  while (off < t.size()) {
    std::size_t end = t.find('\n', off);
    if (end == std::string_view::npos) end = t.size();
    ++no;
    const std::string_view raw = t.substr(off, end - off);
    if (may_start_with(raw, "oOnN")) {
      ngc::normalise(raw, l);
      const std::string& s = l.text;
      std::size_t i = past_line_number(s);
      if (l.error_column == 0 && i < s.size() && s[i] == 'o') {
        OLine ol;
        ol.offset = off;
        ol.line_no = no;
        ++i;
        if (i < s.size() && s[i] == '<') {
          const std::size_t close = s.find('>', i);
          if (close != std::string::npos) {
            ol.label = s.substr(i + 1, close - i - 1);
            i = close + 1;
          }
        } else {
          const std::size_t j0 = i;
          while (i < s.size() && s[i] >= '0' && s[i] <= '9') ++i;
          ol.label = s.substr(j0, i - j0);
          const std::size_t nz = ol.label.find_first_not_of('0');
          ol.label = nz == std::string::npos ? "0" : ol.label.substr(nz);
        }
        std::size_t j = i;
        while (j < s.size() && s[j] >= 'a' && s[j] <= 'z') ++j;
        const std::string_view kw = std::string_view(s).substr(i, j - i);
        for (const OKeyword& k : kOKeywords) {
          if (kw == k.name) ol.kind = k.kind;
        }
        if (ol.kind != OKind::none && !ol.label.empty()) src.olines.push_back(std::move(ol));
      }
    }
    off = end == t.size() ? end : end + 1;
  }
}

// The index in the running source's O-lines of the line just read.
std::size_t Interpreter::this_oline() {
  Source& src = sources_[cur_.source];
  index(src);
  const auto it = std::lower_bound(src.olines.begin(), src.olines.end(), line_offset_,
                                   [](const OLine& o, std::size_t off) { return o.offset < off; });
  if (it == src.olines.end() || it->offset != line_offset_) {
    // The index reads lines as the interpreter does; a line it missed is a reader bug.
    throw Error(
        fmt::format("{}:{}: this O-word line is not in the reader's index (a bug of "
                    "trochomill's: please report it with the program)",
                    src.name, cur_.line_no));
  }
  return static_cast<std::size_t>(it - src.olines.begin());
}

// The next O-line after `from` with this label and one of the kinds; fails naming `what`.
std::size_t Interpreter::find_forward(std::size_t from, const std::string& label,
                                      std::initializer_list<OKind> kinds, std::string_view what,
                                      std::size_t at) {
  const Source& src = sources_[cur_.source];
  for (std::size_t k = from + 1; k < src.olines.size(); ++k) {
    const OLine& o = src.olines[k];
    if (o.label != label) continue;
    if (std::find(kinds.begin(), kinds.end(), o.kind) != kinds.end()) return k;
  }
  fail(at, fmt::format("o{} has no matching {} below it", show_label(label), what));
}

std::string Interpreter::show_label(const std::string& label) {
  const bool number = !label.empty() && std::all_of(label.begin(), label.end(),
                                                    [](char c) { return c >= '0' && c <= '9'; });
  return number ? label : "<" + label + ">";
}

// Continue reading at O-line k of the running source (that line itself, or the one after).
void Interpreter::jump(std::size_t k, bool after) {
  const Source& src = sources_[cur_.source];
  const OLine& o = src.olines[k];
  if (!after) {
    cur_.offset = o.offset;
    cur_.line_no = o.line_no - 1;
    return;
  }
  const std::size_t end = src.text.find('\n', o.offset);
  cur_.offset = end == std::string_view::npos ? src.text.size() : end + 1;
  cur_.line_no = o.line_no;
}

// Opens an if or loop of the running frame.
Control& Interpreter::open_control(OKind kind, const std::string& label, const Cursor& start) {
  Control ctl;
  ctl.kind = kind;
  ctl.label = label;
  ctl.start = start;
  frames_.back().controls.push_back(ctl);
  return frames_.back().controls.back();
}

// The open `kind` labelled `label`, or an error: "o<label> <what> without its <opener>".
Control& Interpreter::open_of(OKind kind, const std::string& label, std::string_view what,
                              std::string_view opener, std::size_t at) {
  Control* ctl = find_control(label);
  if (ctl == nullptr || ctl->kind != kind) {
    fail(at, fmt::format("o{} {} without its {}", show_label(label), what, opener));
  }
  return *ctl;
}

Control* Interpreter::find_control(const std::string& label) {
  auto& cs = frames_.back().controls;
  for (auto it = cs.rbegin(); it != cs.rend(); ++it) {
    if (it->label == label) return &*it;
  }
  return nullptr;
}

void Interpreter::pop_to(const std::string& label) {
  auto& cs = frames_.back().controls;
  while (!cs.empty() && cs.back().label != label) cs.pop_back();
  if (!cs.empty()) cs.pop_back();
}

void Interpreter::o_word(OKind kind, const std::string& label, std::size_t i, std::size_t at) {
  switch (kind) {
    case OKind::sub: {
      o_end(i);
      // A definition met in the flow: skip its body.
      const std::size_t k = this_oline();
      jump(find_forward(k, label, {OKind::endsub}, "endsub", at), true);
      return;
    }
    case OKind::endsub:
    case OKind::ret: {
      const std::optional<double> v = o_value(i);
      o_end(i);
      if (frames_.size() < 2 || frames_.back().label != label) {
        if (kind == OKind::endsub && frames_.size() < 2) {
          fail(at, fmt::format("o{} endsub without its sub", show_label(label)));
        }
        fail(at,
             fmt::format("o{} {} outside subroutine o{}", show_label(label),
                         kind == OKind::ret ? "return" : "endsub",
                         show_label(frames_.back().label.empty() ? label : frames_.back().label)));
      }
      value_returned_ = v.has_value();
      value_ = v.value_or(0.0);
      return_from_sub();
      return;
    }
    case OKind::call:
      call(label, i, at);
      return;
    case OKind::if_: {
      const double c = o_required(i, "if");
      o_end(i);
      open_control(OKind::if_, label, cur_).taken = c != 0;
      if (c == 0) {
        const std::size_t k = this_oline();
        jump(find_forward(k, label, {OKind::elseif, OKind::else_, OKind::endif},
                          "elseif, else or endif", at),
             false);
      }
      return;
    }
    case OKind::elseif:
    case OKind::else_: {
      Control* ctl =
          &open_of(OKind::if_, label, kind == OKind::else_ ? "else" : "elseif", "if", at);
      const std::size_t k = this_oline();
      if (ctl->taken) {
        jump(find_forward(k, label, {OKind::endif}, "endif", at), false);
        return;
      }
      if (kind == OKind::else_) {
        o_end(i);
        ctl->taken = true;
        return;
      }
      const double c = o_required(i, "elseif");
      o_end(i);
      if (c != 0) {
        ctl->taken = true;
      } else {
        jump(find_forward(k, label, {OKind::elseif, OKind::else_, OKind::endif},
                          "elseif, else or endif", at),
             false);
      }
      return;
    }
    case OKind::endif: {
      o_end(i);
      (void)open_of(OKind::if_, label, "endif", "if", at);
      pop_to(label);
      return;
    }
    case OKind::while_: {
      Control* open = find_control(label);
      if (open != nullptr && open->kind == OKind::do_) {
        // The end of a do loop.
        const double c = o_required(i, "while");
        o_end(i);
        if (c != 0) {
          cur_ = open->start;
        } else {
          pop_to(label);
        }
        return;
      }
      const double c = o_required(i, "while");
      o_end(i);
      const bool here = open != nullptr && open->kind == OKind::while_ &&
                        open->start.offset == line_offset_ && open->start.source == cur_.source;
      if (c != 0) {
        if (!here) {
          open_control(OKind::while_, label, {cur_.source, line_offset_, cur_.line_no - 1});
        }
        return;
      }
      if (here) pop_to(label);
      const std::size_t k = this_oline();
      jump(find_forward(k, label, {OKind::endwhile}, "endwhile", at), true);
      return;
    }
    case OKind::endwhile: {
      o_end(i);
      cur_ = open_of(OKind::while_, label, "endwhile", "while", at).start;  // its condition decides
      return;
    }
    case OKind::do_: {
      o_end(i);
      open_control(OKind::do_, label, cur_);
      return;
    }
    case OKind::repeat: {
      const double n = o_required(i, "repeat");
      o_end(i);
      if (n >= 1) {
        open_control(OKind::repeat, label, cur_).remaining = std::floor(n);
        return;
      }
      const std::size_t k = this_oline();
      jump(find_forward(k, label, {OKind::endrepeat}, "endrepeat", at), true);
      return;
    }
    case OKind::endrepeat: {
      o_end(i);
      end_repeat_pass(open_of(OKind::repeat, label, "endrepeat", "repeat", at), label);
      return;
    }
    case OKind::brk:
    case OKind::cont: {
      o_end(i);
      Control* ctl = find_control(label);
      if (ctl == nullptr || (ctl->kind != OKind::while_ && ctl->kind != OKind::do_)) {
        fail(at, fmt::format("o{} {} outside a while or do loop o{} (LinuxCNC's break and "
                             "continue work in those, not in repeat)",
                             show_label(label), kind == OKind::brk ? "break" : "continue",
                             show_label(label)));
      }
      const std::size_t k = this_oline();
      if (kind == OKind::brk) {
        const OKind closing = ctl->kind == OKind::while_ ? OKind::endwhile
                              : ctl->kind == OKind::do_  ? OKind::while_
                                                         : OKind::endrepeat;
        const std::size_t e = find_forward(k, label, {closing}, "loop end", at);
        pop_to(label);
        jump(e, true);
      } else if (ctl->kind == OKind::while_) {
        cur_ = ctl->start;
      } else if (ctl->kind == OKind::do_) {
        jump(find_forward(k, label, {OKind::while_}, "while", at), false);
      } else {
        end_repeat_pass(*ctl, label);
      }
      return;
    }
    case OKind::none:
      break;
  }
}

void Interpreter::end_repeat_pass(Control& ctl, const std::string& label) {
  ctl.remaining -= 1;
  if (ctl.remaining >= 1) {
    cur_ = ctl.start;
    return;
  }
  // Done: continue after the endrepeat.
  const std::size_t k = this_oline();
  const Source& src = sources_[cur_.source];
  std::size_t e = k;
  if (src.olines[k].kind != OKind::endrepeat) {
    e = find_forward(k, label, {OKind::endrepeat}, "endrepeat", 0);
  }
  pop_to(label);
  jump(e, true);
}

void Interpreter::call(const std::string& label, std::size_t i, std::size_t at) {
  // Arguments: [expr] [expr] ... into #1 .. #30.
  std::array<double, 31> args{};
  int n = 0;
  while (i < line_.text.size()) {
    if (line_.text[i] != '[') {
      fail(i, fmt::format("a call's arguments are [expressions], found {}",
                          ngc::shown(line_.text[i])));
    }
    if (n == 30) fail(i, "more than 30 arguments");
    args[static_cast<std::size_t>(++n)] = read_expression(i);
  }
  if (static_cast<int>(frames_.size()) > opt_.max_call_depth) {
    fail(at, fmt::format("subroutine calls nested deeper than {} (recursion without end?)",
                         opt_.max_call_depth));
  }
  const auto [src, k] = find_sub(label, at);
  Frame f;
  f.label = label;
  f.ret = cur_;
  for (std::size_t p = 1; p <= 30; ++p) {
    f.saved_locals[p] = params_[p];
    params_[p] = args[p];
  }
  frames_.push_back(std::move(f));
  cur_.source = src;
  jump(k, true);
}

void Interpreter::return_from_sub() {
  Frame& f = frames_.back();
  if (f.new_locals) {
    for (std::size_t p = 1; p <= (fanuc_ ? 33U : 30U); ++p) params_[p] = f.saved_locals[p];
  }
  const bool restore = f.restore_modal;
  cur_ = f.ret;
  frames_.pop_back();
  if (restore) {
    restore_modal(sub_saved_.back());
    sub_saved_.pop_back();
  }
}

// The source and O-line of `o<label> sub`: the running file, then the loaded ones, then
// label.ngc on the search path.
std::pair<std::size_t, std::size_t> Interpreter::find_sub(const std::string& label,
                                                          std::size_t at) {
  auto in = [&](std::size_t s) -> std::optional<std::size_t> {
    index(sources_[s]);
    const auto& ol = sources_[s].olines;
    for (std::size_t k = 0; k < ol.size(); ++k) {
      if (ol[k].kind == OKind::sub && ol[k].label == label) return k;
    }
    return std::nullopt;
  };
  if (auto k = in(cur_.source)) return {cur_.source, *k};
  for (std::size_t s = 0; s < sources_.size(); ++s) {
    if (auto k = in(s)) return {s, *k};
  }
  const bool number =
      std::all_of(label.begin(), label.end(), [](char c) { return c >= '0' && c <= '9'; });
  std::vector<std::filesystem::path> dirs;
  const std::filesystem::path main(sources_[0].name);
  if (main.has_parent_path()) {
    dirs.push_back(main.parent_path());
  } else {
    dirs.emplace_back(".");
  }
  dirs.insert(dirs.end(), opt_.include_dirs.begin(), opt_.include_dirs.end());
  if (!number && label.find('/') == std::string::npos) {
    for (const auto& d : dirs) {
      const std::filesystem::path file = d / (label + ".ngc");
      std::error_code ec;
      if (!std::filesystem::is_regular_file(file, ec)) continue;
      Source s;
      s.owned = read_text_file(file);
      s.name = file.string();
      sources_.push_back(std::move(s));
      Source& added = sources_.back();
      added.text = added.owned;
      if (auto k = in(sources_.size() - 1)) return {sources_.size() - 1, *k};
      fail(at, fmt::format("{} does not define o<{}> sub", file.string(), label));
    }
  }
  std::string where;
  for (const auto& d : dirs) where += (where.empty() ? "" : ", ") + d.string();
  fail(at, fmt::format("subroutine o{} is not defined in the program{}", show_label(label),
                       number ? "" : fmt::format(" nor found as {}.ngc in {}", label, where)));
}

GcodeProgram interpret_gcode(std::string_view text, std::string_view source_name,
                             const GcodeReadOptions& options) {
  return Interpreter(text, source_name, options).run();
}

}  // namespace trochomill::gcode_detail
