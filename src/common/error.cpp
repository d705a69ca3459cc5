// InputError joins its problems into what(), one per line.
#include "trochomill/error.hpp"

namespace trochomill {
namespace {
// An option's name is marked by two control characters no message text holds (ASCII's record
// and unit separators).
constexpr char kOpen = '\x1e';
constexpr char kClose = '\x1f';

std::string join_lines(const std::vector<std::string>& lines) {
  std::string out;
  for (const auto& l : lines) {
    if (!out.empty()) out += '\n';
    out += l;
  }
  return out;
}
}  // namespace

InputError::InputError(std::vector<std::string> problems) : Error(join_lines(problems)) {
  for (std::string& p : problems) p = render_options(p);
  problems_ = std::move(problems);
}

std::string option_name(std::string_view api_name) {
  std::string out;
  out.reserve(api_name.size() + 2);
  out += kOpen;
  out += api_name;
  out += kClose;
  return out;
}

std::string render_options(std::string_view text,
                           const std::function<std::string(std::string_view)>& name_of) {
  std::string out;
  out.reserve(text.size());
  std::size_t at = 0;
  while (at < text.size()) {
    const std::size_t open = text.find(kOpen, at);
    const std::size_t close = open == std::string_view::npos ? open : text.find(kClose, open + 1);
    if (close == std::string_view::npos) {  // no (whole) mark left: the rest as it is
      out += text.substr(at);
      break;
    }
    out += text.substr(at, open - at);
    const std::string_view name = text.substr(open + 1, close - open - 1);
    if (name_of) {
      out += name_of(name);
    } else {
      out += name;
    }
    at = close + 1;
  }
  return out;
}

Error::Error(const std::string& text)
    : std::runtime_error(render_options(text)),
      marked_(text.find(kOpen) == std::string::npos ? nullptr
                                                    : std::make_shared<const std::string>(text)) {}

std::string Error::message(const std::function<std::string(std::string_view)>& name_of) const {
  return marked_ ? render_options(*marked_, name_of) : std::string(what());
}

}  // namespace trochomill
