// The slot planner: the five path families of Wagih 2023 Eq. 1 (docs/models.md section 2) with
// entry to depth, cycles until the slot end is cleared, and exit. Everything is built in the
// clockwise-orbit frame (the new material on the left of the tool: conventional milling with a
// clockwise spindle) and mirrored in x for the other orbit direction (climb with a clockwise
// spindle).
//
// Placement (docs/models.md, "Planning"): with an `outside` entry the slot is open at y = 0:
// the tool feeds in along the wall line x = -a from outside the stock to the first cycle's
// start (-a, y0), and y0 is the largest value for which the rear envelope of cycle 0 still
// reaches y <= 0 at every x the approach does not cover. With helix/ramp/plunge the slot is
// closed at y = 0 and y0 puts the rearmost tool point of cycle 0 exactly on y = 0. The cycle
// count is the smallest for which the front envelope of the last cycle reaches y >= L across
// the width (less the wall scallop bound). Envelopes are evaluated on the sampled cycle-0
// centre path; sampling under-estimates the front and over-estimates the rear, so both
// choices err towards cutting the whole slot.
#include "families.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <limits>

#include "trochomill/error.hpp"
#include "trochomill/path.hpp"
#include "trochomill/units.hpp"

namespace trochomill::path_detail {

void emit_cycle(Builder& bld, const Geometry& g, double y) {
  const Vec3 ax(-g.a, 0, 0), by(0, g.b, 0), drift(0, g.s / kTwoPi, 0);
  switch (g.type) {
    case PathType::trochoidal:
    case PathType::elliptical:
      bld.curve(Vec3(0, y, g.zf), ax, by, drift, 0.0, kTwoPi, g.feed);
      break;
    case PathType::circular:
      bld.curve(Vec3(0, y, g.zf), ax, Vec3(0, g.a, 0), Vec3::Zero(), 0.0, kTwoPi, g.feed);
      bld.line_to(Vec3(-g.a, y + g.s, g.zf), Motion::feed, g.feed);
      break;
    case PathType::linear_elliptical:
      if (g.d > 0) bld.line_to(Vec3(-g.a, y + g.d, g.zf), Motion::feed, g.feed);
      bld.curve(Vec3(0, y + g.d, g.zf), ax, by, drift, 0.0, kPi, g.feed);
      if (g.d > 0) bld.line_to(Vec3(g.a, y + 0.5 * g.s, g.zf), Motion::feed, g.feed);
      bld.curve(Vec3(0, y, g.zf), ax, by, drift, kPi, kTwoPi, g.feed);
      break;
    case PathType::linear:
      throw Error("emit_cycle: the linear family has no cycles");
  }
}

}  // namespace trochomill::path_detail

namespace trochomill {
using namespace path_detail;
namespace {

// The envelope's centre points are at most this far apart along the path (mm).
constexpr double kEnvelopeSample = 0.1;
// The largest shortfall of the sampled envelope (mm): that of centres kEnvelopeSample apart
// on a straight path, 0.25 um for R = 5 mm.
double envelope_sampling_error_mm(double R) { return kEnvelopeSample * kEnvelopeSample / (8 * R); }

struct Envelope {
  double max_rear = -std::numeric_limits<double>::infinity();  // max_x of solid rear (rel. y)
  double min_front = std::numeric_limits<double>::infinity();  // min_x of solid front
  double min_center_y = std::numeric_limits<double>::infinity();
  double cycle_length = 0;
  std::vector<double> col_x;                                   // x of each column (mm)
  std::vector<std::vector<std::pair<double, double>>> col_iv;  // merged y intervals of one cycle
  int span_cycles = 0;  // max over columns of the cycles one cycle's coverage spans (J)
};

using Interval = std::pair<double, double>;

// Sorts and merges intervals in place (touching ones join).
void merge(std::vector<Interval>& v) {
  std::sort(v.begin(), v.end());
  std::size_t k = 0;
  for (std::size_t i = 1; i < v.size(); ++i) {
    if (v[i].first <= v[k].second) {
      v[k].second = std::max(v[k].second, v[i].second);
    } else {
      v[++k] = v[i];
    }
  }
  if (!v.empty()) v.resize(k + 1);
}

// The solid front and rear of the steady-state coverage in one x column. `iv` is the union
// of y intervals one cycle covers (relative to its start). With cycles every s, the cut
// region at this x behind the last cycle is C = U_{j>=0} (iv - j s); the solid front is the
// top of the gap-free part of C that reaches down indefinitely (above it an island of a wide
// orbit may remain). Symmetrically for the rear with shifts + j s. Returns false when the
// periodic pattern itself has gaps (the step leaves islands everywhere).
bool solid_extents(std::vector<Interval> iv, double s, double& front, double& rear, int& span) {
  merge(iv);
  const double lo = iv.front().first, hi = iv.back().second;
  const int J = checked_count(std::ceil((hi - lo) / s)) + 1;
  span = J;
  auto solid = [&](double sign, double& out) {
    std::vector<Interval> all;
    all.reserve(iv.size() * (J + 2));
    for (int j = 0; j <= J + 1; ++j) {
      for (const auto& [a, b] : iv) all.emplace_back(a - sign * j * s, b - sign * j * s);
    }
    merge(all);
    // Levels within one period of ref are reached only by shifts j <= J + 1, so the union
    // there is exact and equals the periodic steady state: it must be gap-free over a whole
    // period around ref; the contiguous run through ref then ends at the solid front
    // (starts at the solid rear).
    const double ref = sign > 0 ? hi - J * s : lo + J * s;
    for (const auto& [a, b] : all) {
      if (a <= ref - s && ref + s <= b) {
        out = sign > 0 ? b : a;
        return true;
      }
    }
    return false;
  };
  return solid(+1.0, front) && solid(-1.0, rear);
}

// Solid front and rear coverage of the cycles (relative to a cycle's start y), over the slot
// width less the wall scallop bound delta; the rear only where the wall-line approach does
// not cover. Also the exact rearmost centre point.
Envelope cycle_envelope(const Geometry& g, double delta) {
  ToolPath one;
  Builder bld(one, false);
  bld.start_at(Vec3(-g.a, 0, g.zf));
  emit_cycle(bld, g, 0.0);
  Envelope env;
  env.cycle_length = one.length_mm();
  // Centre points ds apart along the path, plus every segment's end points. Discs of radius
  // R on a path of curvature kappa, ds apart, fall short of the region it sweeps by
  // ds^2 / 8 (kappa + 1 / R) midway between two of them (the envelope's sampling error,
  // docs/models.md): ds is chosen per segment, from its largest curvature, so that this stays
  // within envelope_sampling_error_mm(R), which plan_path adds to the wall band.
  const double err = envelope_sampling_error_mm(g.R);
  std::vector<double> xs, ys;
  for (const Segment& seg : one.segments()) {
    double kappa = 0;
    for (int k = 0; k <= 64; ++k)
      kappa = std::max(kappa, seg.curvature_at(seg.length_mm() * k / 64));
    // A 5 % margin on the curvature, for its peak between the 65 samples.
    const double ds = std::min(kEnvelopeSample, std::sqrt(8 * err / (1.05 * kappa + 1 / g.R)));
    const int n = std::max(2, static_cast<int>(std::ceil(seg.length_mm() / ds)));
    for (int k = 0; k <= n; ++k) {
      const Vec3 p = seg.point_at(seg.length_mm() * k / n);
      xs.push_back(p.x());
      ys.push_back(p.y());
    }
  }
  const double x_lo = -0.5 * g.W + delta, x_hi = 0.5 * g.W - delta;
  const int nx = 400;
  const double dx = (x_hi - x_lo) / nx;
  std::vector<std::vector<Interval>> cols(nx + 1);
  for (std::size_t i = 0; i < xs.size(); ++i) {
    const double xc = xs[i], yc = ys[i];
    const int j0 = std::max(0, static_cast<int>(std::ceil((xc - g.R - x_lo) / dx)));
    const int j1 = std::min(nx, static_cast<int>(std::floor((xc + g.R - x_lo) / dx)));
    for (int j = j0; j <= j1; ++j) {
      const double x = x_lo + dx * j;
      const double h = std::sqrt(std::max(0.0, g.R * g.R - (x - xc) * (x - xc)));
      // Samples come in path order, so a column's new interval usually overlaps its last
      // one: extend that in place and keep the columns short.
      auto& col = cols[j];
      if (!col.empty() && yc - h <= col.back().second && yc + h >= col.back().first) {
        col.back().first = std::min(col.back().first, yc - h);
        col.back().second = std::max(col.back().second, yc + h);
      } else {
        col.emplace_back(yc - h, yc + h);
      }
    }
  }
  const double approach_hi = -g.a + g.R;  // the approach along x = -a covers x < -a + R
  for (int j = 0; j <= nx; ++j) {
    const double x = x_lo + dx * j;
    double front = 0, rear = 0;
    int span = 0;
    merge(cols[j]);
    env.col_x.push_back(x);
    env.col_iv.push_back(cols[j]);
    if (cols[j].empty() || !solid_extents(std::move(cols[j]), g.s, front, rear, span)) {
      throw InputError(fmt::format(
          "[path] step: the cycles leave uncut islands at x = {:.3f} mm; use a smaller step", x));
    }
    env.span_cycles = std::max(env.span_cycles, span);
    env.min_front = std::min(env.min_front, front);
    if (x > approach_hi) env.max_rear = std::max(env.max_rear, rear);
  }
  // The rearmost centre point exactly: golden-section search on y(u) of each segment around
  // its lowest sample (a closed start puts the tool's rear exactly on y = 0, so sampling
  // error would cut behind it).
  double best = std::numeric_limits<double>::infinity();
  for (const Segment& seg : one.segments()) {
    const int n = 256;
    int k_min = 0;
    for (int k = 0; k <= n; ++k) {
      if (seg.point_u(seg.u0() + (seg.u1() - seg.u0()) * k / n).y() <
          seg.point_u(seg.u0() + (seg.u1() - seg.u0()) * k_min / n).y()) {
        k_min = k;
      }
    }
    double lo = seg.u0() + (seg.u1() - seg.u0()) * std::max(0, k_min - 1) / n;
    double hi = seg.u0() + (seg.u1() - seg.u0()) * std::min(n, k_min + 1) / n;
    const double gr = (std::sqrt(5.0) - 1) / 2;
    for (int it = 0; it < 100; ++it) {
      const double m1 = hi - gr * (hi - lo), m2 = lo + gr * (hi - lo);
      if (seg.point_u(m1).y() < seg.point_u(m2).y())
        hi = m2;
      else
        lo = m1;
    }
    best = std::min({best, seg.point_u(0.5 * (lo + hi)).y(), seg.start().y(), seg.end().y()});
  }
  env.min_center_y = best;
  return env;
}

// Entry to depth at the wall point p = (-a or x, y, zf) of the clockwise-orbit frame, arriving with
// the tool at p. The tool starts at safe z above the entry.
void emit_entry(Builder& bld, const Geometry& g, const PathSpec& spec, const Vec3& p, bool along_y,
                double room_mm) {
  const double z_top = g.clearance;  // start feeding this far above the top face
  switch (spec.entry) {
    case EntryType::outside: {
      const double y_out = -(g.R + g.clearance);
      bld.start_at(Vec3(p.x(), y_out, g.safe_z));
      bld.line_to(Vec3(p.x(), y_out, z_top), Motion::rapid, g.rapid);
      bld.line_to(Vec3(p.x(), y_out, g.zf), Motion::feed, g.entry_feed);
      bld.line_to(p, Motion::feed, g.feed);
      return;
    }
    case EntryType::plunge:
      bld.start_at(Vec3(p.x(), p.y(), g.safe_z));
      bld.line_to(Vec3(p.x(), p.y(), z_top), Motion::rapid, g.rapid);
      bld.line_to(p, Motion::feed, g.entry_feed);
      return;
    case EntryType::ramp: {
      if (!(room_mm > 1e-6)) {
        throw InputError(
            fmt::format("[path] entry = \"ramp\": no room for a ramp beside the "
                        "entry point ({:.4g} mm); use entry = \"plunge\" or a wider "
                        "slot",
                        room_mm));
      }
      const double len = room_mm;
      const double drop = z_top - g.zf;
      const double max_drop_per_leg = len * std::tan(deg_to_rad(spec.entry_angle_deg));
      const int legs = std::max(1, static_cast<int>(std::ceil(drop / max_drop_per_leg - 1e-12)));
      const Vec3 far = along_y ? Vec3(p.x(), p.y() + len, 0) : Vec3(p.x() + len, p.y(), 0);
      bld.start_at(Vec3(p.x(), p.y(), g.safe_z));
      bld.line_to(Vec3(p.x(), p.y(), z_top), Motion::rapid, g.rapid);
      bool at_far = false;
      for (int k = 1; k <= legs; ++k) {
        const double z = z_top - drop * k / legs;
        const Vec3 target = at_far ? Vec3(p.x(), p.y(), z) : Vec3(far.x(), far.y(), z);
        bld.line_to(target, Motion::feed, g.entry_feed);
        at_far = !at_far;
      }
      // Finish the floor under the last ramp leg at full depth, ending at the entry point.
      if (!at_far) bld.line_to(Vec3(far.x(), far.y(), g.zf), Motion::feed, g.entry_feed);
      bld.line_to(p, Motion::feed, g.entry_feed);
      return;
    }
    case EntryType::helix: {
      const double max_r = 0.5 * room_mm;
      double r = spec.entry_radius_mm > 0 ? spec.entry_radius_mm : 0.5 * max_r;
      if (!(max_r > 1e-6)) {
        throw InputError(
            "[path] entry = \"helix\": the slot leaves no room for a helix beside "
            "the entry point; use entry = \"plunge\" or \"ramp\"");
      }
      if (r > max_r + 1e-12) {
        throw InputError(
            fmt::format("[path] entry_radius: a helix of radius {:g} mm leaves the "
                        "slot; at most {:.4g} mm fits here",
                        r, max_r));
      }
      r = std::min(r, max_r);
      // Helix centre beside p so the helix passes through p with tangent +y (cw orbit,
      // climb), the direction the cycles start in.
      const double cx = p.x() + r, cy = p.y();
      const double drop = z_top - g.zf;
      const double turns = drop / spec.entry_pitch_mm;
      bld.start_at(Vec3(p.x(), p.y(), g.safe_z));
      bld.line_to(Vec3(p.x(), p.y(), z_top), Motion::rapid, g.rapid);
      bld.arc_xy(cx, cy, r, kPi, -kTwoPi * turns, z_top, g.zf, g.entry_feed);
      // One full circle at depth cleans the floor of the bore; the helix may have ended
      // anywhere on the circle, so continue to the entry point and around once more.
      const Vec3 h = bld.here();
      const double ang = std::atan2(h.y() - cy, h.x() - cx);
      double to_p = std::fmod(ang - kPi, kTwoPi);  // cw sweep from ang back to pi
      if (to_p < 0) to_p += kTwoPi;
      bld.arc_xy(cx, cy, r, ang, -(to_p + kTwoPi), g.zf, g.zf, g.entry_feed);
      return;
    }
  }
}

}  // namespace

SlotGeometry slot_geometry(const Job& job) {
  SlotGeometry g;
  g.width_mm = job.slot.width_mm;
  g.tool_radius_mm = job.tool.radius_mm();
  g.orbit_a_mm = 0.5 * (job.slot.width_mm - job.tool.diameter_mm);
  g.orbit_b_mm =
      job.path.type == PathType::elliptical || job.path.type == PathType::linear_elliptical
          ? job.path.aspect_ratio * g.orbit_a_mm
          : g.orbit_a_mm;
  g.step_mm = job.path.step_mm;
  return g;
}

ToolPath family_cycle(PathType type, double orbit_a_mm, double aspect, double step_mm,
                      double linear_distance_mm, bool mirror, double speed_mm_per_min) {
  if (type == PathType::linear) throw Error("family_cycle: the linear family has no cycles");
  Geometry g;
  g.type = type;
  g.a = orbit_a_mm;
  g.b = (type == PathType::trochoidal ? 1.0 : aspect) * orbit_a_mm;
  g.s = step_mm;
  g.d = type == PathType::linear_elliptical ? linear_distance_mm : 0.0;
  g.feed = speed_mm_per_min;
  ToolPath out;
  Builder bld(out, mirror);
  bld.start_at(Vec3(-g.a, 0, 0));
  emit_cycle(bld, g, 0.0);
  return out;
}

Geometry path_detail::make_geometry(const Job& job) {
  Geometry g;
  g.type = job.path.type;
  const SlotGeometry sg = slot_geometry(job);
  g.R = sg.tool_radius_mm;
  g.W = sg.width_mm;
  g.a = sg.orbit_a_mm;
  g.s = sg.step_mm;
  g.b = sg.orbit_b_mm;
  g.d = g.type == PathType::linear_elliptical ? job.path.linear_distance_mm : 0.0;
  g.L = job.slot.length_mm;
  g.zf = -job.slot.depth_mm;
  g.feed = job.cutting.feed_rate_mm_per_min;
  g.entry_feed = job.path.entry_feed_mm_per_min > 0 ? job.path.entry_feed_mm_per_min : 0.5 * g.feed;
  g.rapid = job.machine.rapid_rate_mm_per_min;
  g.safe_z = job.machine.safe_z_mm;
  g.clearance = std::min(job.path.clearance_mm, job.machine.safe_z_mm);
  return g;
}

namespace {

PlannedPath plan_linear(const Job& job, const Geometry& g, bool mirror) {
  PlannedPath out;
  Builder bld(out.path, mirror);
  const bool closed = job.path.entry != EntryType::outside;
  if (job.path.entry == EntryType::helix) {
    throw InputError(
        "[path] entry = \"helix\" is for the trochoidal families; a linear slot "
        "enters with \"ramp\", \"plunge\" or \"outside\"");
  }
  const int passes = g.a > 0 ? checked_count(std::ceil(2 * g.a / g.s - 1e-12)) + 1 : 1;
  const double y_start = closed ? g.R : 0.0;
  const double y_end = g.L + g.R + g.clearance;  // past the open end by the clearance
  for (int i = 0; i < passes; ++i) {
    // The frame (conventional with a cw spindle) feeding +y: new material on the left, so passes
    // go from +a towards -a (the first pass cuts full width).
    const double x = passes > 1 ? g.a - 2 * g.a * i / (passes - 1) : 0.0;
    if (i > 0) {
      bld.line_to(Vec3(bld.here().x(), bld.here().y(), g.safe_z), Motion::rapid, g.rapid);
      const double y_next = closed ? y_start : -(g.R + g.clearance);
      bld.line_to(Vec3(x, y_next, g.safe_z), Motion::rapid, g.rapid);
    }
    bld.mark_cycle();
    // The slot end is open, so a ramp along +y may run one diameter from the start.
    const double room = job.tool.diameter_mm;
    if (i == 0) {
      emit_entry(bld, g, job.path, Vec3(x, y_start, g.zf), true, room);
    } else {
      // Later passes: the start is already open beside them, so feed straight down.
      const Vec3 p(x, y_start, g.zf);
      if (job.path.entry == EntryType::outside) {
        bld.line_to(Vec3(x, bld.here().y(), g.clearance), Motion::rapid, g.rapid);
        bld.line_to(Vec3(x, bld.here().y(), g.zf), Motion::feed, g.entry_feed);
        bld.line_to(p, Motion::feed, g.feed);
      } else {
        bld.line_to(Vec3(x, y_start, g.clearance), Motion::rapid, g.rapid);
        bld.line_to(p, Motion::feed, g.entry_feed);
      }
    }
    bld.line_to(Vec3(x, y_end, g.zf), Motion::feed, g.feed);
  }
  bld.line_to(Vec3(bld.here().x(), bld.here().y(), g.safe_z), Motion::rapid, g.rapid);
  if (closed && passes > 1) {
    // End clean-up: the passes touch the closed end y = 0 only at their own x; one leg
    // along y = R from wall to wall removes the scallops between them. It starts above the
    // last pass's start (cut already).
    const double x_last = bld.here().x();
    bld.line_to(Vec3(x_last, y_start, g.safe_z), Motion::rapid, g.rapid);
    bld.line_to(Vec3(x_last, y_start, g.clearance), Motion::rapid, g.rapid);
    bld.line_to(Vec3(x_last, y_start, g.zf), Motion::feed, g.entry_feed);
    bld.line_to(Vec3(-x_last, y_start, g.zf), Motion::feed, g.feed);
    bld.line_to(Vec3(-x_last, y_start, g.safe_z), Motion::rapid, g.rapid);
  }
  out.info.trochoid_radius_mm = g.a;
  out.info.semi_axis_feed_mm = 0;
  out.info.first_cycle_y_mm = y_start;
  out.info.cycles = passes;
  out.info.cycle_length_mm = y_end - y_start;
  out.info.closed_start = closed;
  return out;
}

}  // namespace

double feed_rate_mm_per_min(const Job& job) { return job.cutting.feed_rate_mm_per_min; }
double spindle_speed_rpm(const Job& job) { return job.cutting.spindle_speed_rpm; }
double link_feed_mm_per_min(const Machine& m) {
  return m.air_feed_mm_per_min > 0   ? m.air_feed_mm_per_min
         : m.max_feed_mm_per_min > 0 ? m.max_feed_mm_per_min
                                     : m.rapid_rate_mm_per_min;
}

double estimate_plan_memory(const Job& job) {
  const SlotGeometry g = slot_geometry(job);
  double cycles = 1;
  if (job.path.type == PathType::linear) {
    cycles = g.orbit_a_mm > 0 && g.step_mm > 0 ? 2 * g.orbit_a_mm / g.step_mm + 2 : 1;
  } else if (g.step_mm > 0) {
    cycles =
        (job.slot.length_mm + 2 * (g.orbit_a_mm + g.orbit_b_mm + g.tool_radius_mm)) / g.step_mm + 8;
  }
  // Measured on the trochoidal family (VmHWM of `plan`): 1.7 to 5.7 kB a cycle from a
  // 0.01 mm to a 1 mm step (longer cycles fit more arcs), over 30 MB for the process.
  const double per_cycle = job.path.type == PathType::linear_elliptical ? 4500.0 : 3000.0;
  // A slot along a contour: its cycles once per depth level.
  if (job.slot.curved() && job.slot.max_step_down_mm > 0) {
    cycles *= std::ceil(job.slot.depth_mm / job.slot.max_step_down_mm - 1e-9);
  }
  return 30e6 + cycles * per_cycle;
}

void check_stock_top(const Job& job) {
  if (!job.stock_max_mm) return;
  const double top = (*job.stock_max_mm)[2];
  // 1e-9 mm: a top written as 0 in another unit or frame and read back.
  if (top > 1e-9) {
    const bool mesh = job.stock_mesh != nullptr;
    throw InputError(fmt::format(
        "{}: [stock] {}: the stock's top z = {:g} mm is above the top face z = 0 the program is "
        "planned from: its depths and levels are measured from z = 0 and its rapids come down "
        "to [path] clearance = {:g} mm above z = 0. Face the stock down to z = 0 first and "
        "give {}",
        job.source, mesh ? "mesh" : "max", top, job.path.clearance_mm,
        mesh ? "a mesh whose highest vertex is at z <= 0" : "[stock] max z <= 0"));
  }
}

PlannedPath plan_path(const Job& job, const ChipJudge& judge) {
  if (job.pocket.defined()) {
    throw InputError(fmt::format(
        "{}: the job plans a pocket ([pocket]); this models a slot (give a job with [slot])",
        job.source));
  }
  if (!(job.slot.width_mm > 0)) {
    throw InputError(fmt::format(
        "{}: the job has no [slot] to plan (width, length, depth mm; [path] type and step): its "
        "[stock] alone is the stock of a program read from G-code",
        job.source));
  }
  check_stock_top(job);
  const Geometry g = make_geometry(job);
  if (!(g.feed > 0)) throw InputError("[cutting]: the feed rate must be > 0 mm/min");
  // Orbit direction. A clockwise (M3) spindle's tooth enters the material on the right of the
  // tool's motion at its thickest (climb, down milling) and the material on its left at zero
  // (conventional, up milling). The frame's orbit is clockwise, its new material on the left:
  // conventional with a cw spindle. Climb mirrors it (a counter-clockwise orbit, G3), and so
  // does a ccw spindle (both together cancel).
  const bool mirror = (job.path.direction == Direction::climb) !=
                      (job.cutting.spindle_direction == SpindleDirection::ccw);
  if (job.slot.curved()) {
    if (!judge) throw Error("plan_path: a slot along a curve needs a chip judge (plan_slot)");
    return plan_along_curve(job, g, mirror, judge);
  }
  if (g.type == PathType::linear) return plan_linear(job, g, mirror);
  if (!(g.a > 0)) {
    throw InputError(
        fmt::format("[slot] width: a {} path needs a slot wider than the tool", to_string(g.type)));
  }
  if (!(g.s > 0) || g.s >= 2 * g.R) {
    throw InputError(fmt::format("[path] step: must be in (0, {:g}) mm, got {:g}", 2 * g.R, g.s));
  }

  // The wall band left out of the coverage check: the scallop bound (circles of radius >= R
  // touching the wall every s, docs/models.md) plus twice the envelope's sampling error (its
  // dips come on top of the scallops). With only the larger of the two, and centres spaced
  // without regard to the path's curvature, the column at the band's edge sat on the
  // scallops' crests and a dip between two samples there read as an uncut island (elliptical,
  // aspect 0.5, step 0.3 mm, where the orbit turns on a 1.25 mm radius at the wall).
  const double delta =
      g.R - std::sqrt(g.R * g.R - 0.25 * g.s * g.s) + 2 * envelope_sampling_error_mm(g.R);
  // The count first: a step tiny against the slot is refused before any work.
  (void)checked_count(std::ceil((g.L + 2 * (g.a + g.b + g.R)) / g.s));
  const Envelope env = cycle_envelope(g, delta);
  const bool closed = job.path.entry != EntryType::outside;
  double y0;
  // Near the walls the envelopes are steep (the tool grazes the wall band), so the sampled
  // envelopes are trusted only to a margin: start that much earlier and cut that much further.
  const double margin = 0.02;  // mm
  if (closed) {
    y0 = g.R - env.min_center_y;  // rearmost tool point of cycle 0 on y = 0
  } else {
    y0 = (std::isfinite(env.max_rear) ? -env.max_rear : 0.0) - margin;
  }
  // The solid front gives a lower bound on the cycle count; the count is then raised until
  // the finite union of the cycles actually covers every column from y = 0 to L (+margin):
  // with a wide orbit (a > R) each cycle leaves an island at its centre that only the rear
  // arcs of later cycles sweep.
  const int n_front =
      std::max(1, checked_count(std::ceil((g.L + margin - y0 - env.min_front) / g.s - 1e-12)) + 1);
  const double approach_hi = -g.a + g.R;
  auto covers = [&](int n) {
    // With n - 1 >= 2 J + 2 the middle of the finite union is the verified gap-free periodic
    // pattern and its ends are the solid rear and front already accounted for.
    if (n - 1 >= 2 * env.span_cycles + 2) return true;
    std::vector<Interval> u;
    for (std::size_t j = 0; j < env.col_x.size(); ++j) {
      const double x = env.col_x[j];
      u.clear();
      for (int k = 0; k < n; ++k) {
        for (const auto& [lo, hi] : env.col_iv[j])
          u.emplace_back(lo + y0 + k * g.s, hi + y0 + k * g.s);
      }
      const double inf = std::numeric_limits<double>::infinity();
      if (closed) {
        // The end clean-up: the leg along y = R covers y <= 2R; the wall legs cover their
        // bands up to where cycle 0 touched the walls.
        u.emplace_back(-inf, 2 * g.R);
        if (x <= -g.a + g.R) u.emplace_back(-inf, y0 + g.R);
        if (x >= g.a - g.R) u.emplace_back(-inf, y0 + 0.5 * g.s + g.R);
      } else {
        u.emplace_back(-inf, x < approach_hi ? y0 : 0.0);  // approach; nothing below y = 0
      }
      merge(u);
      if (u.front().second < g.L + margin) return false;
    }
    return true;
  };
  int cycles = n_front;
  const int n_max = n_front + checked_count(std::ceil(2 * (g.a + g.b + g.R) / g.s)) + 8;
  while (!covers(cycles)) {
    if (++cycles > n_max) {
      throw Error(fmt::format("planner: {} cycles do not cover the slot; this is a bug", n_max));
    }
  }

  PlannedPath out;
  Builder bld(out.path, mirror);
  const Vec3 p0(-g.a, y0, g.zf);
  // Room beside the entry point: along x for a ramp (the slot's free width) and, for a
  // helix, the smaller of the free width and the distance to the closed end.
  const double room_ramp = 2 * g.a;
  const double room =
      job.path.entry == EntryType::helix ? std::min(2 * g.a, 2 * (y0 - g.R)) : room_ramp;
  emit_entry(bld, g, job.path, p0, false, room);
  for (int k = 0; k < cycles; ++k) {
    bld.mark_cycle();
    emit_cycle(bld, g, y0 + g.s * k);
  }
  bld.line_to(Vec3(bld.here().x(), bld.here().y(), g.safe_z), Motion::rapid, g.rapid);
  if (closed) {
    // End clean-up of the closed start: the cycles leave the corners behind the rear
    // envelope of cycle 0. Back above the first cycle's start (cut already, so the tool
    // descends into air), then a U at depth: down the left wall to y = R, across the end,
    // up the right wall to where cycle 0 touched it. Only the R fillets a round tool cannot
    // cut remain (docs/models.md, "Closed start").
    const double y_right = y0 + 0.5 * g.s;
    bld.line_to(Vec3(-g.a, y0, g.safe_z), Motion::rapid, g.rapid);
    bld.line_to(Vec3(-g.a, y0, g.clearance), Motion::rapid, g.rapid);
    bld.line_to(Vec3(-g.a, y0, g.zf), Motion::feed, g.entry_feed);
    bld.line_to(Vec3(-g.a, g.R, g.zf), Motion::feed, g.feed);
    bld.line_to(Vec3(g.a, g.R, g.zf), Motion::feed, g.feed);
    bld.line_to(Vec3(g.a, y_right, g.zf), Motion::feed, g.feed);
    bld.line_to(Vec3(g.a, y_right, g.safe_z), Motion::rapid, g.rapid);
  }

  out.info.trochoid_radius_mm = g.a;
  out.info.semi_axis_feed_mm = g.b;
  out.info.first_cycle_y_mm = y0;
  out.info.cycles = cycles;
  out.info.cycle_length_mm = env.cycle_length;
  out.info.closed_start = closed;
  return out;
}

}  // namespace trochomill
