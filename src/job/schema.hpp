// The job schema (schema.cpp): one entry per key of the job file.
#pragma once

#include <functional>
#include <map>
#include <set>
#include <string>
#include <vector>

#include "job/reader.hpp"
#include "trochomill/job.hpp"

namespace trochomill::job_detail {

/// One key: where it is, what it holds, how it is read into the job and what its default is.
struct Key {
  const char* section;
  const char* key;
  std::string type;     ///< number, integer, choice, string, array of numbers, ...
  std::string unit;     ///< as in messages ("mm", "degrees", "% of r_e"; empty: none)
  std::string allowed;  ///< range or choices
  bool required = false;
  const char* doc;
  /// Reads the key (absent: the member keeps its value) and reports problems to the reader.
  std::function<void(JobReader&, Job&)> read;
  /// The default, as text, from a default-constructed job.
  std::function<std::string(Job&)> show;
};

/// Every key, in reading order (a key that depends on others comes after them).
[[nodiscard]] const std::vector<Key>& schema();
/// Each section's keys, for the unknown-key check.
[[nodiscard]] const std::map<std::string, std::vector<std::string>>& schema_sections();

/// Validates and builds the job from a document with its overrides applied.
[[nodiscard]] Job build_job(const toml::table& root, const std::string& source,
                            const std::map<std::string, std::string>& overridden);
/// Reads the keys of `root` (overrides only) into an existing job; see apply_overrides.
void apply_to_job(const toml::table& root, const std::map<std::string, std::string>& overridden,
                  Job& job);

/// `[material]`'s coefficient keys read over `m` (a library entry is read this way too).
void read_material_section(JobReader& r, Material& m);
/// The coefficients a model needs are there, and none of another model's.
void check_material(JobReader& r, const Material& m);
/// The library entry of that name (the library is read once per directory). Throws InputError.
[[nodiscard]] Material library_material(const std::string& name);

}  // namespace trochomill::job_detail
