// The job reader: typed access to a parsed TOML job document that collects every problem
// (file:line:column or the --set override, and what is allowed) instead of stopping at the
// first. The schema (schema.cpp) reads every key through it; the materials library too.
#pragma once

#include <fmt/format.h>
#include <toml++/toml.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <map>
#include <optional>
#include <set>
#include <string>
#include <string_view>
#include <vector>

#include "trochomill/io.hpp"

namespace trochomill::job_detail {

// The nearest candidate to a mistyped word (io.hpp: did_you_mean).
inline std::string suggestion(std::string_view word, const std::vector<std::string>& candidates) {
  return did_you_mean(word, candidates);
}

inline std::string fmt_num(double v) { return fmt::format("{:g}", v); }

// How a message names an override: as its caller named it (Override::origin: the CLI's
// "--set path.step", "--share (mechanism.share)" for a flag that stands for a key), else by its
// key alone (the library's and Python's callers).
inline std::string override_label(const std::string& origin, const std::string& key) {
  return origin.empty() ? key : origin;
}

struct Range {
  double lo = -std::numeric_limits<double>::infinity();
  double hi = std::numeric_limits<double>::infinity();
  bool lo_incl = true;
  bool hi_incl = true;
  [[nodiscard]] bool contains(double v) const {
    return (lo_incl ? v >= lo : v > lo) && (hi_incl ? v <= hi : v < hi);
  }
  [[nodiscard]] std::string describe() const {
    const bool has_lo = std::isfinite(lo), has_hi = std::isfinite(hi);
    if (has_lo && has_hi) {
      return fmt::format("in {}{}, {}{}", lo_incl ? "[" : "(", fmt_num(lo), fmt_num(hi),
                         hi_incl ? "]" : ")");
    }
    if (has_lo) return fmt::format("{} {}", lo_incl ? ">=" : ">", fmt_num(lo));
    if (has_hi) return fmt::format("{} {}", hi_incl ? "<=" : "<", fmt_num(hi));
    return "finite";
  }
};
constexpr Range positive() { return Range{0.0, std::numeric_limits<double>::infinity(), false}; }
constexpr Range non_negative() { return Range{0.0}; }

class JobReader {
 public:
  /// `known`: each section's keys (from the schema); anything else is reported with the
  /// closest suggestion.
  /// `overridden`: the keys set by overrides, with the flag that set each (empty: --set).
  JobReader(const toml::table& root, std::string source,
            std::map<std::string, std::string> overridden,
            const std::map<std::string, std::vector<std::string>>& known)
      : root_(root),
        source_(std::move(source)),
        overridden_(std::move(overridden)),
        known_(known) {}
  [[nodiscard]] const std::string& source() const noexcept { return source_; }

  std::vector<std::string>& problems() { return problems_; }

  [[nodiscard]] std::string where(const std::string& section, const std::string& key,
                                  const toml::node* node) const {
    const std::string full = section + "." + key;
    if (const auto it = overridden_.find(full); it != overridden_.end()) return origin(it);
    if (node != nullptr && node->source().begin.line > 0) {
      return fmt::format("{}:{}:{}: [{}] {}", source_, node->source().begin.line,
                         node->source().begin.column, section, key);
    }
    return fmt::format("{}: [{}] {}", source_, section, key);
  }

  void problem(const std::string& section, const std::string& key, const std::string& what) {
    problems_.push_back(fmt::format("{}: {}", where(section, key, find(section, key)), what));
  }

  [[nodiscard]] const toml::node* find(const std::string& section, const std::string& key) const {
    const toml::table* t = root_[section].as_table();
    return t ? t->get(key) : nullptr;
  }
  [[nodiscard]] bool has_section(std::string_view section) const {
    return root_[section].as_table() != nullptr;
  }
  [[nodiscard]] bool has(const std::string& section, const std::string& key) const {
    return find(section, key) != nullptr;
  }

  std::optional<double> number(const std::string& section, const std::string& key,
                               const std::string& unit, Range range,
                               std::optional<double> fallback = std::nullopt,
                               bool required = false) {
    const toml::node* n = find(section, key);
    if (n == nullptr) {
      if (required) {
        problems_.push_back(fmt::format("{}: missing required key [{}] {} ({}{})", source_, section,
                                        key, unit.empty() ? "number" : unit, range_hint(range)));
      }
      return fallback;
    }
    if (!n->is_number()) {
      problem(section, key,
              fmt::format("expected a number ({}), got {}", unit_or(unit), type_name(*n)));
      return fallback;
    }
    const double v = n->value<double>().value_or(0.0);
    if (!std::isfinite(v)) {
      problem(section, key, fmt::format("must be a finite number, got {}", fmt_num(v)));
      return fallback;
    }
    if (!range.contains(v)) {
      problem(section, key,
              fmt::format("must be {} {}, got {}", range.describe(), unit, fmt_num(v)));
      return fallback;
    }
    return v;
  }

  std::optional<int> integer(const std::string& section, const std::string& key, int lo, int hi,
                             std::optional<int> fallback = std::nullopt, bool required = false) {
    const toml::node* n = find(section, key);
    if (n == nullptr) {
      if (required) {
        problems_.push_back(fmt::format("{}: missing required key [{}] {} (integer in [{}, {}])",
                                        source_, section, key, lo, hi));
      }
      return fallback;
    }
    if (!n->is_integer()) {
      problem(section, key,
              fmt::format("expected an integer in [{}, {}], got {}", lo, hi, type_name(*n)));
      return fallback;
    }
    const int64_t v = n->value<int64_t>().value_or(0);
    if (v < lo || v > hi) {
      problem(section, key, fmt::format("must be an integer in [{}, {}], got {}", lo, hi, v));
      return fallback;
    }
    return static_cast<int>(v);
  }

  template <typename Enum>
  std::optional<Enum> choice(const std::string& section, const std::string& key,
                             const std::vector<std::pair<std::string, Enum>>& options,
                             std::optional<Enum> fallback, bool required = false) {
    std::string allowed;
    for (const auto& [name, value] : options) allowed += (allowed.empty() ? "" : " | ") + name;
    const toml::node* n = find(section, key);
    if (n == nullptr) {
      if (required) {
        problems_.push_back(
            fmt::format("{}: missing required key [{}] {} ({})", source_, section, key, allowed));
      }
      return fallback;
    }
    if (!n->is_string()) {
      problem(section, key,
              fmt::format("expected one of {} (a string), got {}", allowed, type_name(*n)));
      return fallback;
    }
    const std::string v = n->value<std::string>().value_or("");
    for (const auto& [name, value] : options) {
      if (name == v) return value;
    }
    std::vector<std::string> names;
    for (const auto& [name, value] : options) names.push_back(name);
    const std::string hint = suggestion(v, names);
    problem(section, key,
            fmt::format("'{}' is not one of {}{}", v, allowed,
                        hint.rfind("; did", 0) == 0 ? hint : std::string()));
    return fallback;
  }

  std::optional<std::string> string(const std::string& section, const std::string& key) {
    const toml::node* n = find(section, key);
    if (n == nullptr) return std::nullopt;
    if (!n->is_string()) {
      problem(section, key, fmt::format("expected a string, got {}", type_name(*n)));
      return std::nullopt;
    }
    return n->value<std::string>().value_or("");
  }

  std::optional<bool> boolean(const std::string& section, const std::string& key) {
    const toml::node* n = find(section, key);
    if (n == nullptr) return std::nullopt;
    if (!n->is_boolean()) {
      problem(section, key, fmt::format("expected true or false, got {}", type_name(*n)));
      return std::nullopt;
    }
    return n->value<bool>().value_or(false);
  }

  std::optional<std::vector<std::string>> string_array(const std::string& section,
                                                       const std::string& key) {
    const toml::node* n = find(section, key);
    if (n == nullptr) return std::nullopt;
    const toml::array* arr = n->as_array();
    if (arr == nullptr) {
      problem(section, key, fmt::format("expected an array of strings, got {}", type_name(*n)));
      return std::nullopt;
    }
    std::vector<std::string> out;
    for (std::size_t i = 0; i < arr->size(); ++i) {
      const toml::node& e = *arr->get(i);
      if (!e.is_string()) {
        problem(section, key, fmt::format("element {} must be a string, got {}", i, type_name(e)));
        return std::nullopt;
      }
      out.push_back(e.value<std::string>().value_or(""));
    }
    return out;
  }

  std::optional<std::vector<double>> number_array(const std::string& section,
                                                  const std::string& key, Range range) {
    const toml::node* n = find(section, key);
    if (n == nullptr) return std::nullopt;
    const toml::array* arr = n->as_array();
    if (arr == nullptr) {
      problem(section, key, fmt::format("expected an array of numbers, got {}", type_name(*n)));
      return std::nullopt;
    }
    std::vector<double> out;
    for (std::size_t i = 0; i < arr->size(); ++i) {
      const toml::node& e = *arr->get(i);
      if (!e.is_number()) {
        problem(section, key, fmt::format("element {} must be a number, got {}", i, type_name(e)));
        return std::nullopt;
      }
      const double v = e.value<double>().value_or(0.0);
      if (!std::isfinite(v) || !range.contains(v)) {
        problem(section, key,
                fmt::format("element {} must be {}, got {}", i, range.describe(), fmt_num(v)));
        return std::nullopt;
      }
      out.push_back(v);
    }
    return out;
  }

  void check_unknown() {
    const auto& known = known_;
    std::vector<std::string> sections;
    for (const auto& [name, keys] : known) sections.push_back(name);
    for (auto&& [k, v] : root_) {
      const std::string section(k.str());
      const auto it = known.find(section);
      if (it == known.end()) {
        // A section only an override names has no place in the file: name the override.
        std::string loc =
            fmt::format("{}:{}:{}", source_, k.source().begin.line, k.source().begin.column);
        for (const auto& [key, flag] : overridden_) {
          if (key.rfind(section + ".", 0) == 0) {
            loc = origin(overridden_.find(key));
            break;
          }
        }
        problems_.push_back(
            fmt::format("{}: unknown section [{}]{}", loc, section, suggestion(section, sections)));
        continue;
      }
      const toml::table* t = v.as_table();
      if (t == nullptr) {
        problems_.push_back(fmt::format("{}:{}:{}: '{}' must be a table [{}]", source_,
                                        k.source().begin.line, k.source().begin.column, section,
                                        section));
        continue;
      }
      for (auto&& [kk, vv] : *t) {
        const std::string key(kk.str());
        if (std::find(it->second.begin(), it->second.end(), key) == it->second.end()) {
          const std::string full = section + "." + key;
          const auto ov = overridden_.find(full);
          const std::string loc = ov != overridden_.end()
                                      ? origin(ov)
                                      : fmt::format("{}:{}:{}", source_, kk.source().begin.line,
                                                    kk.source().begin.column);
          problems_.push_back(fmt::format("{}: unknown key [{}] {}{}", loc, section, key,
                                          suggestion(key, it->second)));
        }
      }
    }
  }

 private:
  static std::string origin(std::map<std::string, std::string>::const_iterator it) {
    return override_label(it->second, it->first);
  }
  static std::string unit_or(const std::string& unit) { return unit.empty() ? "number" : unit; }
  static std::string range_hint(const Range& r) {
    const std::string d = r.describe();
    return d == "finite" ? "" : ", " + d;
  }
  static std::string type_name(const toml::node& n) {
    switch (n.type()) {
      case toml::node_type::string:
        return "a string";
      case toml::node_type::integer:
        return "an integer";
      case toml::node_type::floating_point:
        return "a number";
      case toml::node_type::boolean:
        return "a boolean";
      case toml::node_type::array:
        return "an array";
      case toml::node_type::table:
        return "a table";
      default:
        return "a date/time";
    }
  }

  const toml::table& root_;
  std::string source_;
  std::map<std::string, std::string> overridden_;
  std::vector<std::string> problems_;
  const std::map<std::string, std::vector<std::string>>& known_;
};

}  // namespace trochomill::job_detail
