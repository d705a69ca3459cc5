// Line normalisation as LinuxCNC's interpreter does it before parsing (close_and_downcase):
// comments out, blanks out, lower case; the columns are kept for messages.
#include "ngc_lexer.hpp"

#include <fmt/format.h>

namespace trochomill::ngc {

std::string shown(char c) {
  const auto u = static_cast<unsigned char>(c);
  if (u >= 0x20 && u < 0x7f) return fmt::format("'{}'", c);
  return fmt::format("byte 0x{:02x}", u);
}

void normalise(std::string_view raw, Line& out) {
  out.text.clear();
  out.column.clear();
  out.comment.clear();
  out.comment_column = 0;
  out.error_column = 0;
  out.error.clear();
  const std::size_t n = raw.size();
  for (std::size_t i = 0; i < n; ++i) {
    const char c = raw[i];
    if (c == ' ' || c == '\t' || c == '\r') continue;
    if (c == ';') {
      out.comment.assign(raw.substr(i + 1));
      out.comment_column = static_cast<std::uint32_t>(i + 1);
      break;
    }
    if (c == '(') {
      const std::size_t close = raw.find(')', i + 1);
      if (close == std::string_view::npos) {
        out.error_column = static_cast<std::uint32_t>(i + 1);
        out.error = "comment '(' is not closed on this line";
        return;
      }
      const std::size_t nested = raw.find('(', i + 1);
      if (nested != std::string_view::npos && nested < close) {
        out.error_column = static_cast<std::uint32_t>(nested + 1);
        out.error = "nested '(' inside a comment";
        return;
      }
      out.comment.assign(raw.substr(i + 1, close - i - 1));
      out.comment_column = static_cast<std::uint32_t>(i + 1);
      i = close;
      continue;
    }
    out.text.push_back(c >= 'A' && c <= 'Z' ? static_cast<char>(c - 'A' + 'a') : c);
    out.column.push_back(static_cast<std::uint32_t>(i + 1));
  }
  out.column.push_back(static_cast<std::uint32_t>(n + 1));
}

}  // namespace trochomill::ngc
