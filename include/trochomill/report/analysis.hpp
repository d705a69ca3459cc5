// The analysis's outputs: process metrics (JSON, text), the engagement series (CSV) and the
// parameter study `compare` (table, JSON, CSV). Part of the report module (trochomill/report.hpp
// includes every part).
#pragma once

#include <cstddef>
#include <filesystem>
#include <functional>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "trochomill/analysis.hpp"

namespace trochomill {

/// A figure as the report's headline and the CLI's summaries show it: rounded to `digits`
/// significant digits and written in the shortest text of that value ("0.075", "64.96",
/// "2216", "12350"), in exponent form from 1e6 up and below 1e-4; "-" when not finite. The
/// report's page formats the same way (web/src/report.js, fmtNum).
[[nodiscard]] std::string figure_text(double v, int digits = 4);

/// The parts of the analysis (analysis.hpp: AnalysisParts) the metrics named need, by their
/// keys in metrics_json (a study's metric names: nested keys joined by '.'); a key of the
/// whole program or the steady cycle needs none. A metric's value is the same to the bit
/// with its parts as with all.
[[nodiscard]] AnalysisParts analysis_parts_for(const std::vector<std::string>& metric_keys);

/// The analysis as a JSON document (keys carry their units: _mm, _s, _deg, _mm3_per_min); the
/// figures of a part not computed (m.parts) are null.
[[nodiscard]] std::string metrics_json(const Job& job, const ProcessMetrics& m);
/// `analyze`'s summary; `gcode`: the program analysed (empty: the planned path).
[[nodiscard]] std::string metrics_text(const std::string& job_file, const std::string& gcode,
                                       const Job& job, const ProcessMetrics& m);

/// The time series as CSV: t_s, x_mm, y_mm, z_mm, engaged angles (deg, "start:end" pairs
/// separated by ';'), engagement_deg, h_max_mm, teeth_in_cut, mrr_mm3_per_min.
[[nodiscard]] std::string series_csv(const EngagementSeries& e);

/// One `--vary key=v1,v2,...` of a parameter study.
[[nodiscard]] std::string study_table(const std::vector<Vary>& varies,
                                      const std::vector<StudyPoint>& points);
[[nodiscard]] std::string study_json(const std::vector<Vary>& varies,
                                     const std::vector<StudyPoint>& points);
[[nodiscard]] std::string study_csv(const std::vector<Vary>& varies,
                                    const std::vector<StudyPoint>& points);

}  // namespace trochomill
