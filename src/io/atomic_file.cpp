// Atomic file output: write a temporary file beside the target, flush, then rename.
#include <cerrno>
#include <cstring>
#include <fstream>
#include <random>
#include <sstream>

#include "trochomill/error.hpp"
#include "trochomill/io.hpp"

namespace trochomill {
namespace fs = std::filesystem;

void write_file_atomic(const fs::path& path, std::string_view content) {
  const fs::path dir = path.has_parent_path() ? path.parent_path() : fs::path(".");
  std::error_code ec;
  if (!fs::is_directory(dir, ec)) {
    throw IoError("cannot write '" + path.string() + "': directory '" + dir.string() +
                  "' does not exist");
  }
  // A unique name per call: the pid-free random suffix avoids clashes between processes.
  std::random_device rd;
  const fs::path tmp = path.string() + ".tmp." + std::to_string(rd());
  {
    std::ofstream out(tmp, std::ios::binary | std::ios::trunc);
    if (!out) {
      throw IoError("cannot write '" + path.string() + "': " + std::strerror(errno));
    }
    out.write(content.data(), static_cast<std::streamsize>(content.size()));
    out.flush();
    if (!out) {
      out.close();
      fs::remove(tmp, ec);
      throw IoError("cannot write '" + path.string() + "': write failed");
    }
  }
  fs::rename(tmp, path, ec);
  if (ec) {
    std::error_code ignored;
    fs::remove(tmp, ignored);
    throw IoError("cannot write '" + path.string() + "': " + ec.message());
  }
}

std::string read_file(const fs::path& path) {
  std::error_code ec;
  if (fs::is_directory(path, ec)) {
    throw IoError("cannot read '" + path.string() + "': it is a directory");
  }
  std::ifstream in(path, std::ios::binary);
  if (!in) {
    throw IoError("cannot read '" + path.string() + "': " + std::strerror(errno));
  }
  std::ostringstream ss;
  ss << in.rdbuf();
  if (in.bad()) throw IoError("cannot read '" + path.string() + "': read failed");
  return ss.str();
}

}  // namespace trochomill
