// `mechanism`'s curves and zone summary, and `recommend`'s recommendation. Part of the report
// module (trochomill/report.hpp includes every part).
#pragma once

#include <cstddef>
#include <filesystem>
#include <functional>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "trochomill/mechanism.hpp"

namespace trochomill {

/// `mechanism`'s curves and zone summary (`use_wear`: K_re with the flank wear).
[[nodiscard]] std::string mechanism_json(const Job& job, const MechanismSettings& st,
                                         const MechanismCurve& c, const ZoneSummary& z,
                                         bool use_wear);
[[nodiscard]] std::string mechanism_csv(const MechanismCurve& c);
[[nodiscard]] std::string mechanism_text(const std::string& job_file, const Job& job,
                                         const MechanismSettings& st, const MechanismCurve& c,
                                         const ZoneSummary& z, bool use_wear);
[[nodiscard]] std::string recommendation_json(const Job& job, const MechanismSettings& st,
                                              const Recommendation& r, bool for_feed);

}  // namespace trochomill
