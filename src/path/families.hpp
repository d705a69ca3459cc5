// The slot planner's shared pieces (private to src/path): the families' geometry, the builder
// that mirrors x for the other orbit direction, one cycle of a family, and the planner of a
// slot along a drawing's contour (curved.cpp).
#pragma once

#include <fmt/format.h>

#include <cmath>

#include "trochomill/error.hpp"
#include "trochomill/path.hpp"

namespace trochomill::path_detail {

// The planner's counts (cycles, passes, spans) from a ratio, computed in double and checked
// before the conversion: a step tiny against the slot would overflow an int (and the path
// would hold billions of segments). The limit is far above any real slot (a 1 m slot at a
// 0.001 mm step is 1e6 cycles).
inline constexpr double kMaxCount = 1e7;
inline int checked_count(double n) {
  if (!(n <= kMaxCount)) {
    throw InputError(fmt::format(
        "[path] step: the slot would need {:.4g} cycles or passes (limit {:g}); raise [path] step "
        "or shorten [slot] length",
        n, kMaxCount));
  }
  return static_cast<int>(n);
}

// Builds segments in the clockwise-orbit frame (plan_path) and mirrors x on the way into the
// path when asked.
class Builder {
 public:
  Builder(ToolPath& path, bool mirror) : path_(path), mirror_(mirror) {}

  [[nodiscard]] Vec3 here() const { return here_; }
  void start_at(const Vec3& p) { here_ = p; }

  void line_to(const Vec3& p, Motion m, double speed) {
    path_.append(Segment::line(flip(here_), flip(p), m, speed));
    here_ = p;
  }
  void curve(const Vec3& c, const Vec3& a, const Vec3& b, const Vec3& v, double u0, double u1,
             double speed) {
    const Segment seg =
        Segment::curve(flip(c), flip(a), flip(b), flip(v), u0, u1, Motion::feed, speed);
    here_ = c + a * std::cos(u1) + b * std::sin(u1) + v * u1;
    path_.append(seg);
  }
  void arc_xy(double cx, double cy, double r, double start, double sweep, double z0, double z1,
              double speed) {
    const Vec3 c(cx, cy, z0);
    const Vec3 a(r * std::cos(start), r * std::sin(start), 0);
    const Vec3 b(-r * std::sin(start), r * std::cos(start), 0);
    const Vec3 v(0, 0, (z1 - z0) / sweep);
    curve(c, a, b, v, 0.0, sweep, speed);
  }
  void mark_cycle() { path_.mark_cycle(); }

 private:
  [[nodiscard]] Vec3 flip(const Vec3& p) const { return mirror_ ? Vec3(-p.x(), p.y(), p.z()) : p; }
  ToolPath& path_;
  bool mirror_;
  Vec3 here_ = Vec3::Zero();
};

struct Geometry {
  double R = 0, W = 0, a = 0, b = 0, s = 0, d = 0, L = 0, zf = 0;
  double feed = 0, entry_feed = 0, rapid = 0, safe_z = 0, clearance = 0;
  PathType type = PathType::trochoidal;
};

// One cycle of a trochoidal family starting at (-a, y, zf) in the clockwise-orbit frame.
void emit_cycle(Builder& bld, const Geometry& g, double y);

/// The families' geometry of the job (its tool, slot, step and feeds).
[[nodiscard]] Geometry make_geometry(const Job& job);

/// A slot along the job's centreline (slot.centreline): the family's cycles placed along it.
[[nodiscard]] PlannedPath plan_along_curve(const Job& job, const Geometry& g, bool mirror,
                                           const ChipJudge& judge);

}  // namespace trochomill::path_detail
