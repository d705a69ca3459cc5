// Reading NC programs: the interpreter's entry point (the language: interp.hpp), the
// header keys trochomill writes into its programs, and their check against a job.
#include <fmt/format.h>

#include <algorithm>
#include <array>
#include <charconv>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <map>
#include <optional>

#include "interp.hpp"
#include "trochomill/error.hpp"
#include "trochomill/gcode.hpp"
#include "trochomill/io.hpp"
#include "trochomill/units.hpp"

namespace trochomill {

std::vector<std::pair<std::string, std::string>> gcode_header_keys(std::string_view text) {
  // The leading block of comment lines (and '%', O numbers, blank lines): "(k.e = v)" or
  // "; k.e = v", where k.e is a dotted lower-case key.
  std::vector<std::pair<std::string, std::string>> out;
  std::size_t pos = 0;
  while (pos < text.size()) {
    std::size_t eol = text.find('\n', pos);
    if (eol == std::string_view::npos) eol = text.size();
    std::string_view line = text.substr(pos, eol - pos);
    pos = eol + 1;
    while (!line.empty() && (line.back() == '\r' || line.back() == ' ')) line.remove_suffix(1);
    while (!line.empty() && line.front() == ' ') line.remove_prefix(1);
    if (line.empty() || line == "%" || line.front() == 'O') continue;
    std::string_view body;
    if (line.front() == ';') {
      body = line.substr(1);
    } else if (line.front() == '(' && line.back() == ')') {
      body = line.substr(1, line.size() - 2);
    } else {
      break;  // the first block that is not a comment ends the header
    }
    while (!body.empty() && body.front() == ' ') body.remove_prefix(1);
    const std::size_t eq = body.find(" = ");
    if (eq == std::string_view::npos) continue;
    const std::string_view key = body.substr(0, eq);
    const bool dotted =
        key.find('.') != std::string_view::npos && std::all_of(key.begin(), key.end(), [](char c) {
          return (c >= 'a' && c <= 'z') || (c >= '0' && c <= '9') || c == '_' || c == '.';
        });
    if (dotted) out.emplace_back(std::string(key), std::string(body.substr(eq + 3)));
  }
  return out;
}

GcodeProgram read_gcode(std::string_view text, std::string_view source_name,
                        const GcodeReadOptions& options) {
  if (!(options.rapid_rate_mm_per_min > 0)) throw InputError("rapid rate must be > 0 mm/min");
  GcodeProgram prog = gcode_detail::interpret_gcode(text, source_name, options);
  prog.info.header_keys = gcode_header_keys(text);
  return prog;
}

std::string GcodeProgram::where(std::size_t segment) const {
  if (segment >= segment_lines.size()) return {};
  const SourceLine& l = segment_lines[segment];
  const std::string& file = l.source < source_files.size() ? source_files[l.source] : "?";
  return fmt::format("{}:{}", file, l.line);
}

GcodeProgram read_gcode_file(const std::filesystem::path& file, const GcodeReadOptions& options) {
  return read_gcode(read_text_file(file), file.string(), options);
}

namespace {
// Two TOML values alike: the same text, or numbers equal as numbers ("37" and "37.0").
bool same_value(const std::string& a, const std::string& b) {
  if (a == b) return true;
  char* ea = nullptr;
  char* eb = nullptr;
  const double x = std::strtod(a.c_str(), &ea), y = std::strtod(b.c_str(), &eb);
  return ea != a.c_str() && *ea == '\0' && eb != b.c_str() && *eb == '\0' && x == y;
}
}  // namespace

std::vector<std::string> header_mismatches(const Job& job, const GcodeProgram& prog,
                                           const std::string& name) {
  // The sections the models read beside the program's moves (the tool, the slot and its
  // placement, the orbit, the spindle); the others (how the program was formatted, material,
  // measurements, analysis settings) may well differ on purpose.
  static const std::vector<std::string> kProgramSections = {"tool.", "slot.", "path.", "cutting."};
  auto defines_program = [](const std::string& key) {
    return std::any_of(kProgramSections.begin(), kProgramSections.end(),
                       [&](const std::string& s) { return key.rfind(s, 0) == 0; });
  };
  std::vector<std::string> out;
  if (prog.info.header_keys.empty()) return out;  // not written by trochomill
  std::map<std::string, std::string> in_job(job.flat_keys.begin(), job.flat_keys.end());
  std::map<std::string, std::string> in_program(prog.info.header_keys.begin(),
                                                prog.info.header_keys.end());
  for (const auto& [key, v] : in_program) {
    if (!defines_program(key)) continue;
    const auto it = in_job.find(key);
    if (it == in_job.end()) {
      out.push_back(
          fmt::format("{} was written with {} = {}, which the job does not set", name, key, v));
    } else if (!same_value(v, it->second)) {
      out.push_back(
          fmt::format("{} was written with {} = {}, the job has {}", name, key, v, it->second));
    }
  }
  for (const auto& [key, v] : in_job) {
    if (defines_program(key) && in_program.count(key) == 0) {
      out.push_back(fmt::format("{} was written without {} (the job has {})", name, key, v));
    }
  }
  return out;
}

}  // namespace trochomill
