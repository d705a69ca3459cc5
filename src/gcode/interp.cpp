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
// This file is the driver: the program's lines read, messages, each line's block run in
// LinuxCNC's order; interp.hpp names the files of the other parts.
#include "interp.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <limits>
#include <string>
#include <string_view>
#include <utility>

#include "ngc_lexer.hpp"
#include "trochomill/error.hpp"
#include "trochomill/gcode.hpp"

namespace trochomill::gcode_detail {

Interpreter::Interpreter(std::string_view text, std::string_view name, const GcodeReadOptions& opt)
    : InterpState(opt) {
  Source main;
  main.text = text;
  main.name = std::string(name);
  sources_.push_back(std::move(main));
  params_.assign(o_numbers_ ? kMaxExtendedParameter : kMaxParameter, 0.0);
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
  bool percent_open = false, first = true, percent_closed = false;
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
      if (t == "%") {
        percent_closed = true;
        break;
      }
    }
    run_line(raw);
  }
  // LinuxCNC refuses a program that stops without M2, M30 or a closing '%'; a sender of
  // another control's programs runs it. Read to its last line, with a warning.
  if (!ended_ && !percent_closed && !o_numbers_ && (prog_.info.motion_blocks > 0 || !first)) {
    warn(
        "the program ends without M2, M30 or a closing %: LinuxCNC refuses it (\"File ended "
        "with no percent sign or program end\"); read to its last line");
  }
  if (frames_.size() > 1) {
    fail_at(0, fmt::format("the file ends inside subroutine o<{}> (no endsub reached)",
                           frames_.back().label));
  }
  comp_.dequeue();  // compensated moves still waiting run as they are
  prog_.info.lines = std::max(prog_.info.lines, main_lines_);
  for (const Source& src : sources_) prog_.source_files.push_back(src.name);
  // A program without motion (a setting, a probe-less macro, a tool change) is a program
  // LinuxCNC runs; what needs moves (analysis, simulation) says so where it needs them.
  if (prog_.path.empty() && prog_.summary.segments == 0) {
    prog_.info.warnings.push_back(
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
                           "(the limit is the reader's {})",
                           opt_.max_blocks, option_name("max_blocks")));
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
  if (o_numbers_) {
    if (i < s.size() && (s[i] == 'o' || s[i] == ':')) {
      // A program number: the start of a (sub)program; the rest of the line runs.
      std::size_t j = i + 1;
      while (j < s.size() && s[j] >= '0' && s[j] <= '9') ++j;
      if (j == i + 1) {
        fail(i, fmt::format("'{}' needs a program number after it", s[i] == ':' ? ':' : 'O'));
      }
      i = j;
    }
    if (fanuc_ && fanuc_statement(i)) return;
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
  set_numbered();
  for (const auto& p : block_.named) set_named(p.name, p.value, p.column);
  block_feed_events_ = feed_events_;
  block_feed_before_ = feed_;
  execute();
}

// ---- running the block, in LinuxCNC's order -----------------------------------------------

void Interpreter::execute() {
  pending_m98_.reset();
  pending_m97_ = false;
  pending_m99_ = false;
  for (const auto& gc : block_.g) {
    if (gc.code10 == 650) {
      macro_call(gc.column);
      return;
    }
  }
  check_words();
  xnext_ = xpos_;
  if (block_.has_extra()) note_extra_axes();
  const BlockCodes codes = group_codes();
  // Feed mode, F, S, T, M, then the G groups in LinuxCNC's order.
  set_feed_speed_tool(codes[kFeedMode]);
  bool stop = false, pause = false;
  run_m_codes(stop, pause);
  set_modes(codes);
  polar_words(codes);
  run_motion(codes);
  check_unused(codes[kGroup0], codes[kDwell], codes[kToolLength], codes[kComp] > 400);
  if (stop || pause) {
    comp_.flush_at_stop(block_.m.front().column);
    if (stop) comp_.turn_off();
  }
  if (stop) end_program();
  if (pending_m98_ && !ended_) subprogram_call();
  if (pending_m99_ && !ended_) subprogram_return();
}

// Fanuc's (and Haas's, Mach3's) polar coordinate command, G16 .. G15: in the XY plane a move's
// X is the distance from the program's zero and Y the angle from +X (degrees), read as
// LinuxCNC's @ and ^ words (the one left out the current point's; in G91 the angle adds to
// the current point's). Not in blocks whose X Y are not an end (G10, G28, G30, G52, G53, G92).
void Interpreter::polar_words(const BlockCodes& codes) {
  for (const auto& gc : block_.g) {
    if (gc.code10 == 150 || gc.code10 == 160) polar_mode_ = gc.code10 == 160;
  }
  if (!polar_mode_ || !(block_.has('x') || block_.has('y'))) return;
  const int group0 = codes[kGroup0];
  if (codes.g53 || group0 == 100 || group0 == 280 || group0 == 300 || group0 == 520 ||
      group0 == 920) {
    return;
  }
  const std::uint32_t col = block_.col(block_.has('x') ? 'x' : 'y');
  if (plane_ != Plane::xy)
    fail_at(col, "G16 (polar coordinates) is read in the XY plane (G17) only");
  if (!absolute_ && block_.has('x')) {
    fail_at(block_.col('x'),
            "G16 with the radius X in G91 (the current point as the polar centre) is not read: "
            "give the radius in G90");
  }
  if (block_.has('x')) {
    block_.has_polar_r = true;
    block_.polar_r = block_['x'];
    block_.polar_r_col = block_.col('x');
  }
  if (block_.has('y')) {
    block_.has_polar_a = true;
    block_.polar_a_deg = block_['y'];
    block_.polar_a_col = block_.col('y');
  }
  block_.present &= ~((1U << ('x' - 'a')) | (1U << ('y' - 'a')));
}

// Feed mode, F, S and T.
void Interpreter::set_feed_speed_tool(int feed_mode) {
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
  }
  // G96 D S (constant surface speed, at most D rpm) and G97 (S in rpm), LinuxCNC's group 14.
  const auto g96 = std::find_if(block_.g.begin(), block_.g.end(),
                                [](const Block::Code& c) { return c.code10 == 960; });
  const bool g97 = std::any_of(block_.g.begin(), block_.g.end(),
                               [](const Block::Code& c) { return c.code10 == 970; });
  if (g96 != block_.g.end()) {
    if (g97) fail_at(g96->column, "two spindle speed mode codes in one block");
    if (!block_.has('s')) fail_at(g96->column, "S word missing with G96");
    css_ = true;
    css_max_rpm_ = block_.has('d') ? std::abs(block_['d']) : 0.0;
  } else if (g97) {
    css_ = false;
  }
  if (block_.has('s') && !css_) {
    prog_.info.max_spindle_rpm = std::max(prog_.info.max_spindle_rpm, speed_);
  }
  if (block_.has('t')) {
    // 1e6: the bound of the tool table's T and of G41/G42's D, and well inside an int.
    if (block_['t'] < 0 || block_['t'] != std::floor(block_['t']) || block_['t'] > 1e6) {
      fail_at(block_.col('t'),
              fmt::format("tool number T{:.15g} must be a whole number 0 .. 1e6", block_['t']));
    }
    tool_selected_ = block_['t'];
  }
}

// The M codes: stop and pause set for the end of the block, M98/M99 noted for it.
// LinuxCNC's modal groups of M-codes (at most one code of each in a block, four codes in all):
// stops 4, I/O 5, tool change 6, spindle 7, coolant 8, override switches 9, user codes 10, and
// the modal state's save and restore M70-M73; -1 for the codes of no group (Fanuc's M98/M99).
namespace {
int m_group(int m) {
  switch (m) {
    case 0:
    case 10:
    case 20:
    case 300:
    case 600:
      return 4;
    case 60:
    case 610:
      return 6;
    case 30:
    case 40:
    case 50:
    case 190:
      return 7;
    case 70:
    case 80:
    case 90:
      return 8;
    default:
      break;
  }
  if (m >= 620 && m <= 680) return 5;
  if (m >= 480 && m <= 530) return 9;
  if (m >= 700 && m <= 730) return 11;
  if (m >= 1000 && m <= 1990) return 10;
  return -1;
}
}  // namespace

void Interpreter::check_m_codes() const {
  if (block_.m.size() > 4) {
    fail_at(block_.m[4].column, "more than four M-codes in one block (LinuxCNC's limit)");
  }
  for (std::size_t a = 0; a < block_.m.size(); ++a) {
    const int g = m_group(block_.m[a].code10);
    for (std::size_t b = 0; b < a && g >= 0; ++b) {
      if (m_group(block_.m[b].code10) == g) {
        fail_at(
            block_.m[a].column,
            fmt::format("{} and {} in one block: two M-codes of one modal group",
                        code_name('M', block_.m[b].code10), code_name('M', block_.m[a].code10)));
      }
    }
  }
}

void Interpreter::run_m_codes(bool& stop, bool& pause) {
  check_m_codes();
  // A word an M-code needs, whole and within [lo, hi].
  const auto whole_in = [&](char c, double lo, double hi) {
    return block_.has(c) && block_[c] == std::floor(block_[c]) && block_[c] >= lo &&
           block_[c] <= hi;
  };
  for (const auto& [m, column] : block_.m) {
    switch (m) {
      case 190:
        // Spindle orientation: the spindle stops at angle R (degrees), turning as P says, within
        // Q seconds; no motion of the axes.
        if (block_.has('p') && !whole_in('p', 0, 2)) {
          fail_at(block_.col('p'), "M19's P (the turn to the angle) must be 0, 1 or 2");
        }
        if (block_.has('r') && !(block_['r'] >= 0 && block_['r'] <= 360)) {
          fail_at(block_.col('r'), "M19's R (the angle) must be within 0 .. 360 degrees");
        }
        if (block_.has('q') && !(block_['q'] > 0)) {
          fail_at(block_.col('q'), "M19's Q (the time allowed, s) must be > 0");
        }
        spindle_on_ = false;
        spindle_dir_ = 0;
        break;
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
        comp_.refuse(column, "M6 (a tool change)");
        tool_loaded_ = tool_selected_;
        if (prog_.info.tool_changes.size() < 10000) {
          prog_.info.tool_changes.emplace_back(
              static_cast<int>(tool_loaded_),
              fmt::format("{}:{}", sources_[cur_.source].name, cur_.line_no));
        }
        break;
      case 70:
      case 80:
      case 90:
        break;  // coolant: queued with the compensated moves (LinuxCNC)
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
        comp_.refuse(column, fmt::format("{} (a motion output)", code_name('M', m)));
        if (m >= 620 && m <= 650 && !block_.has('p')) {
          fail_at(column, fmt::format("{} needs the output's number in P", code_name('M', m)));
        }
        if (m == 660) check_m66(column);
        if (m >= 670 && !(block_.has('e') && block_['e'] >= 0)) {
          fail_at(column, fmt::format("{} needs the analog output's number in E (>= 0)",
                                      code_name('M', m)));
        }
        break;
      case 130:
      case 140:
        // Fanuc machines' spindle-and-coolant codes (M13: M3 with coolant, M14: M4 with it);
        // not LinuxCNC's, and the machine maker's in the end: said, and read as such.
        if (!fanuc_) fail_at(column, fmt::format("unsupported M-code {}", code_name('M', m)));
        spindle_on_ = true;
        spindle_dir_ = m == 130 ? 1 : -1;
        warn(
            fmt::format("{}: read as {} with coolant on (most Fanuc machines; the machine "
                        "maker's code)",
                        code_name('M', m), m == 130 ? "M3" : "M4"));
        break;
      case 970:
        // Haas's local subprogram call, M97 P<block number> L<times>: read in the fanuc
        // dialect (on another control of the family M97 is the machine maker's).
        if (!fanuc_) fail_at(column, fmt::format("unsupported M-code {}", code_name('M', m)));
        if (!block_.has('p')) fail_at(column, "M97 needs the block number (N) in P");
        if (block_['p'] < 0 || block_['p'] != std::floor(block_['p']) || block_['p'] > 99999) {
          fail_at(block_.col('p'), "M97 P must be a block number 0 .. 99999");
        }
        {
          const double times = block_.has('l') ? block_['l'] : 1;
          if (times < 0 || times != std::floor(times) || times > 9999) {
            fail_at(column, "M97's repeat count L must be a whole number 0 .. 9999");
          }
          pending_m98_ = std::make_pair(block_['p'], times);
          pending_m97_ = true;
        }
        break;
      case 980: {
        if (!m98_) {
          fail_at(column, fmt::format("M98 is the subprogram call of Fanuc, LinuxCNC, Haas and "
                                      "Mach3, not of the {} dialect",
                                      to_string(opt_.dialect)));
        }
        if (!block_.has('p')) fail_at(column, "M98 needs the program number in P");
        double prog = block_['p'], times = block_.has('l') ? block_['l'] : 1;
        if (prog < 0 || prog != std::floor(prog) || prog > 99999999) {
          fail_at(block_.col('p'), "M98 P must be a program number");
        }
        // Fanuc's P<times 4 digits><program 4 digits>; Haas's programs have 5 digits.
        if (opt_.dialect == Dialect::fanuc && !block_.has('l') && prog > 9999) {
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
        if (!m98_) {
          fail_at(column, fmt::format("M99 is the subprogram return of Fanuc, LinuxCNC, Haas and "
                                      "Mach3, not of the {} dialect",
                                      to_string(opt_.dialect)));
        }
        pending_m99_ = true;
        m99_p_ = block_.has('p') ? block_['p'] : -1;
        break;
      case 610:
        if (!block_.has('q')) fail_at(column, "M61 needs the tool number in Q");
        if (block_['q'] < 0 || block_['q'] != std::floor(block_['q']) || block_['q'] > 1e6) {
          fail_at(block_.col('q'),
                  fmt::format("M61 Q{:.15g}: the tool number must be a whole number 0 .. 1e6",
                              block_['q']));
        }
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
        // In the main program there is no return to restore at: nothing to do (LinuxCNC).
        if (frames_.size() < 2) break;
        save_modal(frames_.back().restore_modal ? sub_saved_.back() : push_sub_saved());
        frames_.back().restore_modal = true;
        break;
      default:
        if (user_m_code(m)) {
          warn(fmt::format("{} (a user M-code) was ignored: it runs a program of the machine's",
                           code_name('M', m)));
          break;
        }
        // A Fanuc control's other M-codes below M100 are the machine maker's (clamps, doors,
        // chip conveyors, probes): they do not move the tool, and are said, not refused.
        if (fanuc_ && m >= 0 && m < 1000 && m % 10 == 0) {
          warn(
              fmt::format("{} (the machine maker's M-code on a Fanuc control) was ignored: it "
                          "does not move the tool here",
                          code_name('M', m)));
          break;
        }
        // Mach3 runs any other M-code as a macro of its profile (a script of the machine's
        // set-up: probing logs, tool changers): said, not refused.
        if (mach3_ && m >= 0 && m < 10000 && m % 10 == 0) {
          warn(
              fmt::format("{} (a macro of the Mach3 profile) was ignored: it does not move the "
                          "tool here",
                          code_name('M', m)));
          break;
        }
        fail_at(column, fmt::format("unsupported M-code {}", code_name('M', m)));
    }
  }
}

// G4's P, then the G groups that set a mode or an offset, in LinuxCNC's order: plane, units,
// cutter compensation, tool length, coordinate system, distance modes, retract mode, group 0.
void Interpreter::set_modes(const BlockCodes& codes) {
  const int plane = codes[kPlane], units = codes[kUnits], distance = codes[kDistance],
            arc_distance = codes[kArcDistance], tool_length = codes[kToolLength],
            system = codes[kSystem], retract = codes[kRetract], comp = codes[kComp],
            group0 = codes[kGroup0], dwell = codes[kDwell];
  const std::uint32_t group0_col = codes.col[kGroup0], comp_col = codes.col[kComp],
                      tool_length_col = codes.col[kToolLength], system_col = codes.col[kSystem];
  if (dwell >= 0 && !block_.has('p')) fail_at(block_.g.front().column, "G4 needs P (seconds)");
  if (plane >= 0) {
    if (plane != 170) comp_.refuse(block_.g.front().column, "a plane change (G18/G19)");
    plane_ = plane == 170 ? Plane::xy : plane == 180 ? Plane::zx : Plane::yz;
  }
  if (units >= 0) {
    unit_ = (units == 200 || units == 700 || units == 7000) ? 25.4 : 1.0;
    if (unit_ != 1.0) prog_.info.inch_units_seen = true;
  }
  if (comp == 400) {
    comp_.stop();
  } else if (comp >= 0) {
    comp_.start(comp, comp_col);
  }
  if (tool_length >= 0) {
    comp_.refuse(tool_length_col, "a tool length offset change (G43/G43.1/G49)");
    tool_length_offset(tool_length);
  }
  if (system >= 0) {
    comp_.refuse(system_col, "a coordinate system change (G54-G59.3)");
    select_system(system, system_col);
  }
  if (distance >= 0) absolute_ = distance == 900;
  if (arc_distance >= 0) arc_absolute_ = arc_distance == 901;
  if (retract >= 0) retract_r_ = retract == 990;
  if (codes.g50) {
    comp_.refuse(codes.g50_col, "G50");
    program_transform(500, codes.g50_col);
  }
  if (codes.g69) {
    comp_.refuse(codes.g69_col, "G69");
    program_transform(690, codes.g69_col);
  }
  if (group0 >= 0) {
    if (group0 != 100) {
      comp_.refuse(group0_col, fmt::format("{}", code_name('G', group0)));
    }
    non_modal(group0, group0_col);
  }
}

// The motion mode, then the move or the canned cycle of the block's axis words.
void Interpreter::run_motion(const BlockCodes& codes) {
  const int motion = codes[kMotion], group0 = codes[kGroup0];
  const std::uint32_t motion_col = codes.col[kMotion];
  const bool g53 = codes.g53;
  const int motion_before = motion_;
  if (motion >= 0) {
    if (motion == 800) {
      motion_ = -1;
      cycle_il_flag_ = false;
    } else {
      motion_ = motion;
    }
  }
  const bool axis_used_by_group0 = group0 == 100 || group0 == 280 || group0 == 300 ||
                                   group0 == 520 || group0 == 920 || group0 == 510 || group0 == 680;
  // G2/G3 with its centre and no end point: a full circle back to the start (LinuxCNC); an
  // R-form arc needs its end.
  const ArcData ax = plane_axes();
  const auto o1 = static_cast<char>('i' + ax.i1), o2 = static_cast<char>('i' + ax.i2);
  full_circle_ = motion >= 20 && motion <= 30 && !axis_used_by_group0 && !block_.has_axis() &&
                 !block_.has('r') && (block_.has(o1) || block_.has(o2));
  // G0 or G1 in a block without axis words: a move to where the tool is (LinuxCNC's canon
  // gets it; it has no length).
  const bool in_place = (motion == 0 || motion == 10) && !g53 && !block_.has_axis();
  if (g53 && fanuc_ && motion != 0 && motion != 10) {
    // Fanuc and Haas: G53 moves at rapid, whatever the motion mode (without axis words not
    // at all); the mode stays.
    if (block_.has_axis() && !axis_used_by_group0) {
      const int mode = motion_;
      motion_ = 0;
      ++prog_.info.motion_blocks;
      move(true, block_.g.front().column);
      motion_ = mode;
    }
  } else if ((block_.has_axis() || full_circle_ || in_place) && !axis_used_by_group0) {
    if (motion == 800) {
      fail_at(motion_col, "G80 cancels the motion mode: it cannot take axis words");
    }
    if (motion_ < 0) {
      const char first = block_.has('x') ? 'x' : block_.has('y') ? 'y' : 'z';
      fail_at(block_.col(first), "axis words without a motion mode (G0/G1/G2/G3)");
    }
    ++prog_.info.motion_blocks;
    if (motion_ >= 730 && block_.has_extra() && (fanuc_ || motion_ != 760)) {
      // LinuxCNC: "Cannot put an A in canned cycle" (and B, C, U, V, W).
      for (const char c : kExtraAxes) {
        if (block_.has(c)) {
          fail_at(block_.col(c), fmt::format("Cannot put {} {} in canned cycle",
                                             c == 'a' || c == 'u' ? "an" : "a", upper(c)));
        }
      }
    }
    if (motion_ == 330 || motion_ == 331 || (motion_ == 760 && !fanuc_)) {
      thread(motion >= 0 ? motion_col
                         : block_.col(block_.has('x')   ? 'x'
                                      : block_.has('y') ? 'y'
                                                        : 'z'));
    } else if (motion_ == 50 || motion_ == 51) {
      spline(motion >= 0 ? motion_col : block_.col(block_.has('x') ? 'x' : 'y'));
    } else if (motion_ == 52) {
      nurbs_point(motion_before != 52, motion >= 0 ? motion_col : 0);
    } else if (motion_ >= 730) {
      comp_.refuse(motion >= 0        ? motion_col
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
  } else if (motion == 52 && !axis_used_by_group0) {
    // G5.2 without a control point: the start's weight P and the order L.
    nurbs_point(motion_before != 52, motion_col);
  } else if (motion >= 20 && motion <= 30 && !axis_used_by_group0) {
    fail_at(motion_col, "arc without an end point");
  } else if (g53) {
    // LinuxCNC: G53 with G0 or G1 in the block and no axis words moves to where the tool
    // already is (a move of no length); without G0 or G1 it is refused.
    if (motion != 0 && motion != 10) {
      fail_at(block_.g.front().column,
              "G53 needs G0 or G1 in its block (LinuxCNC: \"Must use g0 or g1 with g53\")");
    }
    ++prog_.info.motion_blocks;
    move(true, motion_col);
  }
  if (motion_ < 730) {
    cycle_il_flag_ = false;
    cycle_motion_ = -1;  // the next cycle is a first one (its Z and R again)
  }
}

// M66: wait for the digital input P or the analog input E, in the way L (0 returns at once),
// at most Q seconds; the wait does not move the tool.
void Interpreter::check_m66(std::uint32_t column) const {
  const bool p = block_.has('p') && block_['p'] >= 0, e = block_.has('e') && block_['e'] >= 0;
  if (!p && !e) fail_at(column, "M66 needs the input to wait for: P (digital) or E (analog)");
  if (p && e) fail_at(column, "M66 waits for a digital (P) or an analog (E) input, not both");
  const double l = block_.has('l') ? block_['l'] : 0;
  if (l < 0 || l != std::floor(l)) {
    fail_at(block_.col('l'), "M66's L (the way to wait) must be a whole number >= 0");
  }
  if (l != 0 && e) {
    fail_at(block_.col('l'), "M66 reads an analog input (E) only with L0 (return at once)");
  }
  if (l != 0 && !(block_.has('q') && block_['q'] > 0)) {
    fail_at(column, "M66 with L other than 0 (return at once) needs a time Q > 0 s to wait");
  }
}

GcodeProgram interpret_gcode(std::string_view text, std::string_view source_name,
                             const GcodeReadOptions& options) {
  return Interpreter(text, source_name, options).run();
}

}  // namespace trochomill::gcode_detail
