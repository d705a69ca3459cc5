// ToolPath: an ordered list of segments, continuous in position, with cumulative length and
// programmed-feed time for lookup by arc length or time.
#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <utility>

#include "trochomill/error.hpp"
#include "trochomill/path.hpp"
#include "trochomill/units.hpp"

namespace trochomill {

void ToolPath::append(Segment segment) {
  if (segment.length_mm() <= 0) return;  // a move to where the tool already is: nothing to do
  if (!(segment.speed_mm_per_min() > 0)) {
    throw Error(fmt::format("segment {} has no speed (mm/min)", segments_.size()));
  }
  double s0 = 0, t0 = 0;
  if (!segments_.empty()) {
    const Segment& last = segments_.back();
    const double gap = (segment.start() - last.end()).norm();
    if (gap > 1e-9) {
      throw Error(
          fmt::format("path is discontinuous at segment {}: gap {:.3g} mm (from ({:.6f}, {:.6f}, "
                      "{:.6f}) to ({:.6f}, {:.6f}, {:.6f}))",
                      segments_.size(), gap, last.end().x(), last.end().y(), last.end().z(),
                      segment.start().x(), segment.start().y(), segment.start().z()));
    }
    s0 = start_length_.back() + last.length_mm();
    t0 = start_time_.back() + last.length_mm() / (last.speed_mm_per_min() / 60.0);
  }
  start_length_.push_back(s0);
  start_time_.push_back(t0);
  segments_.push_back(std::move(segment));
}

void ToolPath::reserve(std::size_t n) {
  segments_.reserve(n);
  start_length_.reserve(n);
  start_time_.reserve(n);
}

void ToolPath::mark_cycle() {
  cycles_.push_back(CycleMark{segments_.size(), length_mm(), duration_s()});
}

double ToolPath::length_mm() const noexcept {
  return segments_.empty() ? 0.0 : start_length_.back() + segments_.back().length_mm();
}

double ToolPath::feed_length_mm() const noexcept {
  double s = 0;
  for (const auto& seg : segments_) {
    if (seg.motion() == Motion::feed) s += seg.length_mm();
  }
  return s;
}

double ToolPath::duration_s() const noexcept {
  if (segments_.empty()) return 0.0;
  const Segment& last = segments_.back();
  return start_time_.back() + last.length_mm() / (last.speed_mm_per_min() / 60.0);
}

std::size_t ToolPath::segment_at_length(double s_mm) const {
  if (segments_.empty()) throw Error("the path is empty");
  const auto it = std::upper_bound(start_length_.begin(), start_length_.end(), s_mm);
  return it == start_length_.begin() ? 0 : static_cast<std::size_t>(it - start_length_.begin()) - 1;
}

std::size_t ToolPath::segment_at_time(double t_s) const {
  if (segments_.empty()) throw Error("the path is empty");
  const auto it = std::upper_bound(start_time_.begin(), start_time_.end(), t_s);
  return it == start_time_.begin() ? 0 : static_cast<std::size_t>(it - start_time_.begin()) - 1;
}

double ToolPath::length_at_time_mm(double t_s, std::size_t* segment) const {
  const std::size_t k = segment_at_time(t_s);
  if (segment != nullptr) *segment = k;
  const Segment& seg = segments_[k];
  return start_length_[k] +
         std::clamp((t_s - start_time_[k]) * seg.speed_mm_per_min() / 60.0, 0.0, seg.length_mm());
}

Vec3 ToolPath::point_at_length(double s_mm) const {
  const std::size_t i = segment_at_length(s_mm);
  return segments_[i].point_at(s_mm - start_length_[i]);
}

}  // namespace trochomill

namespace trochomill {

// A curve's box in closed form: each coordinate c + A cos u + B sin u + V u is extreme at the
// ends or where its derivative -A sin u + B cos u + V vanishes, at u = phi + asin(V / rho) and
// phi + pi - asin(V / rho) (rho = |(A, B)|, phi = atan2(B, A)) plus whole turns; of those
// within the curve's range only the first and the last of each kind can be extreme (the drift
// V u tilts the turns' values one way).
void extend(Box3& b, const Segment& seg) {
  b.extend(seg.start());
  b.extend(seg.end());
  if (seg.kind() != Segment::Kind::curve) return;
  const double lo = std::min(seg.u0(), seg.u1()), hi = std::max(seg.u0(), seg.u1());
  for (int d = 0; d < 3; ++d) {
    const double A = seg.axis_a()[d], B = seg.axis_b()[d], V = seg.drift()[d], c = seg.center()[d];
    const double rho = std::hypot(A, B);
    if (!(rho > 0) || std::abs(V) >= rho) continue;  // monotonic: the ends hold its extremes
    const double phi = std::atan2(B, A), s = std::asin(V / rho);
    for (const double alpha : {phi + s, phi + M_PI - s}) {
      const double k0 = std::ceil((lo - alpha) / (2 * M_PI)),
                   k1 = std::floor((hi - alpha) / (2 * M_PI));
      for (const double k : {k0, k1}) {
        if (k < k0 || k > k1) continue;
        const double u = alpha + 2 * M_PI * k;
        Vec3 p = b.lo;  // only coordinate d moves the box
        p[d] = c + A * std::cos(u) + B * std::sin(u) + V * u;
        b.extend(p);
      }
    }
  }
}

Box3 bounding_box(const ToolPath& path) {
  Box3 b;
  for (const auto& seg : path.segments()) extend(b, seg);
  return b;
}

void PathSummary::add(const Segment& seg) {
  if (seg.length_mm() <= 0) return;  // as ToolPath::append
  ++segments;
  length_mm += seg.length_mm();
  if (seg.motion() == Motion::feed) feed_length_mm += seg.length_mm();
  duration_s += seg.length_mm() / (seg.speed_mm_per_min() / 60.0);
  extend(box, seg);
}

std::pair<double, double> cycle_window(const ToolPath& path, int a, int b) {
  const auto& marks = path.cycles();
  const int n = static_cast<int>(marks.size());
  if (n == 0) throw InputError("cycles: the path has no cycle marks (a planned trochoid has)");
  if (a < 0 || b <= a || b > n) {
    throw InputError(
        fmt::format("cycles {}:{}: need 0 <= A < B <= {} (the path's cycles)", a, b, n));
  }
  const double t0 = marks[static_cast<std::size_t>(a)].start_time_s;
  const double t1 = b < n ? marks[static_cast<std::size_t>(b)].start_time_s : path.duration_s();
  return {t0, t1};
}

PathSummary summarize(const ToolPath& path) {
  PathSummary s;
  for (const auto& seg : path.segments()) s.add(seg);
  return s;
}

namespace {
// cos and sin of an angle in degrees, exact at multiples of 90 degrees.
std::pair<double, double> cos_sin_deg(double deg) {
  double r = std::fmod(deg, 360.0);
  if (r < 0) r += 360.0;
  if (r == 0) return {1.0, 0.0};
  if (r == 90) return {0.0, 1.0};
  if (r == 180) return {-1.0, 0.0};
  if (r == 270) return {0.0, -1.0};
  return {std::cos(deg_to_rad(r)), std::sin(deg_to_rad(r))};
}

// Every primitive through a rigid motion about Z: points by `point`, directions by `turn`.
template <class Point, class Turn>
ToolPath rigidly_moved(const ToolPath& path, Point point, Turn turn) {
  ToolPath out;
  std::size_t next_mark = 0;
  const auto& marks = path.cycles();
  for (std::size_t i = 0; i < path.segments().size(); ++i) {
    while (next_mark < marks.size() && marks[next_mark].first_segment == i) {
      out.mark_cycle();
      ++next_mark;
    }
    const Segment& s = path.segments()[i];
    if (s.kind() == Segment::Kind::line) {
      out.append(Segment::line(point(s.start()), point(s.end()), s.motion(), s.speed_mm_per_min()));
    } else {
      out.append(Segment::curve(point(s.center()), turn(s.axis_a()), turn(s.axis_b()),
                                turn(s.drift()), s.u0(), s.u1(), s.motion(), s.speed_mm_per_min()));
    }
  }
  while (next_mark < marks.size()) {
    out.mark_cycle();
    ++next_mark;
  }
  return out;
}
}  // namespace

bool Placement::is_identity() const noexcept {
  return origin_x_mm == 0 && origin_y_mm == 0 && cos_sin_deg(angle_deg).first == 1;
}

Vec3 Placement::turn(const Vec3& v) const {
  const auto [c, s] = cos_sin_deg(angle_deg);
  return Vec3(c * v.x() - s * v.y(), s * v.x() + c * v.y(), v.z());
}

Vec3 Placement::to_work(const Vec3& p) const {
  const Vec3 q = turn(p);
  return Vec3(q.x() + origin_x_mm, q.y() + origin_y_mm, q.z());
}

Vec3 Placement::turn_back(const Vec3& v) const {
  const auto [c, s] = cos_sin_deg(angle_deg);
  return Vec3(c * v.x() + s * v.y(), -s * v.x() + c * v.y(), v.z());
}

Vec3 Placement::to_slot(const Vec3& p) const {
  return turn_back(Vec3(p.x() - origin_x_mm, p.y() - origin_y_mm, p.z()));
}

Placement slot_placement(const Job& job) {
  return Placement{job.slot.origin_x_mm, job.slot.origin_y_mm, job.slot.angle_deg};
}

ToolPath to_work_frame(const ToolPath& path, const Placement& pl) {
  if (pl.is_identity()) return path;
  return rigidly_moved(
      path, [&](const Vec3& p) { return pl.to_work(p); },
      [&](const Vec3& v) { return pl.turn(v); });
}

ToolPath to_slot_frame(const ToolPath& path, const Placement& pl) {
  if (pl.is_identity()) return path;
  return rigidly_moved(
      path, [&](const Vec3& p) { return pl.to_slot(p); },
      [&](const Vec3& v) { return pl.turn_back(v); });
}

}  // namespace trochomill
