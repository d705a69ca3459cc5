// Shared by the libFuzzer targets: a per-process scratch file for the readers that take a
// path (libsndfile, assimp and the CSV readers open files), on /dev/shm when it exists.
#pragma once

#include <unistd.h>

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <string>

namespace trochomill::fuzz {

inline std::filesystem::path scratch_file(const std::string& extension) {
  const std::filesystem::path dir =
      std::filesystem::exists("/dev/shm") ? "/dev/shm" : std::filesystem::temp_directory_path();
  return dir / ("trochomill-fuzz-" + std::to_string(::getpid()) + extension);
}

inline void write_bytes(const std::filesystem::path& p, const std::uint8_t* data,
                        std::size_t size) {
  std::ofstream out(p, std::ios::binary | std::ios::trunc);
  out.write(reinterpret_cast<const char*>(data), static_cast<std::streamsize>(size));
}

}  // namespace trochomill::fuzz
