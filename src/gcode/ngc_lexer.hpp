// The RS274/NGC line as LinuxCNC reads it: comments taken out, spaces and tabs removed, letters
// lower-cased, with a map back to the columns of the text for messages. And the expression
// language on such a line: numbers, parameters, [expressions] with LinuxCNC's precedence,
// unary functions. Internal to the gcode module.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

namespace trochomill::ngc {

/// One normalised line. `text` holds the code, `column[i]` the 1-based column in the source of
/// text[i] (and column.back() one past the end), `comment` the last comment's text (for MSG).
struct Line {
  std::string text;
  std::vector<std::uint32_t> column;
  std::string comment;
  std::uint32_t comment_column = 0;
  /// Where the normalisation failed (0 = it did not) and why.
  std::uint32_t error_column = 0;
  std::string error;
};

/// Normalises `raw` (one line without its newline) into `out`, reusing its buffers.
void normalise(std::string_view raw, Line& out);

/// A character as a message shows it: printable ones quoted, others as a code.
[[nodiscard]] std::string shown(char c);

}  // namespace trochomill::ngc
