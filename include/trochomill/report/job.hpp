// The job keys and the materials library as tables and JSON. Part of the report module
// (trochomill/report.hpp includes every part).
#pragma once

#include <cstddef>
#include <filesystem>
#include <functional>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "trochomill/job.hpp"

namespace trochomill {

/// The materials library as JSON and as a table with sources.
/// The job keys (job_keys()) as an aligned table, and as JSON.
[[nodiscard]] std::string job_keys_text();
[[nodiscard]] std::string job_keys_json();
[[nodiscard]] std::string materials_json(const std::vector<Material>& lib);
[[nodiscard]] std::string materials_text(const std::vector<Material>& lib, const std::string& dir);

}  // namespace trochomill
