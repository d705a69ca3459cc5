// trochomill's one error policy: every failure is a trochomill::Error. InputError means the
// user's input (job file, --set override, NC program) is wrong and names where; IoError
// means a file could not be read or written. The library never prints or exits.
#pragma once

#include <functional>
#include <memory>
#include <stdexcept>
#include <string>
#include <string_view>
#include <vector>

namespace trochomill {

/// An option of a call named inside a message, by its name in the C++ and Python API (rate_hz,
/// lambda_c_mm, parts): what() reads that name, and an adapter shows its own name for the same
/// option through Error::message (the CLI: --rate, --lambda-c, --with). Job keys are named as
/// they are (path.step), never through this.
[[nodiscard]] std::string option_name(std::string_view api_name);

/// Every failure of the library. what() is the message; message() is the same with each
/// option_name given the adapter's name.
class Error : public std::runtime_error {
 public:
  explicit Error(const std::string& text);
  explicit Error(const char* text) : Error(std::string(text)) {}
  /// what(), with each option named by name_of(its API name).
  [[nodiscard]] std::string message(
      const std::function<std::string(std::string_view)>& name_of) const;

 private:
  std::shared_ptr<const std::string> marked_;  ///< the text with its options marked, or null
};

/// `text` with each option_name given name_of(its API name) (the API name itself when name_of is
/// empty): the same rendering as Error::message, for text that is not an exception's.
[[nodiscard]] std::string render_options(
    std::string_view text, const std::function<std::string(std::string_view)>& name_of = {});

/// Bad input. what() holds one line per problem, each naming the key or file:line:column.
class InputError : public Error {
 public:
  explicit InputError(std::vector<std::string> problems);
  explicit InputError(const std::string& problem) : InputError(std::vector<std::string>{problem}) {}
  [[nodiscard]] const std::vector<std::string>& problems() const noexcept { return problems_; }

 private:
  std::vector<std::string> problems_;
};

/// A file could not be opened, read, written or renamed.
class IoError : public Error {
 public:
  using Error::Error;
};

/// The user stopped a computation (Ctrl-C, through RunHooks::cancel); nothing was written.
class Interrupted : public Error {
 public:
  using Error::Error;
};

}  // namespace trochomill
