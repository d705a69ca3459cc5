// O-words: sub/endsub/call/return with arguments and values, if/elseif/else/endif,
// while/endwhile, do/while, repeat/endrepeat, break/continue, subroutine files; and the index
// of a file's O-word lines they jump by.
#include <fmt/format.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstddef>
#include <filesystem>
#include <initializer_list>
#include <optional>
#include <string>
#include <string_view>
#include <system_error>
#include <utility>
#include <vector>

#include "interp.hpp"
#include "ngc_lexer.hpp"
#include "trochomill/error.hpp"
#include "trochomill/gcode.hpp"
#include "trochomill/io.hpp"

namespace trochomill::gcode_detail {

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
  set_numbered();
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
      // A return inside a subroutine returns from it whatever its label (LinuxCNC's
      // retval.ngc returns by an if's number); an endsub must close its own sub.
      const bool in_sub = frames_.size() >= 2;
      if (!in_sub || (kind == OKind::endsub && frames_.back().label != label)) {
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

}  // namespace trochomill::gcode_detail
