// The tool table (LinuxCNC's format) and the interpreter's tool length offsets (G43, G43.1,
// G49).
#include <fmt/format.h>

#include <cctype>
#include <charconv>
#include <cmath>
#include <cstddef>
#include <filesystem>
#include <map>
#include <optional>
#include <string>
#include <string_view>

#include "interp.hpp"
#include "ngc_lexer.hpp"
#include "trochomill/error.hpp"
#include "trochomill/gcode.hpp"
#include "trochomill/io.hpp"

namespace trochomill {
namespace gcode_detail {

void Interpreter::tool_length_offset(int g) {
  double z = 0;
  if (g == 434) {
    // Fanuc's tool centre point control: the length along the tool's axis, which with the
    // rotary axes still (the path is the X Y Z motion) is G43's.
    if (!tcp_warned_) {
      tcp_warned_ = true;
      warn(
          "G43.4 (tool centre point control) read as G43: the length offset along Z, as with "
          "the rotary axes at zero; the path is the tool tip's X Y Z motion");
    }
    g = 430;
  }
  if (g == 430) {
    double h = tool_loaded_;
    if (block_.has('h')) h = block_['h'];
    if (h < 0 || h != std::floor(h) || h > 1e6) {
      fail_at(block_.col('h'), "H must be a whole number 0 .. 1e6");
    }
    const auto it = tools_.find(static_cast<int>(h));
    unknown_tool_ = -1;
    const auto reg = fanuc_ ? registers_.find(static_cast<int>(h)) : registers_.end();
    if (reg != registers_.end() && (reg->second.h_geometry || reg->second.h_wear)) {
      // Fanuc's and Haas's H register set by G10: geometry (else the table's) plus wear.
      const double geometry = reg->second.h_geometry ? *reg->second.h_geometry
                              : it != tools_.end()   ? it->second.length_mm
                                                     : 0.0;
      z = geometry + reg->second.h_wear.value_or(0.0);
    } else if (it != tools_.end()) {
      z = it->second.length_mm;
    } else if (h != 0) {
      unknown_tool_ = h;  // named if a machine-coordinate move needs the length
    }
  } else if (g == 431) {
    unknown_tool_ = -1;
    if (!block_.has('z')) fail_at(block_.g.front().column, "G43.1 needs the length in Z");
    z = len('z');
    block_.present &= ~(1U << ('z' - 'a'));  // the Z word was the offset, not a move
  }
  if (g == 490) unknown_tool_ = -1;
  // The spindle does not move: the controlled point's program Z takes the change.
  cur_pos_.z() += tool_z_ - z;
  tool_z_ = z;
}

// A move in machine coordinates with G43 on a tool the table does not have: say so once.
void Interpreter::note_tool_length(const char* what) {
  if (unknown_tool_ < 0 || tool_warned_) return;
  tool_warned_ = true;
  warn(
      fmt::format("{} with G43 H{:g}: tool {:g} is not in the tool table "
                  "([machine] tool_table); its length is taken as 0",
                  what, unknown_tool_, unknown_tool_));
}

}  // namespace gcode_detail

std::map<int, ToolTableEntry> read_tool_table(const std::filesystem::path& file) {
  const std::string text = read_text_file(file);
  std::map<int, ToolTableEntry> out;
  std::size_t off = 0, no = 0;
  while (off < text.size()) {
    std::size_t end = text.find('\n', off);
    if (end == std::string::npos) end = text.size();
    ++no;
    std::string_view line(text.data() + off, end - off);
    off = end + 1;
    if (const auto sc = line.find(';'); sc != std::string_view::npos) line = line.substr(0, sc);
    std::optional<int> tool;
    ToolTableEntry e;
    std::size_t i = 0;
    auto fail = [&](std::size_t col, const std::string& what) {
      throw InputError(fmt::format("{}:{}:{}: {}", file.string(), no, col + 1, what));
    };
    while (i < line.size()) {
      const char c = line[i];
      if (c == ' ' || c == '\t' || c == '\r') {
        ++i;
        continue;
      }
      const char L = static_cast<char>(std::toupper(static_cast<unsigned char>(c)));
      if (std::string_view("TPXYZABCUVWDIJQ").find(L) == std::string_view::npos) {
        fail(i, fmt::format("unexpected {} in a tool table line (T P X Y Z ... D I J Q words)",
                            ngc::shown(c)));
      }
      const std::size_t at = i++;
      const char* b = line.data() + i;
      const char* e2 = line.data() + line.size();
      double v = 0;
      bool neg = false;
      if (b < e2 && (*b == '+' || *b == '-')) {
        neg = *b == '-';
        ++b;
      }
      auto [ptr, ec] = std::from_chars(b, e2, v, std::chars_format::fixed);
      if (ec != std::errc() || ptr == b || !std::isfinite(v)) {
        fail(at, fmt::format("'{}' needs a number after it", L));
      }
      if (neg) v = -v;
      i = static_cast<std::size_t>(ptr - line.data());
      if (L == 'T') {
        if (v < 0 || v != std::floor(v) || v > 1e6) fail(at, "T must be a whole number 0 .. 1e6");
        tool = static_cast<int>(v);
      } else if (L == 'Z') {
        if (std::abs(v) > 1e4) fail(at, "a tool length beyond +-1e4 mm");
        e.length_mm = v;
      } else if (L == 'D') {
        if (v < 0 || v > 1e4) fail(at, "a tool diameter outside 0 .. 1e4 mm");
        e.diameter_mm = v;
      }
    }
    if (tool) out[*tool] = e;
  }
  return out;
}

}  // namespace trochomill
