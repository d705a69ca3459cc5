// plan_slot: the planner with the engagement kernel as the judge of a curved slot's steps.
#include <algorithm>

#include "trochomill/engagement.hpp"

namespace trochomill {

double kernel_chip_from_mm(const Job& job, const ToolPath& path, double from_mm) {
  const EngagementSeries e = compute_engagement(path, job);
  double h = 0;
  for (std::size_t i = 0; i < e.samples.size(); ++i) {
    if (e.samples.s_mm[i] >= from_mm) h = std::max(h, radial_chip_mm(e, i, e.tool_radius_mm));
  }
  return h;
}

PlannedPath plan_slot(const Job& job) { return plan_path(job, kernel_chip_from_mm); }

}  // namespace trochomill
