// Sound files (WAV, FLAC, AIFF, OGG) behind the plugin libtrochomill_sndfile.so
// (sndfile_plugin.cpp): linked into the program, libsndfile and its codecs cost every start
// about 5 ms.
#pragma once

#include <string>

#include "trochomill/signal.hpp"

namespace trochomill::signal_detail {

/// The plugin's functions (trochomill_sndfile_table()).
struct SndfileTable {
  /// A channel of a sound file (its samples as read: the caller checks them). Throws
  /// InputError for a file libsndfile cannot read, a missing channel, a rate that contradicts
  /// the file's, or missing frames.
  Signal (*read)(const std::string& path, const SignalReadOptions& options);
  /// A mono 32-bit float WAV (no PEAK chunk: the same signal gives the same bytes). Throws
  /// InputError for a rate that is not a whole number, IoError when the write fails.
  void (*write_wav)(const std::string& path, const Signal& signal);
};
inline constexpr const char* kSndfileSymbol = "trochomill_sndfile_table";

}  // namespace trochomill::signal_detail
