// The job document: TOML parsing (toml++), overrides (the CLI's `--set`) applied to a copy of the
// parsed document, the flattened keys written into G-code headers, and the materials library (read
// once per directory). Validation is the schema's (schema.cpp).
#include <fmt/format.h>
#include <toml++/toml.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <map>
#include <mutex>
#include <sstream>

#include "job/schema.hpp"
#include "trochomill/error.hpp"
#include "trochomill/io.hpp"
#include "trochomill/job.hpp"

namespace trochomill {
namespace job_detail {
namespace {

void apply_override(toml::table& root, const Override& o) {
  const auto dot = o.key.find('.');
  const std::string section = o.key.substr(0, dot);
  const std::string key = o.key.substr(dot + 1);
  // The value in TOML syntax; when that does not parse, a bare word is taken as a string.
  toml::table parsed;
  try {
    parsed = toml::parse("v = " + o.value);
  } catch (const toml::parse_error&) {
    parsed.insert_or_assign("v", o.value);
  }
  toml::node* existing = root.get(section);
  if (existing == nullptr) {
    root.insert_or_assign(section, toml::table{});
    existing = root.get(section);
  }
  toml::table* t = existing->as_table();
  if (t == nullptr) {
    throw InputError(
        fmt::format("{}: '{}' is not a table", override_label(o.origin, o.key), section));
  }
  if (key.find('.') != std::string::npos) {
    throw InputError(fmt::format("{}: nested keys are not supported (use section.key)",
                                 override_label(o.origin, o.key)));
  }
  t->insert_or_assign(key, *parsed.get("v"));
}

// A value in TOML syntax; doubles in their shortest round-trip form (0.6, not 0.5999...).
std::string format_value(const toml::node& v) {
  if (v.is_floating_point()) {
    const double d = v.value<double>().value_or(0.0);
    std::string out = fmt::format("{}", d);
    if (std::isfinite(d) && out.find_first_of(".e") == std::string::npos) out += ".0";
    return out;
  }
  if (v.is_integer()) return fmt::format("{}", v.value<int64_t>().value_or(0));
  if (const toml::array* arr = v.as_array()) {
    std::string out = "[";
    for (std::size_t i = 0; i < arr->size(); ++i) {
      out += (i ? ", " : "") + format_value(*arr->get(i));
    }
    return out + "]";
  }
  if (v.is_table()) return "{...}";
  std::ostringstream ss;
  ss << toml::toml_formatter(v, toml::format_flags::none);
  return ss.str();
}

void flatten(const toml::table& root, std::vector<std::pair<std::string, std::string>>& out) {
  for (auto&& [k, v] : root) {
    if (const toml::table* t = v.as_table()) {
      for (auto&& [kk, vv] : *t) {
        out.emplace_back(std::string(k.str()) + "." + std::string(kk.str()), format_value(vv));
      }
    }
  }
}

// [material]: reads the keys present into m (absent keys keep m's values, so a job's keys

toml::table parse_toml(std::string_view text, std::string_view source_name) {
  try {
    return toml::parse(text, source_name);
  } catch (const toml::parse_error& e) {
    throw InputError(fmt::format("{}:{}:{}: TOML syntax error: {}", source_name,
                                 e.source().begin.line, e.source().begin.column, e.description()));
  }
}

std::vector<Material> read_library(const std::filesystem::path& dir) {
  namespace fs = std::filesystem;
  if (!fs::is_directory(dir)) {
    throw InputError(fmt::format(
        "materials library not found at {} (set TROCHOMILL_DATA to the directory holding "
        "materials/)",
        dir.string()));
  }
  std::vector<fs::path> files;
  for (const auto& e : fs::directory_iterator(dir)) {
    if (e.is_regular_file() && e.path().extension() == ".toml") files.push_back(e.path());
  }
  std::sort(files.begin(), files.end());
  std::vector<Material> out;
  for (const auto& f : files) {
    const toml::table root = parse_toml(read_text_file(f), f.string());
    JobReader r(root, f.string(), {}, schema_sections());
    Material m;
    if (auto name = r.string("material", "name")) m.name = *name;
    if (m.name.empty()) r.problem("material", "name", "a library entry needs a name");
    read_material_section(r, m);
    if (!m.model) r.problem("material", "model", "a library entry needs a model");
    check_material(r, m);
    if (m.source.empty()) r.problem("material", "source", "a library entry must cite its source");
    r.check_unknown();
    if (!r.problems().empty()) throw InputError(r.problems());
    out.push_back(std::move(m));
  }
  std::sort(out.begin(), out.end(),
            [](const Material& a, const Material& b) { return a.name < b.name; });
  return out;
}

}  // namespace

Material library_material(const std::string& name) {
  const std::vector<Material> lib = material_library();
  std::vector<std::string> names;
  for (const auto& m : lib) {
    if (m.name == name) return m;
    names.push_back(m.name);
  }
  throw InputError(
      fmt::format("'{}' is not in the materials library{}", name, suggestion(name, names)));
}

}  // namespace job_detail

std::filesystem::path materials_dir() {
  namespace fs = std::filesystem;
  if (const char* env = std::getenv("TROCHOMILL_DATA"); env != nullptr && *env != '\0') {
    return fs::path(env) / "materials";
  }
#ifdef TROCHOMILL_SOURCE_DATA_DIR
  if (fs::is_directory(fs::path(TROCHOMILL_SOURCE_DATA_DIR) / "materials")) {
    return fs::path(TROCHOMILL_SOURCE_DATA_DIR) / "materials";
  }
#endif
#ifdef TROCHOMILL_INSTALL_DATA_DIR
  return fs::path(TROCHOMILL_INSTALL_DATA_DIR) / "materials";
#else
  return fs::path("data") / "materials";
#endif
}

std::vector<Material> material_library() {
  // Read once per directory: a study loads the job per grid point, and a job naming a
  // material would otherwise scan the folder each time. A malformed library is not cached.
  static std::mutex mutex;
  static std::map<std::filesystem::path, std::vector<Material>> cache;
  const std::filesystem::path dir = materials_dir();
  {
    const std::lock_guard<std::mutex> lock(mutex);
    if (const auto it = cache.find(dir); it != cache.end()) return it->second;
  }
  std::vector<Material> lib = job_detail::read_library(dir);
  const std::lock_guard<std::mutex> lock(mutex);
  return cache.emplace(dir, std::move(lib)).first->second;
}

Override parse_override(std::string_view text) {
  const auto eq = text.find('=');
  if (eq == std::string_view::npos) {
    throw InputError(fmt::format("'{}': expected section.key=value", text));
  }
  std::string key(text.substr(0, eq));
  std::string value(text.substr(eq + 1));
  key = trim(key);
  value = trim(value);
  const auto dot = key.find('.');
  if (dot == std::string::npos || dot == 0 || dot + 1 == key.size()) {
    throw InputError(fmt::format("'{}': the key must be section.key (e.g. path.step)", text));
  }
  if (value.empty()) throw InputError(fmt::format("'{}': the value is empty", text));
  return Override{key, value, {}};
}

// The document keeps its text: toml++ does not copy source positions with a table, and every
// message must name its line and column, so each build parses the text again (microseconds;
// the file is read once).
struct JobDocument::Impl {
  std::string text;
  std::string source;
};

JobDocument::JobDocument(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}
JobDocument::JobDocument(JobDocument&&) noexcept = default;
JobDocument& JobDocument::operator=(JobDocument&&) noexcept = default;
JobDocument::~JobDocument() = default;

JobDocument JobDocument::parse(std::string_view toml_text, std::string_view source_name) {
  (void)job_detail::parse_toml(toml_text, source_name);  // a syntax error is reported now
  auto impl = std::make_unique<Impl>();
  impl->text = std::string(toml_text);
  impl->source = std::string(source_name);
  return JobDocument(std::move(impl));
}

JobDocument JobDocument::load(const std::filesystem::path& file) {
  return parse(read_text_file(file), file.string());
}

const std::string& JobDocument::source() const noexcept { return impl_->source; }

Job JobDocument::build(const std::vector<Override>& overrides) const {
  toml::table root = job_detail::parse_toml(impl_->text, impl_->source);
  std::map<std::string, std::string> overridden;
  for (const auto& o : overrides) {
    job_detail::apply_override(root, o);
    overridden[o.key] = o.origin;
  }
  Job job = job_detail::build_job(root, impl_->source, overridden);
  job_detail::flatten(root, job.flat_keys);
  return job;
}

Job parse_job(std::string_view toml_text, std::string_view source_name,
              const std::vector<Override>& overrides) {
  return JobDocument::parse(toml_text, source_name).build(overrides);
}

Job load_job(const std::filesystem::path& file, const std::vector<Override>& overrides) {
  return JobDocument::load(file).build(overrides);
}

void apply_overrides(Job& job, const std::vector<Override>& overrides) {
  toml::table root;
  std::map<std::string, std::string> overridden;
  for (const auto& o : overrides) {
    job_detail::apply_override(root, o);
    overridden[o.key] = o.origin;
  }
  job_detail::apply_to_job(root, overridden, job);
}

std::string to_toml(const Job& job) {
  std::string out, section;
  for (const auto& [key, value] : job.flat_keys) {
    const auto dot = key.find('.');
    if (key.substr(0, dot) != section) {
      section = key.substr(0, dot);
      out += fmt::format("{}[{}]\n", out.empty() ? "" : "\n", section);
    }
    out += fmt::format("{} = {}\n", key.substr(dot + 1), value);
  }
  return out;
}

}  // namespace trochomill
