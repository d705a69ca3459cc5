// The RS274/NGC interpreter's data types (private to src/gcode): its limits, the O-word
// keywords, the modal groups of G codes, the files it reads and where it reads in them, the
// frames of subroutine calls and their open ifs and loops, one block's words, an arc of the
// plane; and the small helpers every part of the interpreter uses. interp.hpp has the
// interpreter itself.
#pragma once

#include <fmt/format.h>

#include <array>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <map>
#include <optional>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "trochomill/units.hpp"

namespace trochomill::gcode_detail {

inline constexpr int kMaxParameter = 5602;  // #1 .. #5601, as LinuxCNC
// Extra coordinate systems (Fanuc's G54.1 P1 .. P300) and, in the dialects that have them, the
// variables up to theirs (#7001 + 20 (P - 1) .. ).
inline constexpr int kExtraSystems = 300;
inline constexpr int kMaxExtendedParameter = 7001 + 20 * kExtraSystems;
// EQ and NE compare within this (LinuxCNC 2.9's TOLERANCE_EQUAL, also its test of an arc
// starting cutter compensation); LE and GE compare exactly there.
inline constexpr double kTolEqual = 1e-4;
inline constexpr double kMaxCoordinate = 1e6;  // mm: beyond this a move is refused (1 km)
/// A user M-code M100-M199 (its code in tenths): a program of the machine's, taking P and Q.
inline constexpr bool user_m_code(int code10) {
  return code10 >= 1000 && code10 <= 1990 && code10 % 10 == 0;
}
inline constexpr int kMaxNesting = 200;  // brackets, signs and # in one value

enum class Plane { xy, zx, yz };
enum class FeedMode { per_minute, inverse_time, per_rev };

// The keywords after an O label.
enum class OKind {
  none,
  sub,
  endsub,
  call,
  ret,
  if_,
  elseif,
  else_,
  endif,
  while_,
  endwhile,
  do_,
  repeat,
  endrepeat,
  brk,
  cont
};

struct OKeyword {
  std::string_view name;
  OKind kind;
};
inline constexpr std::array<OKeyword, 15> kOKeywords{{{"sub", OKind::sub},
                                                      {"endsub", OKind::endsub},
                                                      {"call", OKind::call},
                                                      {"return", OKind::ret},
                                                      {"if", OKind::if_},
                                                      {"elseif", OKind::elseif},
                                                      {"else", OKind::else_},
                                                      {"endif", OKind::endif},
                                                      {"while", OKind::while_},
                                                      {"endwhile", OKind::endwhile},
                                                      {"do", OKind::do_},
                                                      {"repeat", OKind::repeat},
                                                      {"endrepeat", OKind::endrepeat},
                                                      {"break", OKind::brk},
                                                      {"continue", OKind::cont}}};

// The modal groups of G codes (LinuxCNC's, as the block checks them) and their codes (x10).
enum GroupIndex {
  kMotion,
  kGroup0,
  kPlane,
  kUnits,
  kDistance,
  kArcDistance,
  kFeedMode,
  kToolLength,
  kSystem,
  kRetract,
  kComp,
  kDwell,
  kGroups
};
inline constexpr std::array<const char*, kGroups> kGroupNames{
    "motion",
    "non-modal (G5.3 G10 G28 G30 G50 G51 G52 G68 G69 G92)",
    "plane",
    "units",
    "distance mode",
    "arc distance mode",
    "feed mode",
    "tool length",
    "coordinate system",
    "retract mode",
    "cutter compensation",
    "dwell"};
struct GroupOf {
  int code10;
  GroupIndex group;
};
inline constexpr std::array<GroupOf, 100> kGroupOf{{
    {0, kMotion},        {10, kMotion},      {20, kMotion},      {30, kMotion},
    {382, kMotion},      {383, kMotion},     {384, kMotion},     {385, kMotion},
    {730, kMotion},      {740, kMotion},     {760, kMotion},     {800, kMotion},
    {810, kMotion},      {820, kMotion},     {830, kMotion},     {840, kMotion},
    {850, kMotion},      {860, kMotion},     {870, kMotion},     {880, kMotion},
    {890, kMotion},      {40, kDwell},       {100, kGroup0},     {280, kGroup0},
    {281, kGroup0},      {300, kGroup0},     {301, kGroup0},     {520, kGroup0},
    {920, kGroup0},      {921, kGroup0},     {922, kGroup0},     {923, kGroup0},
    {170, kPlane},       {180, kPlane},      {190, kPlane},      {200, kUnits},
    {210, kUnits},       {700, kUnits},      {710, kUnits},      {7000, kUnits},
    {7100, kUnits},      {900, kDistance},   {910, kDistance},   {901, kArcDistance},
    {911, kArcDistance}, {930, kFeedMode},   {940, kFeedMode},   {950, kFeedMode},
    {430, kToolLength},  {431, kToolLength}, {490, kToolLength}, {540, kSystem},
    {550, kSystem},      {560, kSystem},     {570, kSystem},     {580, kSystem},
    {590, kSystem},      {591, kSystem},     {592, kSystem},     {593, kSystem},
    {980, kRetract},     {990, kRetract},    {400, kComp},       {410, kComp},
    {411, kComp},        {420, kComp},       {421, kComp},       {50, kMotion},
    {51, kMotion},       {52, kMotion},      {53, kGroup0},      {330, kMotion},
    {331, kMotion},      {500, kGroup0},     {510, kGroup0},     {680, kGroup0},
    {690, kGroup0},      {541, kSystem},     {1540, kSystem},    {1100, kSystem},
    {1110, kSystem},     {1120, kSystem},    {1130, kSystem},    {1140, kSystem},
    {1150, kSystem},     {1160, kSystem},    {1170, kSystem},    {1180, kSystem},
    {1190, kSystem},     {1200, kSystem},    {1210, kSystem},    {1220, kSystem},
    {1230, kSystem},     {1240, kSystem},    {1250, kSystem},    {1260, kSystem},
    {1270, kSystem},     {1280, kSystem},    {1290, kSystem},    {434, kToolLength},
}};
// A block's G codes by modal group (x10, -1: none of the group), their columns, and G53.
struct BlockCodes {
  std::array<int, kGroups> code;
  std::array<std::uint32_t, kGroups> col;
  bool g53 = false;
  // Fanuc's G50 (scaling off) and G69 (rotation off): modal groups of their own (11, 16), so
  // one block may hold both, and G10 or G92 beside them.
  bool g50 = false, g69 = false;
  std::uint32_t g50_col = 0, g69_col = 0;
  [[nodiscard]] int operator[](GroupIndex g) const { return code[g]; }
};

// An O-word line of a file, found by the index (one pass over the file, made when the program
// first needs to jump).
struct OLine {
  std::size_t offset = 0;  // of the line's first character
  std::size_t line_no = 0;
  std::string label;
  OKind kind = OKind::none;
};

struct Source {
  std::string owned;  // the text of a subroutine file (the main program's is the caller's)
  std::string_view text;
  std::string name;
  bool indexed = false;
  std::vector<OLine> olines;
  // Fanuc: program number -> the line after its O line (made on the first M98/G65).
  std::optional<std::map<long, std::pair<std::size_t, std::size_t>>> programs;
};

// Where the interpreter reads next.
struct Cursor {
  std::size_t source = 0;
  std::size_t offset = 0;   // of the next line
  std::size_t line_no = 0;  // of the line before it (the next line is line_no + 1)
};

// An open if or loop of the running frame.
struct Control {
  OKind kind = OKind::if_;  // if_, while_, do_, repeat
  std::string label;
  Cursor start;          // while: its own line; do/repeat: the line after it
  bool taken = false;    // if: a branch ran
  double remaining = 0;  // repeat: passes left
};

struct Frame {
  std::string label;                      // the subroutine ("" at the top)
  Cursor ret;                             // where the call returns to
  std::array<double, 34> saved_locals{};  // #1..#30 (Fanuc #1..#33) of the caller
  bool new_locals = true;                 // false: Fanuc M98 (the caller's locals)
  Cursor start;                           // Fanuc: the subprogram's first line (L repeats)
  double repeats = 1;                     // Fanuc M98 L
  std::vector<std::pair<std::string, double>> locals;  // named local parameters
  std::vector<Control> controls;
  bool restore_modal = false;  // M73 in the subroutine
};

// The modal state M70 saves and M72 restores (LinuxCNC's list, what matters to motion).
struct ModalSave {
  bool valid = false;
  Plane plane = Plane::xy;
  double unit = 1;
  bool absolute = true, arc_absolute = false;
  FeedMode feed_mode = FeedMode::per_minute;
  double feed = 0, speed = 0;
  bool retract_r = false;
  int system = 1;
};

// One block's words: letters with values and columns, G and M codes, parameter settings.
struct Block {
  std::array<double, 26> value{};
  std::array<std::uint32_t, 26> column{};
  std::uint32_t present = 0;  // bit per letter
  struct Code {
    int code10;  // G90.1 -> 901
    std::uint32_t column;
  };
  std::vector<Code> g, m;
  struct NumberedSet {
    int index;
    double value;
    std::size_t at;  // the line's character of its '#'
  };
  struct NamedSet {
    std::string name;
    double value;
    std::uint32_t column;
  };
  std::vector<NumberedSet> numbered;
  std::vector<NamedSet> named;
  // Fanuc's G65: its argument words in the block's order (I, J and K may repeat: argument
  // specification II).
  struct Argument {
    char letter;
    double value;
    std::uint32_t column;
  };
  std::vector<Argument> arguments;
  // LinuxCNC's polar words: @ the distance from the XY origin (program length units) and ^
  // the angle from +X (degrees); increments of both in G91.
  bool has_polar_r = false, has_polar_a = false;
  double polar_r = 0, polar_a_deg = 0;
  std::uint32_t polar_r_col = 0, polar_a_col = 0;

  void clear() {
    present = 0;
    has_polar_r = has_polar_a = false;
    g.clear();
    m.clear();
    numbered.clear();
    named.clear();
    arguments.clear();
  }
  [[nodiscard]] bool has(char c) const { return (present >> (c - 'a')) & 1U; }
  [[nodiscard]] double operator[](char c) const { return value[static_cast<std::size_t>(c - 'a')]; }
  [[nodiscard]] std::uint32_t col(char c) const {
    return column[static_cast<std::size_t>(c - 'a')];
  }
  [[nodiscard]] bool has_polar() const { return has_polar_r || has_polar_a; }
  [[nodiscard]] std::uint32_t polar_col() const { return has_polar_r ? polar_r_col : polar_a_col; }
  // X Y Z (or polar words) and the axes besides them: A B C (rotary) and U V W.
  [[nodiscard]] bool has_xyz() const { return has('x') || has('y') || has('z') || has_polar(); }
  [[nodiscard]] bool has_extra() const { return (present & kExtraAxisBits) != 0; }
  [[nodiscard]] bool has_axis() const { return has_xyz() || has_extra(); }
  static constexpr std::uint32_t kExtraAxisBits = (1U << ('a' - 'a')) | (1U << ('b' - 'a')) |
                                                  (1U << ('c' - 'a')) | (1U << ('u' - 'a')) |
                                                  (1U << ('v' - 'a')) | (1U << ('w' - 'a'));
};

// The axes besides X Y Z, in LinuxCNC's order: A B C (rotary, degrees) then U V W (linear, mm,
// parallel to X Y Z); their parameters follow X Y Z's (a system's A at 5204 + 20 n, G92's at
// 5214, G28's at 5164).
inline constexpr std::array<char, 6> kExtraAxes{'a', 'b', 'c', 'u', 'v', 'w'};
using ExtraAxes = std::array<double, 6>;

// An arc of the plane: centre (c1, c2) on its axes i1, i2 (normal in), radius and sweep (rad,
// positive counterclockwise, with P's extra turns).
struct ArcData {
  int i1 = 0, i2 = 1, in = 2;
  double c1 = 0, c2 = 0, rad = 0, sweep = 0;
};

// A cheap filter for the line scans (O-words, N labels, Fanuc program numbers): whether the
// first character the line normaliser keeps may be one of `letters`. Blanks, carriage returns
// and block delete are skipped; a comment may come first (then the line is normalised).
inline bool may_start_with(std::string_view raw, std::string_view letters) {
  const std::size_t first = raw.find_first_not_of(" \t\r/");
  return first != std::string_view::npos &&
         (raw[first] == '(' || letters.find(raw[first]) != std::string_view::npos);
}

// The index past a normalised line's block delete '/' and line number "n123" (the statement's
// start), as every scan of the lines reads it.
inline std::size_t past_line_number(const std::string& t) {
  std::size_t k = 0;
  if (k < t.size() && t[k] == '/') ++k;
  if (k < t.size() && t[k] == 'n') {
    ++k;
    while (k < t.size() && ((t[k] >= '0' && t[k] <= '9') || t[k] == '.')) ++k;
  }
  return k;
}

inline int code10(double v) { return static_cast<int>(std::lround(v * 10.0)); }
inline std::string code_name(char letter, int c10) {
  return c10 % 10 == 0 ? fmt::format("{}{}", letter, c10 / 10)
                       : fmt::format("{}{}.{}", letter, c10 / 10, c10 % 10);
}

inline void rotate(double& x, double& y, double deg) {
  if (deg == 0) return;
  const double t = deg * kPi / 180.0, c = std::cos(t), s = std::sin(t);
  const double rx = x * c - y * s;
  y = x * s + y * c;
  x = rx;
}

}  // namespace trochomill::gcode_detail
