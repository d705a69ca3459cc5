// Fanuc Macro B: GOTO, IF [..] GOTO / THEN, WHILE [..] DO m .. END m, G65 macro calls, M98/M99
// subprograms and the O<n> programs they call.
#include <fmt/format.h>

#include <algorithm>
#include <array>
#include <charconv>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <limits>
#include <optional>
#include <string>
#include <string_view>
#include <system_error>
#include <utility>
#include <vector>

#include "interp.hpp"
#include "ngc_lexer.hpp"
#include "trochomill/gcode.hpp"
#include "trochomill/io.hpp"

namespace trochomill::gcode_detail {

// GOTO, IF [..] GOTO / THEN, WHILE (or WH) [..] DO m, DO m, END m at i: true when the line was
// one.
bool Interpreter::fanuc_statement(std::size_t i) {
  const std::string& s = line_.text;
  const std::string_view rest = std::string_view(s).substr(std::min(i, s.size()));
  auto starts = [&](std::string_view w) { return rest.substr(0, w.size()) == w; };
  auto digit_at = [&](std::size_t k) {
    return k < rest.size() && rest[k] >= '0' && rest[k] <= '9';
  };
  const std::size_t at = i;
  if (starts("goto")) {
    count_block();
    i += 4;
    const double n = read_value(i);
    fanuc_end(i);
    goto_label(n, at);
    return true;
  }
  if (starts("if[")) {
    count_block();
    i += 2;
    const double c = zero_if_vacant(read_expression(i));
    const std::string_view after = std::string_view(s).substr(i);
    if (after.substr(0, 4) == "goto") {
      i += 4;
      const double n = read_value(i);
      fanuc_end(i);
      if (c != 0) goto_label(n, at);
      return true;
    }
    // THEN, or (Haas) a setting right after the condition.
    if (after.substr(0, 4) == "then" || (haas_ && after.substr(0, 1) == "#")) {
      if (after.substr(0, 4) == "then") i += 4;
      read_block(i);
      const bool block = block_.present != 0 || !block_.g.empty() || !block_.m.empty();
      if (block && haas_) {
        // Haas: THEN runs a whole block (an M97 call, a move) where the condition holds.
        if (c != 0) {
          count_block();
          set_numbered();
          for (const auto& p : block_.named) set_named(p.name, p.value, p.column);
          block_feed_events_ = feed_events_;
          block_feed_before_ = feed_;
          execute();
        }
        return true;
      }
      if (block || block_.numbered.empty()) {
        fail(i, "IF [..] THEN takes a variable assignment (#1 = ...)");
      }
      if (c != 0) set_numbered();  // an alarm (#3000) only where the condition holds
      return true;
    }
    fail(i, "IF [condition] is followed by GOTO n or THEN #i = value");
  }
  // WHILE, or WH as the 30i series abbreviates it.
  if (starts("while[") || starts("wh[")) {
    count_block();
    i += starts("while[") ? 5 : 2;
    const double c = zero_if_vacant(read_expression(i));
    if (std::string_view(s).substr(i, 2) != "do") fail(i, "WHILE [condition] DO m: DO is missing");
    i += 2;
    const std::string label = loop_id(i);
    Control* open = find_control(label);
    const bool here = open != nullptr && open->kind == OKind::while_ &&
                      open->start.offset == line_offset_ && open->start.source == cur_.source;
    if (c != 0) {
      if (!here) open_control(OKind::while_, label, {cur_.source, line_offset_, cur_.line_no - 1});
      return true;
    }
    if (here) pop_to(label);
    skip_past_end(label, at);
    return true;
  }
  if (starts("do") && digit_at(2)) {
    count_block();
    i += 2;
    open_control(OKind::do_, loop_id(i), cur_);
    return true;
  }
  if (starts("end") && digit_at(3)) {
    count_block();
    i += 3;
    const std::string label = loop_id(i);
    Control* ctl = find_control(label);
    if (ctl == nullptr) fail(at, fmt::format("END {} without its WHILE .. DO {}", label, label));
    cur_ = ctl->start;
    return true;
  }
  return false;
}

void Interpreter::fanuc_end(std::size_t i) const {
  if (i < line_.text.size()) {
    fail(i, fmt::format("unexpected {} after the statement", ngc::shown(line_.text[i])));
  }
}

// The m of DO m / END m (1 .. 3 on a Fanuc; any whole number here).
std::string Interpreter::loop_id(std::size_t& i) {
  const std::size_t j0 = i;
  while (i < line_.text.size() && line_.text[i] >= '0' && line_.text[i] <= '9') ++i;
  if (i == j0) fail(i, "DO and END need their loop number (DO 1 .. END 1)");
  std::string id = line_.text.substr(j0, i - j0);
  fanuc_end(i);
  return id;
}

// After a false WHILE: on after its END m.
void Interpreter::skip_past_end(const std::string& label, std::size_t at) {
  const Source& src = sources_[cur_.source];
  ngc::Line l;
  std::size_t off = cur_.offset, no = cur_.line_no;
  while (off < src.text.size()) {
    std::size_t end = src.text.find('\n', off);
    if (end == std::string_view::npos) end = src.text.size();
    ++no;
    ngc::normalise(src.text.substr(off, end - off), l);
    const std::string& t = l.text;
    const std::size_t k = past_line_number(t);
    off = end == src.text.size() ? end : end + 1;
    if (t.compare(k, std::string::npos, "end" + label) == 0) {
      cur_.offset = off;
      cur_.line_no = no;
      return;
    }
  }
  fail(at, fmt::format("WHILE .. DO {} has no END {} below it", label, label));
}

// GOTO n: the block numbered N n, searched forward from here, then from the file's start.
void Interpreter::goto_label(double n, std::size_t at, const char* what) {
  if (std::isnan(n) || n < 0 || n != std::floor(n) || n > 99999) {
    fail(at, fmt::format("{} needs a sequence number 0 .. 99999", what));
  }
  const Source& src = sources_[cur_.source];
  ngc::Line l;
  for (int pass = 0; pass < 2; ++pass) {
    std::size_t off = pass == 0 ? cur_.offset : 0, no = pass == 0 ? cur_.line_no : 0;
    const std::size_t stop = pass == 0 ? src.text.size() : cur_.offset;
    while (off < stop) {
      std::size_t end = src.text.find('\n', off);
      if (end == std::string_view::npos) end = src.text.size();
      ++no;
      const std::string_view raw = src.text.substr(off, end - off);
      if (may_start_with(raw, "nN")) {
        ngc::normalise(raw, l);
        std::size_t k = l.text.empty() || l.text[0] != '/' ? 0 : 1;
        if (k < l.text.size() && l.text[k] == 'n') {
          double v = 0;
          const char* b = l.text.data() + k + 1;
          auto [ptr, ec] =
              std::from_chars(b, l.text.data() + l.text.size(), v, std::chars_format::fixed);
          if (ec == std::errc() && ptr != b && v == n) {
            cur_.offset = off;
            cur_.line_no = no - 1;
            return;
          }
        }
      }
      off = end == src.text.size() ? end : end + 1;
    }
  }
  fail(at, fmt::format("{} {:g}: no block N{:g} in {}", what, n, n, src.name));
}

// G65 P<program> L<times> with arguments: a call with its own local variables #1 .. #33.
// Fanuc's argument specification I: A B C I J K D E F H M Q R S T U V W X Y Z are #1 .. #26
// (#1 2 3 4 5 6 7 8 9 11 13 17 18 19 20 21 22 23 24 25 26); specification II: A B C are
// #1 .. #3 and up to ten sets of I J K #4 .. #33, set n's I J K at #(3n + 1) .. #(3n + 3). The
// two mix, the type of each word by its order: a set's I, J and K come in that order, and an
// I, J or K not after the one before in I J K order begins the next set. Where two words
// give one variable the later one holds (I2 after I1 and a D both give #7).
void Interpreter::macro_call(std::uint32_t column) {
  if (!fanuc_)
    fail_at(column, "G65 is Fanuc's macro call: read the program with the fanuc dialect");
  if (block_.g.size() > 1 || !block_.m.empty()) {
    fail_at(column, "G65 takes its arguments only: no other G or M code in its block");
  }
  if (!block_.has('p')) fail_at(column, "G65 needs the program number in P");
  static constexpr std::array<std::pair<char, int>, 21> kArgs{
      {{'a', 1},  {'b', 2},  {'c', 3},  {'i', 4},  {'j', 5},  {'k', 6},  {'d', 7},
       {'e', 8},  {'f', 9},  {'h', 11}, {'m', 13}, {'q', 17}, {'r', 18}, {'s', 19},
       {'t', 20}, {'u', 21}, {'v', 22}, {'w', 23}, {'x', 24}, {'y', 25}, {'z', 26}}};
  std::array<double, 34> args;
  args.fill(std::numeric_limits<double>::quiet_NaN());
  for (const auto& [c, n] : kArgs) {
    const bool after = std::any_of(block_.arguments.begin(), block_.arguments.end(),
                                   [c = c](const Block::Argument& a) { return a.letter == c; });
    if (block_.has(c) && !after) {
      fail_at(block_.col(c),
              fmt::format("{} before G65: its arguments come after it (Fanuc)", upper(c)));
    }
  }
  int set = 0, last = -1;  // the I J K set and the last of its letters (0 I, 1 J, 2 K)
  for (const Block::Argument& a : block_.arguments) {
    if (a.letter == 'i' || a.letter == 'j' || a.letter == 'k') {
      const int order = a.letter - 'i';
      if (last >= 0 && order <= last) ++set;
      if (set > 9) {
        fail_at(a.column, "G65 takes at most ten sets of I J K (argument specification II)");
      }
      last = order;
      args[static_cast<std::size_t>(4 + 3 * set + order)] = a.value;
      continue;
    }
    const auto it = std::find_if(kArgs.begin(), kArgs.end(),
                                 [&](const auto& e) { return e.first == a.letter; });
    if (it == kArgs.end()) {
      fail_at(a.column,
              fmt::format("{} is not an argument of G65 (A B C D E F H I J K M Q R S T U V W X "
                          "Y Z)",
                          upper(a.letter)));
    }
    args[static_cast<std::size_t>(it->second)] = a.value;
  }
  const double times = block_.has('l') ? block_['l'] : 1;
  if (times < 0 || times != std::floor(times) || times > 9999) {
    fail_at(block_.col('l'), "G65's repeat count L must be a whole number 0 .. 9999");
  }
  if (times == 0) return;
  Frame f = program_frame(block_['p'], column);
  f.new_locals = true;
  f.repeats = times;
  for (std::size_t p = 1; p <= 33; ++p) {
    f.saved_locals[p] = params_[p];
    params_[p] = args[p];
  }
  enter(std::move(f));
}

void Interpreter::subprogram_call() {
  const auto [prog, times] = *pending_m98_;
  if (times == 0) return;
  if (pending_m97_) {
    // Haas's M97: the subprogram starts at block N<P> of this program (searched as GOTO is)
    // and returns at M99, with the caller's local variables.
    Frame f;
    f.label = fmt::format("N{:g}", prog);
    f.ret = cur_;
    f.new_locals = false;
    f.repeats = times;
    const Cursor back = cur_;
    goto_label(prog, line_.text.find('p'), "M97 P");
    f.start = cur_;
    cur_ = back;
    enter(std::move(f));
    return;
  }
  Frame f = program_frame(prog, block_.col('p'));
  f.new_locals = false;  // M98: the caller's local variables
  f.repeats = times;
  enter(std::move(f));
}

void Interpreter::enter(Frame f) {
  if (static_cast<int>(frames_.size()) > opt_.max_call_depth) {
    fail_at(0, fmt::format("subprogram calls nested deeper than {} (recursion without end?)",
                           opt_.max_call_depth));
  }
  const Cursor start = f.start;
  frames_.push_back(std::move(f));
  cur_ = start;
}

void Interpreter::subprogram_return() {
  if (frames_.size() < 2) {
    warn("M99 in the main program repeats it on the machine: it was read once");
    end_program();
    return;
  }
  Frame& f = frames_.back();
  if (f.repeats > 1) {
    f.repeats -= 1;
    cur_ = f.start;
    f.controls.clear();
    return;
  }
  const double p = m99_p_;
  return_from_sub();
  if (p >= 0) goto_label(p, 0);
}

// Every "O<n>" line of a source: where its program's first line starts.
void Interpreter::index_programs(Source& src) {
  src.programs.emplace();
  const std::string_view t = src.text;
  ngc::Line l;
  std::size_t off = 0, no = 0;
  while (off < t.size()) {
    std::size_t end = t.find('\n', off);
    if (end == std::string_view::npos) end = t.size();
    ++no;
    const std::string_view raw = t.substr(off, end - off);
    off = end == t.size() ? end : end + 1;
    if (!may_start_with(raw, "oO:")) continue;
    ngc::normalise(raw, l);
    if (l.text.size() < 2) continue;
    long v = 0;
    auto [ptr, ec] = std::from_chars(l.text.data() + 1, l.text.data() + l.text.size(), v);
    if (ec == std::errc() && ptr != l.text.data() + 1)
      src.programs->emplace(v, std::make_pair(off, no));
  }
}

// The frame of a call to program O<n>: in the loaded files, else a file O<n> (O0010,
// O10, with .nc, .ngc or none) in the program's folder or the include folders.
Frame Interpreter::program_frame(double n, std::uint32_t column) {
  if (n < 0 || n != std::floor(n) || n > 99999999) {
    fail_at(column, fmt::format("P{:g} is not a program number", n));
  }
  const auto number = static_cast<long>(n);
  auto find_in = [&](std::size_t si) -> std::optional<Cursor> {
    Source& src = sources_[si];
    if (!src.programs) index_programs(src);
    const auto it = src.programs->find(number);
    if (it == src.programs->end()) return std::nullopt;
    return Cursor{si, it->second.first, it->second.second};
  };
  Frame f;
  // LinuxCNC's M98 runs its o<n> subroutines too: their endsub names n.
  f.label = opt_.dialect == Dialect::linuxcnc ? fmt::format("{}", number)
                                              : fmt::format("O{:04d}", number);
  f.ret = cur_;
  for (std::size_t si = 0; si < sources_.size(); ++si) {
    if (auto c = find_in(si)) {
      // LinuxCNC's M98 calls a bare O<n> only: an "o<n> sub" is called with o<n> call.
      if (opt_.dialect == Dialect::linuxcnc) {
        const std::string_view t = sources_[si].text;
        const std::size_t end = c->offset == 0 ? 0 : c->offset - 1;
        const std::size_t begin = t.rfind('\n', end == 0 ? 0 : end - 1);
        ngc::Line l;
        ngc::normalise(t.substr(begin == std::string_view::npos ? 0 : begin + 1,
                                end - (begin == std::string_view::npos ? 0 : begin + 1)),
                       l);
        std::size_t k = 1;
        while (k < l.text.size() && l.text[k] >= '0' && l.text[k] <= '9') ++k;
        if (l.text.compare(k, 3, "sub") == 0) {
          fail_at(column, "'O.... sub' subroutine must be called with 'O.... call' (LinuxCNC)");
        }
      }
      f.start = *c;
      return f;
    }
  }
  std::vector<std::filesystem::path> dirs;
  const std::filesystem::path main(sources_[0].name);
  dirs.push_back(main.has_parent_path() ? main.parent_path() : std::filesystem::path("."));
  dirs.insert(dirs.end(), opt_.include_dirs.begin(), opt_.include_dirs.end());
  for (const auto& d : dirs) {
    // Fanuc's and Haas's names (O0010, O10, o10), LinuxCNC's subroutine file (10.ngc).
    for (const std::string& stem : {fmt::format("O{:04d}", number), fmt::format("O{:05d}", number),
                                    fmt::format("O{}", number), fmt::format("o{:04d}", number),
                                    fmt::format("o{}", number), fmt::format("{}", number)}) {
      for (const char* ext : {"", ".nc", ".ngc", ".NC", ".cnc", ".tap"}) {
        const std::filesystem::path file = d / (stem + ext);
        std::error_code ec;
        if (!std::filesystem::is_regular_file(file, ec)) continue;
        Source src;
        src.owned = read_text_file(file);
        src.name = file.string();
        sources_.push_back(std::move(src));
        sources_.back().text = sources_.back().owned;
        if (auto c = find_in(sources_.size() - 1)) {
          f.start = *c;
          return f;
        }
        f.start = Cursor{sources_.size() - 1, 0, 0};  // a file of the program's body alone
        return f;
      }
    }
  }
  fail_at(column, fmt::format("program O{:04d} is not in the program nor a file O{:04d}(.nc) "
                              "in its folder or the include folders",
                              number, number));
}

}  // namespace trochomill::gcode_detail
