// The small I/O toolkit every module shares: reading a text file (as bad input when it cannot
// be read), atomic output (a temporary file beside the target, then a rename, so a failed or
// interrupted run never leaves a half-written file; one mechanism for text, WAV and HDF5),
// one numeric CSV reader with column selection, and string helpers.
#pragma once

#include <cstddef>
#include <filesystem>
#include <functional>
#include <string>
#include <string_view>
#include <vector>

namespace trochomill {

/// Writes `content` to `path` atomically (temp file in the same directory, then rename).
/// Throws IoError naming the path on failure; the target is then left untouched. A symbolic
/// link stays: its target is written. What is not a regular file (a FIFO, a device such as
/// /dev/null) is never replaced: the output is written through to it.
void write_file_atomic(const std::filesystem::path& path, std::string_view content);

/// Atomic output through a writer: `write(tmp)` creates the file at `tmp` (beside `path`) in
/// whatever format it writes (WAV through libsndfile, HDF5...); it is then renamed to `path`.
/// When `write` throws, the temporary file is removed and the exception passes on.
void write_file_atomic(const std::filesystem::path& path,
                       const std::function<void(const std::filesystem::path& tmp)>& write);

/// A temporary output file while it is being written (write_file_atomic registers its own):
/// remove_pending_files removes it if the process is stopped before it was renamed or
/// removed. At most 32 at a time; more are written unregistered.
class PendingFile {
 public:
  explicit PendingFile(const std::filesystem::path& path);
  ~PendingFile();
  PendingFile(const PendingFile&) = delete;
  PendingFile& operator=(const PendingFile&) = delete;

 private:
  int slot_ = -1;
};
/// Removes every pending temporary output file (async-signal-safe: for a SIGINT handler that
/// ends the process, so that no half-written file is left behind).
void remove_pending_files() noexcept;

/// Text made piece by piece, written atomically as write_file_atomic: `produce` hands each
/// piece to the sink it is given (a file of any size without holding it in memory).
void write_text_atomic(
    const std::filesystem::path& path,
    const std::function<void(const std::function<void(std::string_view)>&)>& produce);

/// Reads a whole file. Throws IoError naming the path when it cannot be read.
[[nodiscard]] std::string read_file(const std::filesystem::path& path);
/// Reads a whole input file (a job, a program, a table): a file that cannot be read is bad
/// input, so this throws InputError naming the path.
[[nodiscard]] std::string read_text_file(const std::filesystem::path& path);

/// `s` without the leading and trailing characters in `chars`.
[[nodiscard]] std::string trim(std::string_view s, std::string_view chars = " \t");
/// A memory size (bytes) as a user reads it: GB to two decimals, MB below 0.01 GB, kB below
/// 0.01 MB ("3.00 GB", "0.10 MB"), so that a small limit never reads "0.00 GB".
[[nodiscard]] std::string memory_text(double bytes);
/// Appends v with `decimals` (0 .. 9) digits after the point, exactly as fmt's "{:.Nf}"
/// writes it (correctly rounded, ties to even, a minus sign on negative values that round to
/// zero): exact binary-to-decimal arithmetic in 128-bit integers for |v| < 1e9, fmt itself
/// beyond and for values that are not finite. About a tenth of fmt's time for such a format:
/// the interpreter's --trace writes millions.
void append_fixed(std::string& out, double v, int decimals);
/// `s` with every `from` replaced by `to` (a temporary path in a message by the one the user
/// named).
[[nodiscard]] std::string replace_all(std::string s, std::string_view from, std::string_view to);
/// For a word that is none of `candidates`: "; did you mean 'X'?" when one is within a third
/// of its length (at least 2) in edit distance, else " (known: a, b, ...)" listing them.
[[nodiscard]] std::string did_you_mean(std::string_view word,
                                       const std::vector<std::string>& candidates);
/// "a,b,c" -> {"a", "b", "c"}: split at `sep`, each item trimmed (empty items kept, for the
/// caller to refuse).
[[nodiscard]] std::vector<std::string> split_trimmed(std::string_view s, char sep = ',');

/// A numeric table read from CSV text: an optional header line, then rows of numbers.
struct CsvTable {
  std::vector<std::string> header;        ///< column names (empty without a header)
  std::vector<std::vector<double>> rows;  ///< the selected columns, per row
  std::vector<std::size_t> line_of_row;   ///< 1-based line of each row, for messages
};
/// How to read it. The separator is ',' (or, with `detect_separator`, the first of ',', ';'
/// and tab that the line holds); '#' lines and blank lines are skipped; fields are trimmed of
/// blanks, '\r' and, with `detect_separator`, quotes. With `columns` the first line is the
/// header; without, it is a header when its first field is not a number.
struct CsvOptions {
  /// Columns to select by name (the header is then required); empty: every column.
  std::vector<std::string> columns;
  bool detect_separator = false;
  /// With no column selection: every row must have the first row's number of fields.
  bool same_width = true;
};
/// Parses CSV text; `source` names it in messages ("file:line:column: ..."). Every selected
/// field must be a finite number. Throws InputError.
[[nodiscard]] CsvTable parse_csv(std::string_view text, std::string_view source,
                                 const CsvOptions& options = {});

/// The process's peak resident memory so far (bytes; Linux VmHWM), 0 where unknown.
[[nodiscard]] std::size_t peak_memory_bytes();
/// The memory limit when none is given (bytes): 75 % of the machine's RAM.
[[nodiscard]] double default_memory_limit_bytes();
/// What a memory estimate counts for the process itself besides the work (bytes): its
/// resident memory now (Linux VmRSS: the code and libraries loaded, the job, the path), at
/// least 20 MB.
[[nodiscard]] double process_base_bytes();

}  // namespace trochomill
