// File output helpers shared by the CLI and every writer: outputs are written to a temporary
// file beside the target and renamed, so a failed or interrupted run never leaves a
// half-finished file.
#pragma once

#include <filesystem>
#include <string>
#include <string_view>

namespace trochomill {

/// Writes `content` to `path` atomically (temp file in the same directory, then rename).
/// Throws IoError naming the path on failure; the target is then left untouched.
void write_file_atomic(const std::filesystem::path& path, std::string_view content);

/// Reads a whole file. Throws IoError naming the path when it cannot be read.
[[nodiscard]] std::string read_file(const std::filesystem::path& path);

}  // namespace trochomill
