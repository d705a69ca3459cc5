// The feeds of an NC program rewritten in place (gcode.hpp: rewrite_feeds). The program's text
// stays as it was except for F words and the moves split where the feed changes: every other
// word, comment, line, subroutine and loop is kept. A move is split only where its words are
// plain numbers of one block run once (a G1/G2/G3 of the program itself, at a feed per
// minute); a block run more than once (a loop, a subroutine of the program) takes the
// slowest feed any of its runs needs; everything else keeps its feed, and where the feed a
// kept move runs at would change (it takes the modal feed the rewritten blocks before it set),
// it gets an F word of its own, or, in a file the rewrite does not touch, the rewrite stops
// with a message naming it.
#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>

#include "ngc_lexer.hpp"
#include "trochomill/error.hpp"
#include "trochomill/gcode.hpp"
#include "trochomill/units.hpp"

namespace trochomill {
namespace {

// One word of a normalised line: its letter and the span [begin, end) of letter and value in
// the normalised text.
struct Word {
  char letter = 0;
  std::size_t begin = 0, end = 0;
};

// The end of the value starting at j of a normalised line (LinuxCNC's real_value: a number, a
// parameter, a bracketed expression or a unary function of one, signs before any of them).
std::size_t value_end(const std::string& s, std::size_t j) {
  auto bracket = [&](std::size_t k) {
    int depth = 0;
    for (; k < s.size(); ++k) {
      if (s[k] == '[') ++depth;
      if (s[k] == ']' && --depth == 0) return k + 1;
    }
    return s.size();
  };
  while (j < s.size() && (s[j] == '+' || s[j] == '-')) ++j;
  if (j >= s.size()) return j;
  if (s[j] == '[') return bracket(j);
  if (s[j] == '#') {
    ++j;
    if (j < s.size() && s[j] == '<') {
      const std::size_t e = s.find('>', j);
      return e == std::string::npos ? s.size() : e + 1;
    }
    return value_end(s, j);
  }
  if (s[j] >= 'a' && s[j] <= 'z') {  // a unary function: name[...] (atan[...]/[...])
    std::size_t k = j;
    while (k < s.size() && s[k] >= 'a' && s[k] <= 'z') ++k;
    if (k < s.size() && s[k] == '[') {
      const bool atan = s.compare(j, k - j, "atan") == 0;
      k = bracket(k);
      if (atan && k + 1 < s.size() && s[k] == '/' && s[k + 1] == '[') k = bracket(k + 1);
      return k;
    }
    return j;
  }
  while (j < s.size() && ((s[j] >= '0' && s[j] <= '9') || s[j] == '.')) ++j;
  return j;
}

// The words of a normalised block (parameter settings "#1=..." skipped).
std::vector<Word> words_of(const std::string& s) {
  std::vector<Word> w;
  std::size_t i = 0;
  while (i < s.size()) {
    const char c = s[i];
    if ((c >= 'a' && c <= 'z') || c == '@' || c == '^') {  // @ ^: LinuxCNC's polar words
      const std::size_t e = std::max(value_end(s, i + 1), i + 1);
      w.push_back({c, i, e});
      i = e;
    } else if (c == '#') {
      i = std::max(value_end(s, i), i + 1);
      if (i < s.size() && s[i] == '=') i = std::max(value_end(s, i + 1), i + 1);
    } else {
      ++i;
    }
  }
  return w;
}

// A number as the program's words write it: `decimals` places, trailing zeros trimmed but
// the point kept (a Fanuc control reads "X10" as 10 um on many machines), no "-0".
std::string number(double v, int decimals) {
  std::string t = fmt::format("{:.{}f}", v, decimals);
  if (t.find('.') != std::string::npos) {
    while (t.back() == '0') t.pop_back();
    if (t.back() == '.') t += '0';
  }
  if (t == "-0.0") t = "0.0";
  return t;
}

// A feed word's value: program units per minute, rounded down to the written places so the
// written feed never exceeds the scheduled one.
std::string feed_number(double mm_per_min, double unit_mm) {
  const int places = unit_mm == 1.0 ? 3 : 4;
  const double scale = std::pow(10.0, places);
  const double v = std::floor(mm_per_min / unit_mm * scale + 1e-6) / scale;
  std::string t = number(v, places);
  if (t.size() > 2 && t.compare(t.size() - 2, 2, ".0") == 0) t.resize(t.size() - 2);
  return t;
}

// Program coordinates (program units) of an output-frame point for a move's frame.
Vec3 to_program(const GcodeMove& m, const Vec3& p) {
  const Vec3 d = p - m.program_zero_mm;
  const double c = std::cos(m.program_turn_rad), s = std::sin(m.program_turn_rad);
  return Vec3(c * d.x() + s * d.y(), -s * d.x() + c * d.y(), d.z()) / m.unit_mm;
}

// Coordinate places a dialect's controls read: LinuxCNC parses doubles (9 places keep a split
// arc's centre, which the control moves onto the chord's bisector, within 1e-8 mm); Sinumerik
// 6; Fanuc and Haas (8 digits a word at most), Grbl (single precision) and Mach3 (its
// displays' 4) 4 in mm. Inch: one more.
}  // namespace

int rewrite_places(Dialect d, double unit_mm) {
  const int mm = d == Dialect::linuxcnc ? 9 : d == Dialect::sinumerik ? 6 : 4;
  return unit_mm == 1.0 ? mm : mm + 1;
}

namespace {

double rounded(double v, int places) {
  const double scale = std::pow(10.0, places);
  return std::round(v * scale) / scale;
}

// The words of one piece of a split move from `from` to `to` (output frame, mm) at `places`;
// the move's last piece (`last`) ends where the block ended, its words as precise as the
// dialect allows (a value the program wrote comes back as written). Incremental words are
// differences of the rounded positions from the move's start, so the pieces add up to the
// move's own increment (no drift along the pieces).
std::string piece_words(const GcodeMove& m, const Vec3& from, const Vec3& to, int places, bool last,
                        Dialect dialect) {
  const Vec3 a = to_program(m, from), b = to_program(m, to), s = to_program(m, m.start_mm);
  // A Fanuc word has at most 8 digits: the exact end only where it fits.
  auto end_number = [&](double v) {
    std::string t = number(v, 9);
    const auto digits =
        std::count_if(t.begin(), t.end(), [](char c) { return c >= '0' && c <= '9'; });
    return (dialect == Dialect::fanuc || dialect == Dialect::haas) && digits > 8 ? number(v, places)
                                                                                 : t;
  };
  std::string out;
  for (int k = 0; k < 3; ++k) {
    // Axes the move does not change are left out (their word would repeat the value).
    if (std::abs(b[k] - a[k]) <= 1e-12 * (1 + std::abs(b[k]))) continue;
    std::string w;
    if (!m.incremental) {
      w = last ? end_number(b[k]) : number(b[k], places);
    } else if (last) {
      w = end_number(rounded(b[k] - s[k], 9) - rounded(a[k] - s[k], places));
    } else {
      w = number(rounded(b[k] - s[k], places) - rounded(a[k] - s[k], places), places);
    }
    out += fmt::format(" {}{}", static_cast<char>('X' + k), w);
  }
  if (m.kind == GcodeMove::Kind::arc) {
    const Vec3 c = to_program(m, m.centre_mm);
    // The plane's two axes: G17 X/Y (I J), G18 Z/X (K I), G19 Y/Z (J K).
    const std::array<int, 2> axes = m.plane == 17   ? std::array<int, 2>{0, 1}
                                    : m.plane == 18 ? std::array<int, 2>{0, 2}
                                                    : std::array<int, 2>{1, 2};
    for (const int k : axes) {
      const double v = m.ijk_absolute ? c[k] : c[k] - a[k];
      out += fmt::format(" {}{}", static_cast<char>('I' + k), number(v, places));
    }
  }
  return out;
}

// A block of the program, with what the rewrite does to it.
struct Block {
  std::vector<std::size_t> moves;  // indices into the move list, in order
  bool rewritten = false;          // its feed is set by the rewrite (split or one feed)
  bool split = false;              // its move is split into pieces
  double feed = 0;                 // one feed: the slowest its runs need (mm/min)
  bool has_f = false;              // it has an F word (its own or added)
  bool add_f = false;              // an F word is added
  double kept_feed = std::numeric_limits<double>::quiet_NaN();  // a kept block's F (mm/min)
};

}  // namespace

FeedRewrite rewrite_feeds(std::string_view text, const std::vector<GcodeMove>& moves,
                          const std::vector<MoveFeeds>& feeds, Dialect dialect) {
  if (feeds.size() != moves.size()) {
    throw Error("rewrite_feeds: one MoveFeeds per move is needed");
  }
  FeedRewrite out;
  // Lines of the program (offsets of their starts).
  std::vector<std::size_t> starts{0};
  for (std::size_t i = 0; i < text.size(); ++i) {
    if (text[i] == '\n' && i + 1 < text.size()) starts.push_back(i + 1);
  }
  const std::string_view eol =
      text.find("\r\n") != std::string_view::npos ? std::string_view("\r\n") : "\n";
  auto line_text = [&](std::size_t line) {
    const std::size_t b = starts[line - 1];
    std::size_t e = text.find('\n', b);
    if (e == std::string_view::npos) e = text.size();
    if (e > b && text[e - 1] == '\r') --e;
    return text.substr(b, e - b);
  };

  // The program's blocks that moved, by line.
  std::map<std::size_t, Block> blocks;
  for (std::size_t i = 0; i < moves.size(); ++i) {
    if (moves[i].source == 0) blocks[moves[i].line].moves.push_back(i);
  }
  ngc::Line norm;
  for (auto& [line, b] : blocks) {
    if (line == 0 || line > starts.size()) {
      throw Error(fmt::format("rewrite_feeds: line {} is not in the program", line));
    }
    ngc::normalise(line_text(line), norm);
    for (const Word& w : words_of(norm.text)) b.has_f |= w.letter == 'f';
    // Rewritten: every move of the block is a plain feed move with new feeds.
    bool plain = true;
    double slowest = std::numeric_limits<double>::infinity();
    for (const std::size_t i : b.moves) {
      const GcodeMove& m = moves[i];
      plain &= m.plain && m.motion >= 1 && !feeds[i].feed_mm_per_min.empty();
      for (const double f : feeds[i].feed_mm_per_min) slowest = std::min(slowest, f);
    }
    if (!plain) continue;
    b.rewritten = true;
    b.feed = slowest;
    const GcodeMove& m = moves[b.moves.front()];
    b.split = b.moves.size() == 1 && feeds[b.moves.front()].feed_mm_per_min.size() > 1 &&
              (m.kind != GcodeMove::Kind::arc || std::abs(m.sweep_rad) <= 2 * kPi + 1e-9);
  }

  // The modal feed along the rewritten program, move by move: where a kept move would run at
  // another feed than it did, its block gets an F word of its own.
  constexpr double nan = std::numeric_limits<double>::quiet_NaN();
  double modal = nan;  // mm/min (G95: mm/rev); NaN: not known
  std::uint64_t events = 0;
  std::uint64_t last_run = std::numeric_limits<std::uint64_t>::max();
  auto differs = [](double a, double b) { return !(std::abs(a - b) <= 1e-9 * std::abs(b)); };
  for (std::size_t i = 0; i < moves.size(); ++i) {
    const GcodeMove& m = moves[i];
    Block* b = nullptr;
    if (m.source == 0) b = &blocks.at(m.line);
    // A block without motion set the feed (kept as it is): the original modal feed.
    if (m.feed_events_before > events) modal = m.feed_before;
    const bool first_of_run = m.block_run != last_run;
    last_run = m.block_run;
    if (first_of_run) {
      events = m.feed_events;
      if (b != nullptr && b->has_f) {
        modal =
            b->rewritten ? (b->split ? feeds[i].feed_mm_per_min.front() : b->feed) : m.feed_word;
      } else if (m.feed_events > m.feed_events_before) {
        modal = m.feed_word;  // a subroutine file's own F word
      }
    }
    if (m.motion == 0 || m.kind == GcodeMove::Kind::rapid || m.feed_mode == 93 || m.synchronized) {
      continue;  // no F of theirs (threading runs at the pitch times the spindle speed)
    }
    double want = m.feed_word;  // a kept move: its feed as it was
    if (b != nullptr && b->rewritten) want = b->split ? feeds[i].feed_mm_per_min.front() : b->feed;
    if (differs(modal, want)) {
      if (b == nullptr) {
        throw InputError(fmt::format(
            "{}:{}: this move of a called file runs at the feed in effect when it is called "
            "({:g} mm/min); optimize-feed rewrites only the program itself, where the feed "
            "before the call changes: give the block its own F word or bring the subroutine "
            "into the program",
            m.file, m.line, m.feed_word));
      }
      if (!b->rewritten) {
        if (!std::isnan(b->kept_feed) && differs(b->kept_feed, want)) {
          throw InputError(fmt::format(
              "{}:{}: this block runs at different modal feeds ({:g} and {:g}) and the "
              "rewritten feeds before it would change them; give it an F word of its own",
              m.file, m.line, b->kept_feed, want));
        }
        b->kept_feed = want;
      }
      b->has_f = b->add_f = true;
    }
    modal = want;
    if (b != nullptr && b->split) modal = feeds[i].feed_mm_per_min.back();
  }

  // The text, line by line.
  out.text.reserve(text.size() + text.size() / 4);
  std::size_t next = 1;
  auto copy_through = [&](std::size_t line) {  // lines next .. line - 1 as they are
    for (; next < line; ++next) {
      const std::size_t b = starts[next - 1];
      const std::size_t e = next < starts.size() ? starts[next] : text.size();
      out.text.append(text.substr(b, e - b));
    }
  };
  for (auto& [line, b] : blocks) {
    // Kept blocks stay as they are unless they get an F word; rewritten ones without an F
    // word and not split have nothing to change.
    if (!b.split && !b.add_f && !(b.rewritten && b.has_f)) continue;
    copy_through(line);
    const std::string_view raw = line_text(line);
    ngc::normalise(raw, norm);
    const std::vector<Word> words = words_of(norm.text);
    const GcodeMove& m = moves[b.moves.front()];
    const MoveFeeds& mf = feeds[b.moves.front()];
    // Edits on the raw line: word spans removed, words inserted after the last code character.
    std::vector<std::pair<std::size_t, std::size_t>> cut;  // raw [begin, end)
    auto raw_span = [&](const Word& w) {
      return std::pair<std::size_t, std::size_t>(norm.column[w.begin] - 1, norm.column[w.end - 1]);
    };
    std::string insert;
    const double first_feed = b.split       ? mf.feed_mm_per_min.front()
                              : b.rewritten ? b.feed
                                            : b.kept_feed;
    const std::string f_word = "F" + feed_number(first_feed, m.unit_mm);
    for (const Word& w : words) {
      // Split moves get X Y Z words: the polar words that placed the end go too.
      const bool coordinate = std::string_view("xyzijkrp@^").find(w.letter) != std::string::npos;
      // A replaced F word goes with the new words at the end: motion words, then F.
      if (w.letter == 'f' && b.rewritten) {
        cut.push_back(raw_span(w));
      } else if (b.split && coordinate) {
        cut.push_back(raw_span(w));
      }
    }
    const int places = rewrite_places(dialect, m.unit_mm);
    if (b.split) {
      insert += piece_words(m, m.start_mm, mf.ends_mm.front(), places, false, dialect);
    }
    if (b.has_f) insert += " " + f_word;
    std::string edited(raw);
    const std::size_t at = norm.text.empty() ? raw.size() : norm.column[norm.text.size() - 1];
    // Right to left, so earlier positions stay valid; the insertion point is after every cut.
    std::sort(cut.begin(), cut.end());
    edited.insert(at, insert);
    for (auto it = cut.rbegin(); it != cut.rend(); ++it) {
      // With the blanks before the word, so the line keeps one blank between words.
      std::size_t from = it->first;
      while (from > 0 && (edited[from - 1] == ' ' || edited[from - 1] == '\t')) --from;
      if (from == 0) from = it->first;
      edited.erase(from, it->second - from);
    }
    out.text += edited;
    out.text += eol;
    ++out.blocks_changed;
    if (b.split) {
      const char* g = m.motion == 1 ? "G1" : m.motion == 2 ? "G2" : "G3";
      for (std::size_t k = 1; k < mf.ends_mm.size(); ++k) {
        std::string piece = g + piece_words(m, mf.ends_mm[k - 1], mf.ends_mm[k], places,
                                            k + 1 == mf.ends_mm.size(), dialect);
        if (differs(mf.feed_mm_per_min[k - 1], mf.feed_mm_per_min[k])) {
          piece += " F" + feed_number(mf.feed_mm_per_min[k], m.unit_mm);
        }
        out.text += piece;
        out.text += eol;
        ++out.lines_added;
      }
    }
    ++next;
  }
  copy_through(starts.size() + 1);
  return out;
}

}  // namespace trochomill
