// The interpreter's motion: a move's end point, its feed, straight moves and arcs turned into
// the output frame, appended to the path and traced (GcodeMove).
#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <string_view>
#include <utility>
#include <vector>

#include "interp.hpp"
#include "trochomill/error.hpp"
#include "trochomill/gcode.hpp"
#include "trochomill/geometry.hpp"
#include "trochomill/io.hpp"
#include "trochomill/units.hpp"

namespace trochomill::gcode_detail {

// The end point of a move in program coordinates (mm): the axis words in the distance mode,
// or G53's machine coordinates.
// The axes besides X Y Z go to xnext_ (program coordinates) for the move the block makes.
Vec3 Interpreter::ends(bool g53) {
  Vec3 t = cur_pos_;
  xnext_ = xpos_;
  if (block_.has_extra()) {
    for (int k = 0; k < 6; ++k) {
      const auto ku = static_cast<std::size_t>(k);
      if (!block_.has(kExtraAxes[ku])) continue;
      const double v = xlen(k);
      xnext_[ku] = g53 ? xfrom_machine(k, v) : absolute_ ? v : xpos_[ku] + v;
    }
  }
  if (block_.has_polar() && g53) {
    fail_at(block_.polar_col(), "Cannot use polar coordinates with G53");
  }
  if (g53) {
    note_tool_length("G53");
    const Vec3 m = to_machine_tip(cur_pos_) + Vec3(0, 0, tool_z_);
    Vec3 target_machine = m;
    for (int a = 0; a < 3; ++a) {
      const char c = static_cast<char>('x' + a);
      if (block_.has(c)) target_machine[a] = len(c);
    }
    target_machine.z() -= tool_z_;
    return from_machine_tip(target_machine);
  }
  for (int a = 0; a < 3; ++a) {
    const char c = static_cast<char>('x' + a);
    if (block_.has(c)) t[a] = absolute_ ? len(c) : cur_pos_[a] + len(c);
  }
  if (block_.has_polar()) polar_end(t.x(), t.y());
  return t;
}

// The XY end of polar words as LinuxCNC's find_ends takes them: in G90 @ and ^ are the
// distance from the origin and the angle from +X (the missing one the current point's); in
// G91 they add to the current point's distance and angle. The XY plane (G17) only.
void Interpreter::polar_end(double& x, double& y) const {
  if (plane_ != Plane::xy) {
    fail_at(block_.polar_col(), "polar coordinates (@, ^) are in the XY plane (G17) only");
  }
  const bool use_r = block_.has_polar_r, use_a = block_.has_polar_a;
  if (block_.has('x') || block_.has('y')) {
    fail_at(block_.col(block_.has('x') ? 'x' : 'y'),
            "Cannot specify X or Y words with polar coordinate");
  }
  const double r_word = use_r ? block_.polar_r * unit_ : 0.0;
  const double a_word = use_a ? block_.polar_a_deg * kPi / 180 : 0.0;
  if (absolute_) {
    if (use_r && !use_a && x == 0 && y == 0) {
      fail_at(block_.polar_r_col, "Must specify angle in polar coordinate if at the origin");
    }
    const double r = use_r ? r_word : std::hypot(y, x);
    const double a = use_a ? a_word : std::atan2(y, x);
    x = r * std::cos(a);
    y = r * std::sin(a);
    return;
  }
  if (x == 0 && y == 0) {
    fail_at(block_.polar_col(),
            use_r ? "Incremental motion with polar coordinates is indeterminate when at the origin"
                  : "G91 motion with polar coordinates is indeterminate when at the origin");
  }
  const double r = std::hypot(y, x) + r_word, a = std::atan2(y, x) + a_word;
  x = r * std::cos(a);
  y = r * std::sin(a);
}

void Interpreter::move(bool g53, std::uint32_t column) {
  if (g53 && motion_ != 0 && motion_ != 10) {
    fail_at(column, "G53 moves need G0 or G1 (a straight move in machine coordinates)");
  }
  if (g53) comp_.refuse(column, "G53 (a move in machine coordinates)");
  const Vec3 target = ends(g53);
  if (motion_ >= 382 && motion_ <= 385) {
    probe(target, column);
    return;
  }
  if (comp_.moves() && xnext_ != xpos_) {
    fail_at(block_.col(*std::find_if(kExtraAxes.begin(), kExtraAxes.end(),
                                     [&](char c) { return block_.has(c); })),
            "A B C U V W motion with cutter radius compensation on is not supported (the "
            "compensated moves wait for their corners; program the turn with G40)");
  }
  if (motion_ <= 10) {
    comp_.allow_arcs();
    if (comp_.moves()) {
      comp_.line(target, motion_ == 0, column);
    } else {
      plain_move_ = !g53 && (motion_ == 0 || feed_mode_ == FeedMode::per_minute) && xnext_ == xpos_;
      emit_line(target, motion_ == 0, column);
      plain_move_ = false;
    }
    cur_pos_ = target;
    xpos_ = xnext_;
    return;
  }
  if (comp_.arc_not_allowed()) {
    fail_at(column,
            "the move right after cutter compensation ends (G40) must be straight, "
            "not an arc (the tool is a radius away from the programmed point)");
  }
  if (comp_.moves()) {
    comp_.arc(target, column);
    cur_pos_ = target;
    return;
  }
  plain_move_ = feed_mode_ == FeedMode::per_minute && xnext_ == xpos_;
  arc(target, column);
  plain_move_ = false;
  xpos_ = xnext_;
}

// G38.2-G38.5, a probing move: read as a feed move to its end (where a probe stops at contact
// no reading of the program can know), the probe's result parameters set as LinuxCNC's
// preview sets them (#5061-#5063 the end point, #5070 = 0: not tripped), with a warning once.
// Refused as LinuxCNC refuses it: with cutter compensation on, in inverse time, G38.2 and
// G38.4 of zero length.
void Interpreter::probe(const Vec3& target, std::uint32_t column) {
  const std::string name = code_name('G', motion_);
  comp_.refuse(column, fmt::format("{} (probing)", name));
  if (feed_mode_ == FeedMode::inverse_time) {
    fail_at(column, fmt::format("{}: cannot probe in inverse time feed mode (G93)", name));
  }
  // G38.3 and G38.5 (no error when the probe does not trip) may stay where they are.
  if ((motion_ == 382 || motion_ == 384) && (target - cur_pos_).norm() <= 1e-9) {
    fail_at(column, fmt::format("{}: Start point too close to probe point (the probe move "
                                "has no length)",
                                name));
  }
  if (!probe_warned_) {
    probe_warned_ = true;
    warn(
        fmt::format("{} (probing) read as a feed move to its end point: a probe stops where "
                    "it touches, which reading the program cannot know; as in LinuxCNC's "
                    "preview, #5061-#5063 are that end point and #5070 is 0 (not tripped)",
                    name));
  }
  emit_line(target, false, column);
  cur_pos_ = target;
  xpos_ = xnext_;
  for (int a = 0; a < 3; ++a) params_[5061 + static_cast<std::size_t>(a)] = target[a] / unit_;
  params_[5070] = 0;
}

double Interpreter::feed_for(double length_mm, std::uint32_t column) {
  double f = 0;
  switch (feed_mode_) {
    case FeedMode::per_minute:
      if (!(feed_ > 0)) {
        fail_at(column, feed_given_ ? "feed move at F0: program a feed F > 0 (mm/min)"
                                    : "feed move with no feed rate: program F before G1/G2/G3");
      }
      f = feed_;
      break;
    case FeedMode::inverse_time:
      if (inverse_f_ < 0) {
        fail_at(column, "inverse-time feed (G93): every feed move needs its own F");
      }
      if (!(inverse_f_ > 0)) fail_at(column, "inverse-time feed F0: the move would never end");
      f = length_mm * inverse_f_;  // the move takes 1/F minutes
      break;
    case FeedMode::per_rev:
      if (!(feed_ > 0)) fail_at(column, "feed per revolution (G95) with no feed F > 0");
      if (!(speed_ > 0)) {
        fail_at(column, "feed per revolution (G95) with the spindle speed S0: program S");
      }
      f = feed_ * spindle_rpm(column);
      break;
  }
  return f;
}

double Interpreter::spindle_rpm(std::uint32_t column) {
  if (!css_) return speed_;
  if (!css_warned_) {
    css_warned_ = true;
    warn(
        "G96 (constant surface speed): a move at a feed per revolution or spindle-synchronized "
        "runs at the spindle speed of its start's X (S over the circumference there, at most "
        "D)");
  }
  // LinuxCNC's motion: S m/min (G20: ft/min) over 2 pi |X| (X from the program's zero).
  const double r_mm = std::abs(cur_pos_.x());
  const double per_min_mm = speed_ * (unit_ == 1.0 ? 1000.0 : 304.8);
  double rpm = r_mm > 0 ? per_min_mm / (2 * kPi * r_mm) : std::numeric_limits<double>::infinity();
  if (css_max_rpm_ > 0) rpm = std::min(rpm, css_max_rpm_);
  if (!std::isfinite(rpm)) {
    fail_at(column,
            "G96 without D at X0: the spindle speed would be unbounded (give D, the most rpm)");
  }
  prog_.info.max_spindle_rpm = std::max(prog_.info.max_spindle_rpm, rpm);
  return rpm;
}

void Interpreter::note_feed(double f) {
  if (!(f > 0)) return;
  if (prog_.info.min_feed_mm_per_min == 0 || f < prog_.info.min_feed_mm_per_min) {
    prog_.info.min_feed_mm_per_min = f;
  }
  prog_.info.max_feed_mm_per_min = std::max(prog_.info.max_feed_mm_per_min, f);
}

void Interpreter::check_target(const Vec3& out, std::uint32_t column) const {
  if (!(out.cwiseAbs().maxCoeff() <= kMaxCoordinate)) {
    fail_at(column, fmt::format("the move reaches X{:g} Y{:g} Z{:g} mm, beyond +-1e6 mm "
                                "(incremental moves add up)",
                                out.x(), out.y(), out.z()));
  }
}

// A straight move to program position `target`. `starts` marks a move that fixes every axis
// (G28 without axis words): it starts the path like an XY move.
void Interpreter::emit_line(const Vec3& target, bool rapid, std::uint32_t column, bool starts) {
  put_line(to_out(target), rapid, -1, column, cur_.source, cur_.line_no,
           starts || block_.has('x') || block_.has('y') || block_.has_polar());
}

// A straight move to `end` (output frame) at feed f (mm/min; < 0: the feed mode's), made by
// line `line` of source `source`. `xy` marks a move that fixes X and Y (it starts the path).
void Interpreter::put_line(const Vec3& end, bool rapid, double f, std::uint32_t column,
                           std::size_t source, std::size_t line, bool xy) {
  check_target(end, column);
  GcodeMove mv;
  mv.kind = rapid ? GcodeMove::Kind::rapid : GcodeMove::Kind::feed;
  mv.start_mm = started_ ? out_pos_ : to_out(cur_pos_);
  mv.end_mm = end;
  mv.plane = plane_code();
  describe(mv, source, line);
  const ExtraAxes xend = extras_out(mv);
  if (!started_) {
    // The machine's position before the program is unknown: the first move in X or Y only
    // establishes where the path starts.
    mv.feed_mm_per_min = rapid ? opt_.rapid_rate_mm_per_min : 0;
    if (!rapid) mv.feed_mm_per_min = f >= 0 ? f : feed_for((end - mv.start_mm).norm(), column);
    trace(mv);
    out_pos_ = end;
    xout_ = xend;
    started_ = xy;
    return;
  }
  const double length = (end - out_pos_).norm();
  if (length == 0 && !rapid && xend != xout_) {
    prog_.info.extra_only_time_s += extra_time_s(xend, column);
  }
  if (rapid) {
    f = opt_.rapid_rate_mm_per_min;
  } else {
    if (f < 0) f = feed_for(length, column);
    note_feed(f);
  }
  mv.feed_mm_per_min = f;
  mv.path_started = true;
  if (length > 0) {
    mv.segment = append(Segment::line(out_pos_, end, rapid ? Motion::rapid : Motion::feed, f),
                        column, source, line);
  }
  trace(mv);
  out_pos_ = end;
  xout_ = xend;
}

// The axes besides X Y Z at the end of the move being made (xnext_), in the output frame, put
// in the move; the ones that move noted with their range.
ExtraAxes Interpreter::extras_out(GcodeMove& mv) {
  if (!extra_seen_) return xout_;
  ExtraAxes e{};
  for (int k = 0; k < 6; ++k) {
    const auto ku = static_cast<std::size_t>(k);
    e[ku] = xmachine(k, xnext_[ku]) - xout_origin_[ku];
    if (e[ku] != xout_[ku]) {
      std::string& used = prog_.info.extra_axes;
      const char name = upper(kExtraAxes[ku]);
      if (used.find(name) == std::string::npos) {
        used += name;
        std::sort(used.begin(), used.end(), [](char a, char b) {
          return std::string_view("ABCUVW").find(a) < std::string_view("ABCUVW").find(b);
        });
        prog_.info.extra_min[ku] = prog_.info.extra_max[ku] = xout_[ku];
      }
      prog_.info.extra_min[ku] = std::min(prog_.info.extra_min[ku], e[ku]);
      prog_.info.extra_max[ku] = std::max(prog_.info.extra_max[ku], e[ku]);
    }
  }
  mv.extra_end = e;
  mv.extra_axes = true;
  return e;
}

// The time (s) of a feed move that moves only the axes besides X Y Z to `out_end` (output
// frame), as LinuxCNC reads F there: along U V W at F mm/min when they move, else along A B C
// at F degrees/min; in G93 1/F minutes.
double Interpreter::extra_time_s(const ExtraAxes& out_end, std::uint32_t column) {
  double uvw = 0, abc = 0;
  for (std::size_t k = 0; k < 6; ++k) {
    const double d = out_end[k] - xout_[k];
    (k >= 3 ? uvw : abc) += d * d;
  }
  uvw = std::sqrt(uvw);
  abc = std::sqrt(abc);
  if (feed_mode_ == FeedMode::inverse_time) {
    (void)feed_for(1.0, column);  // the checks of F
    return 60.0 / inverse_f_;
  }
  const double f = feed_for(0.0, column);  // mm/min (G95: F times S)
  // F is in the program's units per minute: mm or inches for U V W, degrees for A B C.
  return 60.0 * (uvw > 0 ? uvw / f : abc / (f / unit_));
}

// Appends a segment; returns its index in the path (npos: not kept, or of no length).
std::size_t Interpreter::append(Segment seg, std::uint32_t column, std::size_t source,
                                std::size_t line) {
  if (!opt_.keep_path) {
    prog_.summary.add(seg);
    return GcodeMove::npos;
  }
  const std::vector<Segment>& segs = prog_.path.segments();
  const std::size_t n = segs.size();
  if (opt_.max_path_bytes > 0 && n == segs.capacity()) {
    // Checked when the path grows: the next move doubles its buffers (the segments and the
    // two running totals), and the old and new buffers are held at once while they move, so
    // the peak is three times what the buffers hold now. The trace's moves are held too: by
    // the next check twice as many, in a vector that doubles as well (three times again).
    const double cap = static_cast<double>(std::max<std::size_t>(n, 1));
    const double per_move =
        static_cast<double>(sizeof(Segment) + 2 * sizeof(double) + sizeof(SourceLine));
    const double traced =
        opt_.trace ? 3.0 * cap * static_cast<double>(sizeof(GcodeMove) + 64) : 0.0;
    const double peak = 3.0 * cap * per_move + traced;
    if (peak > opt_.max_path_bytes) {
      fail_at(0, fmt::format("the program's path holds {} moves ({}) after {} blocks, "
                             "and the next would take it past the {} the memory limit "
                             "leaves for reading it: does the program loop without end? (a "
                             "long program that does not: raise the memory limit)",
                             n, memory_text(cap * per_move + traced), prog_.info.blocks_executed,
                             memory_text(opt_.max_path_bytes)));
    }
  }
  try {
    prog_.path.append(std::move(seg));
  } catch (const Error& e) {
    fail_at(column, e.what());
  }
  if (prog_.path.segments().size() == n) return GcodeMove::npos;
  prog_.segment_lines.push_back(
      {static_cast<std::uint32_t>(source), static_cast<std::uint32_t>(line)});
  return n;
}

// What a move's block was and the frame its words were in (GcodeMove's rewrite fields).
void Interpreter::describe(GcodeMove& mv, std::size_t source, std::size_t line) const {
  mv.file = sources_[source].name;
  mv.line = line;
  mv.source = source;
  mv.plain = plain_move_ && !transformed();
  mv.motion = motion_ == 0 ? 0 : motion_ == 10 ? 1 : motion_ == 20 ? 2 : motion_ == 30 ? 3 : -1;
  mv.synchronized = motion_ == 330 || motion_ == 331 || (motion_ == 760 && !fanuc_);
  mv.block_run = prog_.info.blocks_executed;
  mv.program_zero_mm = to_out(Vec3::Zero());
  mv.program_turn_rad = (rotation_ - out_rotation_) * kPi / 180.0;
  mv.unit_mm = unit_;
  mv.incremental = !absolute_;
  mv.ijk_absolute = arc_absolute_;
  mv.feed_mode = feed_mode_ == FeedMode::per_minute     ? 94
                 : feed_mode_ == FeedMode::inverse_time ? 93
                                                        : 95;
  mv.feed_word = feed_;
  mv.feed_before = block_feed_before_;
  mv.feed_events_before = block_feed_events_;
  mv.feed_events = feed_events_;
}

// The arc of this block's words from `from` to `target` (program mm): its centre from I J K
// (moved onto the chord's bisector) or R, its sweep with P turns.
ArcData Interpreter::arc_data(const Vec3& from, const Vec3& target, std::uint32_t column) const {
  const double u = unit_;
  // The plane: e1, e2 span it, n = e1 x e2 (G17: XY/Z, G18: ZX/Y, G19: YZ/X); positive
  // angles turn from e1 to e2 (G3).
  int i1 = 0, i2 = 1, in = 2;
  char o1 = 'i', o2 = 'j';
  if (plane_ == Plane::zx) {
    i1 = 2;
    i2 = 0;
    in = 1;
    o1 = 'k';
    o2 = 'i';
  } else if (plane_ == Plane::yz) {
    i1 = 1;
    i2 = 2;
    in = 0;
    o1 = 'j';
    o2 = 'k';
  }
  const double s1 = from[i1], s2 = from[i2], t1 = target[i1], t2 = target[i2];
  const bool ccw = motion_ == 30;
  double c1, c2;
  if (block_.has('r')) {
    const double rr = len('r');
    const double dx = t1 - s1, dy = t2 - s2, chord = std::hypot(dx, dy);
    if (chord <= 1e-12) fail_at(column, "an R-form arc cannot be a full circle (end = start)");
    if (std::abs(rr) * 2 < chord - opt_.arc_radius_tolerance_mm) {
      fail_at(column, fmt::format("arc radius R{:g} is smaller than half the chord ({:.4f} {})",
                                  block_['r'], 0.5 * chord / u, unit_name()));
    }
    const double h = std::sqrt(std::max(0.0, rr * rr - 0.25 * chord * chord));
    // Centre left of the chord for a ccw arc of <= 180 degrees, right for cw; R < 0 flips.
    double side = ccw ? 1.0 : -1.0;
    if (rr < 0) side = -side;
    c1 = 0.5 * (s1 + t1) - side * h * dy / chord;
    c2 = 0.5 * (s2 + t2) + side * h * dx / chord;
  } else {
    if (!block_.has(o1) && !block_.has(o2)) {
      fail_at(column, fmt::format("arc needs its centre ({} or {} for the G{} plane) or a radius R",
                                  upper(o1), upper(o2), plane_code()));
    }
    const double d1 = block_.has(o1) ? len(o1) : 0.0, d2 = block_.has(o2) ? len(o2) : 0.0;
    c1 = arc_absolute_ ? d1 : s1 + d1;
    c2 = arc_absolute_ ? d2 : s2 + d2;
    const double r0 = std::hypot(s1 - c1, s2 - c2), r1 = std::hypot(t1 - c1, t2 - c2);
    // LinuxCNC's limits (its arc_data_ijk): the radii may differ by 0.02 sqrt(2) mm (0.002
    // sqrt(2) in in G20), or by more when that is at most 0.1 % of the larger, up to 100 times
    // that. The centre stays where it is programmed; the arc then ends at its end point as a
    // spiral (put_arc), as LinuxCNC's motion runs it.
    const double abs_tol = (unit_ == 1.0 ? 0.02 : 0.002 * 25.4) * std::sqrt(2.0);
    const double abs_err = std::abs(r0 - r1), rel_err = abs_err / std::max(r0, r1);
    if (abs_err > 100 * abs_tol || (abs_err > abs_tol && rel_err > 0.001)) {
      fail_at(column,
              fmt::format("arc radius to the end ({:.4f} {}) differs from the radius to the start "
                          "({:.4f} {}) by {:.4g} {} ({:.3g} %; allowed, as LinuxCNC: {:.4g} {}, or "
                          "0.1 % up to {:.4g} {})",
                          r1 / u, unit_name(), r0 / u, unit_name(), abs_err / u, unit_name(),
                          100 * rel_err, abs_tol / u, unit_name(), 100 * abs_tol / u, unit_name()));
    }
  }
  const double rad = std::hypot(s1 - c1, s2 - c2);
  if (rad <= 1e-9) fail_at(column, "arc radius is zero");
  const double a0 = std::atan2(s2 - c2, s1 - c1), a1 = std::atan2(t2 - c2, t1 - c1);
  double sweep;
  const bool full = std::hypot(t1 - s1, t2 - s2) <= 1e-9;
  if (ccw) {
    sweep = full ? kTwoPi : std::fmod(a1 - a0 + 2 * kTwoPi, kTwoPi);
    if (sweep <= 0) sweep += kTwoPi;
  } else {
    sweep = full ? -kTwoPi : -std::fmod(a0 - a1 + 2 * kTwoPi, kTwoPi);
    if (sweep >= 0) sweep -= kTwoPi;
  }
  if (block_.has('p')) {
    const double p = block_['p'];
    if (p < 1 || std::abs(p - std::round(p)) > 1e-9) {
      fail_at(block_.col('p'), "arc turns P must be a whole number >= 1");
    }
    if (p > 1e4) fail_at(block_.col('p'), "arc turns P beyond 10000");
    sweep += (ccw ? 1.0 : -1.0) * kTwoPi * (std::round(p) - 1.0);
  }
  ArcData d;
  d.i1 = i1;
  d.i2 = i2;
  d.in = in;
  d.c1 = c1;
  d.c2 = c2;
  d.rad = rad;
  d.sweep = sweep;
  return d;
}

void Interpreter::arc(const Vec3& target, std::uint32_t column) {
  const ArcData d = arc_data(cur_pos_, target, column);
  // A circle or helix: its length in closed form gives the feed (G93) before the segment is
  // made once, at that feed.
  const double length = std::hypot(d.rad * d.sweep, target[d.in] - cur_pos_[d.in]);
  const double f = feed_for(length, column);
  const Vec3 from = cur_pos_;
  cur_pos_ = target;
  put_arc(from, d, target[d.in], f, column, cur_.source, cur_.line_no,
          block_.has('x') || block_.has('y') || block_.has_polar(), &target);
}

// An arc from `from` (program mm) about d's centre through d.sweep, ending at `axial` along
// the plane's normal, at feed f (mm/min), made by line `line` of source `source`. With
// `exact_end` (program mm) the arc ends there: a radius at the end that differs from the one
// at the start (cutter compensation's corners, rounding) becomes a drift spread along it, as
// a control runs such an arc as a spiral.
void Interpreter::put_arc(const Vec3& from, const ArcData& d, double axial, double f,
                          std::uint32_t column, std::size_t source, std::size_t line, bool xy,
                          const Vec3* exact_end) {
  const int i1 = d.i1, i2 = d.i2, in = d.in;
  const double rad = d.rad, sweep = d.sweep;
  const double a0 = std::atan2(from[i2] - d.c2, from[i1] - d.c1);
  Vec3 e1 = Vec3::Zero(), e2 = Vec3::Zero(), nrm = Vec3::Zero();
  e1[i1] = 1;
  e2[i2] = 1;
  nrm[in] = 1;
  Vec3 c = Vec3::Zero();
  c[i1] = d.c1;
  c[i2] = d.c2;
  c[in] = from[in];
  const Vec3 A = rad * (std::cos(a0) * e1 + std::sin(a0) * e2);
  const Vec3 B = rad * (-std::sin(a0) * e1 + std::cos(a0) * e2);
  Vec3 V = nrm * ((axial - from[in]) / sweep);
  if (exact_end != nullptr) {
    const Vec3 miss = *exact_end - (c + A * std::cos(sweep) + B * std::sin(sweep) + V * sweep);
    if (miss.norm() > 1e-9) V += miss / sweep;
  }
  const Vec3 c_out = to_out(c), A_out = dir_to_out(A), B_out = dir_to_out(B), V_out = dir_to_out(V);
  Segment seg = Segment::curve(c_out, A_out, B_out, V_out, 0.0, sweep, Motion::feed, f);
  const Vec3 end = seg.end();
  check_target(end, column);
  GcodeMove mv;
  mv.kind = GcodeMove::Kind::arc;
  mv.start_mm = started_ ? out_pos_ : to_out(from);
  mv.end_mm = end;
  mv.centre_mm = c_out;
  mv.axis = dir_to_out(nrm);
  mv.sweep_rad = sweep;
  if (scale_on_) {
    // Scaled (G51): the plane's normal stays a unit normal of its sign; a mirror of one of
    // the plane's axes turns the arc the other way about it.
    mv.axis = mv.axis.normalized() * (scale_k_[in] < 0 ? -1.0 : 1.0);
    for (int a = 0; a < 3; ++a) mv.axis[a] += 0.0;  // no negative zeros
    if (scale_k_[i1] * scale_k_[i2] < 0) mv.sweep_rad = -sweep;
  }
  mv.plane = plane_code();
  describe(mv, source, line);
  mv.feed_mm_per_min = f;
  const ExtraAxes xend = extras_out(mv);
  if (!started_) {
    trace(mv);
    out_pos_ = end;
    xout_ = xend;
    started_ = xy;
    return;
  }
  if ((seg.start() - out_pos_).norm() > 1e-9) {
    fail_at(column,
            "an arc that starts where the tool is not (right after a tool length change "
            "G43/G49 or the end of cutter compensation G40): program a straight move first");
  }
  note_feed(f);
  mv.path_started = true;
  mv.segment = append(std::move(seg), column, source, line);
  trace(mv);
  out_pos_ = end;
  xout_ = xend;
}

}  // namespace trochomill::gcode_detail

namespace trochomill::gcode_detail {

// G5 (a cubic) and G5.1 (a quadratic) as LinuxCNC 2.9's convert_spline reads them: Bézier
// curves in the XY plane from the current point; G5's first control point I J from the start
// (left out: the last G5's second control point mirrored, for a smooth join), its second P Q
// from the end; G5.1's one control point I J from the start.
void Interpreter::spline(std::uint32_t column) {
  if (comp_.on()) fail_at(column, "Cannot convert spline with cutter radius compensation");
  if (plane_ != Plane::xy) fail_at(column, "Splines must be in the XY plane");
  for (const char c : std::string_view("zabc")) {
    if (block_.has(c)) fail_at(block_.col(c), "Splines may not have motion in Z, A, B, or C");
  }
  const Vec3 end = ends(false);
  std::vector<Vec3> points{cur_pos_};
  if (motion_ == 51) {
    if (!block_.has('i') || !block_.has('j')) {
      fail_at(column, "Must specify both I and J with G5.1");
    }
    points.push_back(cur_pos_ + Vec3(len('i'), len('j'), 0));
  } else {
    double i = spline_i_, j = spline_j_;
    if (block_.has('i') != block_.has('j')) {
      fail_at(column, "Must specify both I and J, or neither");
    }
    if (block_.has('i')) {
      i = len('i');
      j = len('j');
    }
    if (!block_.has('p') || !block_.has('q')) fail_at(column, "Must specify both P and Q with G5");
    check_range('p');  // a length here (P is not one in most codes: not in check_words)
    points.push_back(cur_pos_ + Vec3(i, j, 0));
    points.push_back(end + Vec3(len('p'), len('q'), 0));
    spline_i_ = -len('p');
    spline_j_ = -len('q');
  }
  points.push_back(end);
  put_curve(points, std::vector<double>(points.size(), 1.0), static_cast<int>(points.size()),
            column);
  cur_pos_ = end;
  xpos_ = xnext_;
}

// A block of G5.2 (LinuxCNC 2.9's convert_nurbs): a control point X Y with its weight P (the
// first block may give the start's weight P alone) and the order L (3 unless above 3); the
// points wait for G5.3. `fresh`: the block starts a new curve (the mode was not G5.2).
void Interpreter::nurbs_point(bool fresh, std::uint32_t column) {
  if (comp_.on()) fail_at(column, "Cannot convert spline with cutter radius compensation");
  if (plane_ != Plane::xy) fail_at(column, "Splines must be in the XY plane");
  const bool x = block_.has('x'), y = block_.has('y');
  if (x != y) fail_at(column, "You must specify both X and Y coordinates for Control Points");
  if (fresh) {
    nurbs_points_.clear();
    nurbs_weights_.clear();
  }
  const double p = block_.has('p') ? block_['p'] : -1.0;
  if (!x && p > 0 && !nurbs_points_.empty()) {
    fail_at(block_.col('p'), "Can specify P without X and Y only for the first control point");
  }
  if (p <= 0 && (!nurbs_points_.empty() || x)) {
    fail_at(block_.has('p') ? block_.col('p') : column,
            "Must specify positive weight P for every Control Point");
  }
  if (feed_mode_ == FeedMode::per_minute && !(feed_ > 0)) {
    fail_at(column, "Cannot make a NURBS with 0 feedrate");
  }
  if (nurbs_points_.empty()) {
    nurbs_points_.push_back(cur_pos_);
    nurbs_weights_.push_back(!x && p > 0 ? p : 1.0);
    nurbs_order_ = 3;
  }
  if (block_.has('l') && block_['l'] > 3) {
    if (block_['l'] != std::floor(block_['l']) || block_['l'] > 30) {
      fail_at(block_.col('l'), "G5.2's order L must be a whole number 3 .. 30");
    }
    nurbs_order_ = static_cast<int>(block_['l']);
  }
  if (x) {
    // Control points are placed from the curve's start (LinuxCNC moves the current point only
    // at G5.3).
    Vec3 q = ends(false);
    q.z() = cur_pos_.z();
    nurbs_points_.push_back(q);
    nurbs_weights_.push_back(p);
  }
}

// G5.3: the NURBS of the G5.2 blocks before it, from the current point to its last control
// point.
void Interpreter::nurbs_end(std::uint32_t column) {
  if (motion_ != 52 || nurbs_points_.empty()) {
    fail_at(column, "Cannot use G5.3 without G5.2 first");
  }
  if (nurbs_points_.size() < static_cast<std::size_t>(nurbs_order_)) {
    fail_at(column, fmt::format("You must specify a number of control points at least equal to "
                                "the order L = {}",
                                nurbs_order_));
  }
  ++prog_.info.motion_blocks;
  const Vec3 end = nurbs_points_.back();
  put_curve(nurbs_points_, nurbs_weights_, nurbs_order_, column);
  cur_pos_ = end;
  nurbs_points_.clear();
  nurbs_weights_.clear();
  motion_ = -1;
}

// A NURBS of the given order (degree + 1) on LinuxCNC's clamped uniform knots (0 .. n - k + 2,
// the ends repeated k times) in the XY plane at the current height, from the current point:
// fitted with biarcs within spline_tolerance_mm and run at the block's feed (G93: the whole
// curve in 1/F minutes).
void Interpreter::put_curve(const std::vector<Vec3>& points, const std::vector<double>& weights,
                            int order, std::uint32_t column) {
  const std::size_t n = points.size() - 1, k = static_cast<std::size_t>(order);
  std::vector<double> knots;
  for (std::size_t i = 0; i <= n + k; ++i) {
    knots.push_back(i < k    ? 0.0
                    : i <= n ? static_cast<double>(i - k + 1)
                             : static_cast<double>(n - k + 2));
  }
  const NurbsCurve curve(order - 1, std::move(knots), points, weights);
  double extent = 0;
  for (std::size_t i = 1; i < points.size(); ++i) extent += (points[i] - points[i - 1]).norm();
  if (extent <= 1e-9) {
    // Every control point on the start: no motion (LinuxCNC's preview draws nothing either).
    return;
  }
  // Weights a million-fold apart fold the curve into its control polygon's corners, which no
  // bounded set of arcs within the tolerance follows (the fit ran for minutes: a fuzzer's find).
  const auto [wlo, whi] = std::minmax_element(weights.begin(), weights.end());
  if (wlo != weights.end() && *whi > 1e6 * *wlo) {
    fail_at(column, fmt::format("the NURBS weights P differ more than a million-fold ({:g} and "
                                "{:g}): its curve is its control polygon's corners; not read",
                                *wlo, *whi));
  }
  std::vector<FitArc> arcs;
  try {
    arcs = fit_biarcs(curve, curve.u0(), curve.u1(), static_cast<int>(std::max<std::size_t>(4, n)),
                      opt_.spline_tolerance_mm, 100000);
  } catch (const ArcLimit&) {
    fail_at(column, fmt::format("the spline needs more than 100000 arcs within {} mm of its curve",
                                opt_.spline_tolerance_mm));
  } catch (const Error& e) {
    fail_at(column, fmt::format("the spline cannot be followed with arcs: {}", e.what()));
  }
  double length = 0;
  for (const FitArc& a : arcs) {
    length += a.is_line ? (a.end - a.start).norm() : std::abs(a.radius_mm * a.sweep_rad);
  }
  const double f = feed_for(length, column);
  for (const FitArc& a : arcs) {
    Vec3 end = a.end;
    end.z() = cur_pos_.z();
    if (a.is_line) {
      put_line(to_out(end), false, f, column, cur_.source, cur_.line_no, true);
      continue;
    }
    if (a.radius_mm > kMaxCoordinate) {
      // A nearly straight stretch (far control points) fits arcs of radius 1e8 mm and more,
      // whose start recomputed from the centre misses the tool's point by 1e-8 mm, and whose
      // centre no program could give: chords within a tenth of the tolerance of the arc.
      const double chord = std::sqrt(8 * a.radius_mm * 0.1 * opt_.spline_tolerance_mm);
      const double len = std::abs(a.radius_mm * a.sweep_rad);
      const int chords = static_cast<int>(std::min(1e5, std::ceil(len / chord)));
      const double a0 = std::atan2(a.start.y() - a.cy, a.start.x() - a.cx);
      for (int i = 1; i <= chords; ++i) {
        Vec3 q = end;
        if (i < chords) {
          const double t = a0 + a.sweep_rad * i / chords;
          q = Vec3(a.cx + a.radius_mm * std::cos(t), a.cy + a.radius_mm * std::sin(t), end.z());
        }
        put_line(to_out(q), false, f, column, cur_.source, cur_.line_no, true);
      }
      continue;
    }
    ArcData d;
    d.c1 = a.cx;
    d.c2 = a.cy;
    d.rad = a.radius_mm;
    d.sweep = a.sweep_rad;
    Vec3 start = a.start;
    start.z() = cur_pos_.z();
    put_arc(start, d, end.z(), f, column, cur_.source, cur_.line_no, true, &end);
  }
}

}  // namespace trochomill::gcode_detail
