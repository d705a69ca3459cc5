// The names of the job's choices, one table per enum: the schema reads them, to_string writes
// them, and the key reference lists them.
#pragma once

#include <string_view>
#include <utility>

#include "trochomill/job.hpp"

namespace trochomill::job_detail {

template <class E>
using Names = std::pair<std::string_view, E>;

inline constexpr Names<ToolType> kToolTypes[] = {{"end_mill", ToolType::end_mill},
                                                 {"insert_mill", ToolType::insert_mill}};
inline constexpr Names<PathType> kPathTypes[] = {
    {"linear", PathType::linear},
    {"trochoidal", PathType::trochoidal},
    {"circular", PathType::circular},
    {"elliptical", PathType::elliptical},
    {"linear-elliptical", PathType::linear_elliptical}};
inline constexpr Names<Direction> kDirections[] = {{"climb", Direction::climb},
                                                   {"conventional", Direction::conventional}};
inline constexpr Names<EntryType> kEntries[] = {{"helix", EntryType::helix},
                                                {"ramp", EntryType::ramp},
                                                {"plunge", EntryType::plunge},
                                                {"outside", EntryType::outside}};
inline constexpr Names<SpindleDirection> kSpindleDirections[] = {{"cw", SpindleDirection::cw},
                                                                 {"ccw", SpindleDirection::ccw}};
inline constexpr Names<Coolant> kCoolants[] = {
    {"off", Coolant::off}, {"flood", Coolant::flood}, {"mist", Coolant::mist}};
inline constexpr Names<Dialect> kDialects[] = {
    {"linuxcnc", Dialect::linuxcnc}, {"fanuc", Dialect::fanuc}, {"sinumerik", Dialect::sinumerik},
    {"grbl", Dialect::grbl},         {"haas", Dialect::haas},   {"mach3", Dialect::mach3}};
inline constexpr Names<WorkOffset> kWorkOffsets[] = {
    {"G54", WorkOffset::g54}, {"G55", WorkOffset::g55}, {"G56", WorkOffset::g56},
    {"G57", WorkOffset::g57}, {"G58", WorkOffset::g58}, {"G59", WorkOffset::g59}};
inline constexpr Names<ArcOutput> kArcOutputs[] = {{"arcs", ArcOutput::arcs},
                                                   {"chords", ArcOutput::chords}};
inline constexpr Names<ChipModel> kChipModels[] = {{"exact", ChipModel::exact},
                                                   {"pivkin2025", ChipModel::pivkin2025}};
inline constexpr Names<ShareOf> kSharesOf[] = {{"cutting", ShareOf::cutting},
                                               {"cycle", ShareOf::cycle}};
inline constexpr Names<Criterion> kCriteria[] = {{"cziii", Criterion::cziii},
                                                 {"plunger", Criterion::plunger}};
inline constexpr Names<KfCriteria> kKfCriteria[] = {{"none", KfCriteria::none},
                                                    {"pivkin2025", KfCriteria::pivkin2025}};
inline constexpr Names<ForceModel> kForceModels[] = {{"bergmann", ForceModel::bergmann},
                                                     {"kienzle", ForceModel::kienzle},
                                                     {"linear", ForceModel::linear}};

/// The name of `value` in `table` ("?" when absent, which a complete table never is).
template <class E, std::size_t N>
constexpr std::string_view name_of(const Names<E> (&table)[N], E value) noexcept {
  for (const auto& [name, v] : table) {
    if (v == value) return name;
  }
  return "?";
}

}  // namespace trochomill::job_detail
