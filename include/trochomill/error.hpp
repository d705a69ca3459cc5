// trochomill's one error policy: every failure is a trochomill::Error. InputError means the
// user's input (job file, --set override, NC program) is wrong and names where; IoError
// means a file could not be read or written. The library never prints or exits.
#pragma once

#include <stdexcept>
#include <string>
#include <vector>

namespace trochomill {

class Error : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

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
