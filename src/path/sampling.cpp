// Path sampling by time, by length and by spindle angle (one function evaluates every
// sample: sample_at), and tooth-tip trajectories with radial and axial runout.
#include <fmt/format.h>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <limits>

#include "trochomill/error.hpp"
#include "trochomill/path.hpp"
#include "trochomill/units.hpp"

namespace trochomill {
namespace {

constexpr double kMaxSamples = 2e8;  // ~20 GB of samples: refuse rather than exhaust memory

// Where a sample lies: its segment and the length along it (mm).
struct Place {
  std::size_t seg;
  double s_in_seg;
};

// The samples at the places, evaluated on TBB's threads (each sample on its own: the same
// values whatever the thread count).
PathSamples samples_at(const ToolPath& path, const std::vector<Place>& at) {
  const std::size_t n = at.size();
  PathSamples out;
  for (auto* v : {&out.t_s, &out.s_mm, &out.x_mm, &out.y_mm, &out.z_mm, &out.tx, &out.ty, &out.tz,
                  &out.curvature_per_mm}) {
    v->resize(n);
  }
  out.segment.resize(n);
  tbb::parallel_for(
      tbb::blocked_range<std::size_t>(0, n, 512), [&](const tbb::blocked_range<std::size_t>& r) {
        for (std::size_t i = r.begin(); i != r.end(); ++i) {
          const std::size_t seg = at[i].seg;
          const double s_in_seg = at[i].s_in_seg;
          const Segment& g = path.segments()[seg];
          const Segment::Frame f = g.frame_at(s_in_seg);
          const Vec3& p = f.point;
          const Vec3& t = f.tangent;
          out.t_s[i] = path.segment_start_time_s(seg) + s_in_seg / (g.speed_mm_per_min() / 60.0);
          out.s_mm[i] = path.segment_start_length_mm(seg) + s_in_seg;
          out.x_mm[i] = p.x();
          out.y_mm[i] = p.y();
          out.z_mm[i] = p.z();
          out.tx[i] = t.x();
          out.ty[i] = t.y();
          out.tz[i] = t.z();
          out.curvature_per_mm[i] = f.curvature_per_mm;
          out.segment[i] = seg;
        }
      });
  return out;
}

std::size_t sample_count(double total, double step, const char* what) {
  if (!(step > 0) || !std::isfinite(step)) {
    throw InputError(
        fmt::format("sampling {} must be a positive finite number, got {}", what, step));
  }
  const double n = std::floor(total / step);
  if (n > kMaxSamples) {
    throw InputError(
        fmt::format("sampling every {:g} {} gives {:.3g} samples (limit {:.0g}): "
                    "use a coarser step",
                    step, what, n, kMaxSamples));
  }
  return static_cast<std::size_t>(n);
}

// Uniform samples along one of the path's two axes, time or length: `start(seg)` is the
// segment's start on that axis and `rate(seg)` converts a distance on the axis into mm along
// the segment. The last sample sits at the path's end.
template <typename Start, typename Rate>
PathSamples sample_uniform(const ToolPath& path, double step, double total, const char* what,
                           Start start, Rate rate) {
  if (path.empty())
    throw InputError("the path is empty (a program without motion?): nothing to sample");
  const std::size_t n = sample_count(total, step, what);
  std::vector<Place> at;
  at.reserve(n + 2);
  std::size_t seg = 0;
  const std::size_t nseg = path.segments().size();
  double last = -1;
  auto emit = [&](double v) {
    while (seg + 1 < nseg && start(seg + 1) <= v) ++seg;
    const double local = (v - start(seg)) * rate(seg);
    at.push_back({seg, std::min(local, path.segments()[seg].length_mm())});
    last = v;
  };
  for (std::size_t i = 0; i <= n; ++i) emit(static_cast<double>(i) * step);
  if (total - last > 1e-12 * std::max(1.0, total)) emit(total);
  return samples_at(path, at);
}

}  // namespace

PathSamples sample_by_time(const ToolPath& path, double dt_s) {
  return sample_uniform(
      path, dt_s, path.duration_s(), "time step (s)",
      [&](std::size_t i) { return path.segment_start_time_s(i); },
      [&](std::size_t i) { return path.segments()[i].speed_mm_per_min() / 60.0; });
}

PathSamples sample_by_length(const ToolPath& path, double ds_mm) {
  return sample_uniform(
      path, ds_mm, path.length_mm(), "length step (mm)",
      [&](std::size_t i) { return path.segment_start_length_mm(i); },
      [](std::size_t) { return 1.0; });
}

PathSamples sample_at_times(const ToolPath& path, const std::vector<double>& times_s) {
  if (path.empty())
    throw InputError("the path is empty (a program without motion?): nothing to sample");
  std::vector<Place> at;
  at.reserve(times_s.size());
  std::size_t seg = 0;
  const std::size_t nseg = path.segments().size();
  double prev = -std::numeric_limits<double>::infinity();
  for (const double t : times_s) {
    if (!(t >= prev)) throw Error("sample_at_times: times must be finite and non-decreasing");
    prev = t;
    while (seg + 1 < nseg && path.segment_start_time_s(seg + 1) <= t) ++seg;
    const Segment& g = path.segments()[seg];
    at.push_back(
        {seg, std::clamp((t - path.segment_start_time_s(seg)) * (g.speed_mm_per_min() / 60.0), 0.0,
                         g.length_mm())});
  }
  PathSamples out = samples_at(path, at);
  for (std::size_t i = 0; i < times_s.size(); ++i) {
    out.t_s[i] = std::clamp(times_s[i], 0.0, path.duration_s());
  }
  return out;
}

PathSamples sample_by_spindle_angle(const ToolPath& path, int steps_per_rev, double spindle_rpm) {
  if (steps_per_rev < 1) {
    throw InputError(fmt::format("steps per revolution must be >= 1, got {}", steps_per_rev));
  }
  if (!(spindle_rpm > 0) || !std::isfinite(spindle_rpm)) {
    throw InputError(fmt::format("spindle speed must be > 0 rpm, got {}", spindle_rpm));
  }
  return sample_by_time(path, 60.0 / (spindle_rpm * steps_per_rev));
}

double tooth_period_s(const Tool& tool, const Cutting& cutting) {
  return 60.0 / (cutting.spindle_speed_rpm * tool.teeth);
}

double tooth_radius_mm(const Tool& tool, int k) {
  const double alpha = deg_to_rad(tool.tooth_angles_deg.at(static_cast<std::size_t>(k)));
  const double lambda = deg_to_rad(tool.runout_phase_deg);
  const double e = tool.runout_radial_mm, R = tool.radius_mm();
  return std::hypot(R * std::cos(alpha) + e * std::cos(lambda),
                    R * std::sin(alpha) + e * std::sin(lambda));
}

ToothTracks tooth_tracks(const PathSamples& samples, const Tool& tool, const Cutting& cutting) {
  if (tool.teeth < 1 || static_cast<int>(tool.tooth_angles_deg.size()) != tool.teeth) {
    throw InputError(fmt::format("tool needs one tooth angle per tooth ({} teeth, {} angles)",
                                 tool.teeth, tool.tooth_angles_deg.size()));
  }
  const double omega = rpm_to_rad_per_s(cutting.spindle_speed_rpm) *
                       (cutting.spindle_direction == SpindleDirection::cw ? -1.0 : 1.0);
  const double R = tool.radius_mm(), e = tool.runout_radial_mm, eax = tool.runout_axial_mm;
  const double lambda = deg_to_rad(tool.runout_phase_deg);
  const std::size_t n = samples.size();
  ToothTracks tr;
  tr.teeth = tool.teeth;
  tr.spindle_angle_rad.resize(n);
  tr.x_mm.assign(tool.teeth, std::vector<double>(n));
  tr.y_mm.assign(tool.teeth, std::vector<double>(n));
  tr.z_mm.assign(tool.teeth, std::vector<double>(n));
  for (std::size_t i = 0; i < n; ++i) tr.spindle_angle_rad[i] = omega * samples.t_s[i];
  for (int k = 0; k < tool.teeth; ++k) {
    const double alpha = deg_to_rad(tool.tooth_angles_deg[k]);
    const double dz = -eax * std::cos(alpha - lambda);
    for (std::size_t i = 0; i < n; ++i) {
      const double phi = tr.spindle_angle_rad[i];
      tr.x_mm[k][i] = samples.x_mm[i] + e * std::cos(phi + lambda) + R * std::cos(phi + alpha);
      tr.y_mm[k][i] = samples.y_mm[i] + e * std::sin(phi + lambda) + R * std::sin(phi + alpha);
      tr.z_mm[k][i] = samples.z_mm[i] + dz;
    }
  }
  return tr;
}

}  // namespace trochomill
