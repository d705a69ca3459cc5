// Cutter radius compensation (G41/G42, G41.1/G42.1, G40) as LinuxCNC runs it: the tool
// centre a radius beside the programmed contour, the moves waiting in a queue for their corner.
#include <fmt/format.h>

#include <cmath>
#include <cstdint>
#include <string>

#include "interp.hpp"
#include "trochomill/gcode.hpp"
#include "trochomill/units.hpp"

namespace trochomill::gcode_detail {

// LinuxCNC's algorithm (docs/gcode.md): the tool centre runs a radius beside the programmed
// contour in the XY plane. Each compensated move waits in a queue until the next one shows
// the corner between them: a concave corner moves the waiting move's end back to where the
// two offset contours meet, a convex one adds an arc about the programmed corner. Positions
// are program mm; the interpreter's cur_pos_ stays the programmed point, centre_ is the tool
// centre.

const Vec3& CutterComp::current() const { return moves() && !first_ ? centre_ : interp_.cur_pos_; }

void CutterComp::refuse(std::uint32_t column, const std::string& what) const {
  if (on()) {
    interp_.fail_at(
        column,
        fmt::format("{} with cutter radius compensation on: cancel it with G40 first", what));
  }
}

// LinuxCNC's find_turn: the sweep (rad) from (x1, y1) to (x2, y2) about (cx, cy), `turn`
// circles counterclockwise (negative: clockwise); 0 for turn 0.
double CutterComp::find_turn(double x1, double y1, double cx, double cy, int turn, double x2,
                             double y2) {
  if (turn == 0) return 0.0;
  double a = std::atan2(y1 - cy, x1 - cx), b = std::atan2(y2 - cy, x2 - cx);
  if (turn > 0) {
    if (b <= a) b += kTwoPi;
    return b - a + (turn - 1) * kTwoPi;
  }
  if (a <= b) a += kTwoPi;
  return b - a + (turn + 1) * kTwoPi;
}

void CutterComp::start(int g, std::uint32_t column) {
  if (interp_.plane_ != Plane::xy) {
    interp_.fail_at(column, "cutter radius compensation is supported in the XY plane (G17) only");
  }
  // Fanuc's G41/G42 in offset mode: the same side and offset again go on as they were.
  if (on() && !interp_.fanuc_) {
    interp_.fail_at(column,
                    "G41/G42 while cutter radius compensation is on: cancel it with G40 first");
  }
  Side side = (g == 410 || g == 411) ? Side::left : Side::right;
  double radius = 0;
  const std::string name = code_name('G', g);
  if (g == 411 || g == 421) {
    if (!interp_.block_.has('d')) {
      interp_.fail_at(column, fmt::format("{} needs the tool diameter in D", name));
    }
    radius = 0.5 * interp_.len('d');
  } else {
    double tool = interp_.tool_loaded_;
    if (interp_.block_.has('d')) {
      tool = interp_.block_['d'];
      if (tool < 0 || tool != std::floor(tool) || tool > 1e6) {
        interp_.fail_at(interp_.block_.col('d'),
                        fmt::format("{} D{:g}: D is a tool number 0 .. 1e6 (its "
                                    "diameter in the tool table sets the offset)",
                                    name, tool));
      }
    }
    if (interp_.fanuc_ && !fanuc_warned_) {
      fanuc_warned_ = true;
      interp_.warn(
          fmt::format("{} read with LinuxCNC's rules: D is the offset register G10 L12/L13 "
                      "set, else a tool of the tool table (half its diameter is the offset), "
                      "and corners follow LinuxCNC; a Fanuc control starts up by its own type",
                      name));
    }
    const auto reg =
        interp_.fanuc_ ? interp_.registers_.find(static_cast<int>(tool)) : interp_.registers_.end();
    if (reg != interp_.registers_.end() && (reg->second.d_geometry || reg->second.d_wear)) {
      // Fanuc's D register (a radius) or Haas's (a diameter, its setting 40 at Diameter) set
      // by G10 L12/L13: geometry (else the table's) plus wear.
      const auto it = interp_.tools_.find(static_cast<int>(tool));
      const double table = it != interp_.tools_.end() ? it->second.diameter_mm : 0.0;
      const double scale = interp_.haas_ ? 0.5 : 1.0;
      radius = reg->second.d_geometry ? scale * *reg->second.d_geometry : 0.5 * table;
      radius += scale * reg->second.d_wear.value_or(0.0);
    } else if (tool == 0) {
      interp_.warn(
          fmt::format("{} with no tool loaded (M6) and no D: the offset is 0, the path is "
                      "not compensated",
                      name));
    } else {
      const auto it = interp_.tools_.find(static_cast<int>(tool));
      if (it == interp_.tools_.end()) {
        // LinuxCNC runs a tool its table lacks with diameter 0; a job's tool stands in.
        const double d = interp_.opt_.missing_tool_diameter_mm;
        interp_.warn(
            fmt::format("{}: tool {:g} is not in the tool table ([machine] tool_table): its "
                        "diameter is taken as {}",
                        name, tool,
                        d > 0 ? fmt::format("the job's tool's, {:g} mm", d)
                              : std::string("0 (as LinuxCNC does): the path is not compensated")));
        radius = 0.5 * d;
      } else {
        radius = 0.5 * it->second.diameter_mm;
      }
    }
  }
  if (radius < 0) {  // a negative diameter offsets to the other side (LinuxCNC)
    radius = -radius;
    side = side == Side::left ? Side::right : Side::left;
  }
  if (on()) {
    if (side == side_ && radius == radius_) return;
    interp_.fail_at(column,
                    "G41/G42 changing the side or the offset while compensating (Fanuc's offset "
                    "mode) is not read: cancel it with G40 first");
  }
  side_ = side;
  radius_ = radius;
  first_ = true;
}

void CutterComp::stop() {
  if (moves() && !first_) {
    move_endpoint_and_flush(centre_.x(), centre_.y(), interp_.block_.g.front().column);
    dequeue();
    arc_not_allowed_ = true;  // the tool is not at the programmed point
  }
  side_ = Side::off;
  first_ = true;
}

// A program stop (M0 M1 M2 M30 M60): the waiting moves run to where they are.
void CutterComp::flush_at_stop(std::uint32_t column) {
  if (queue_.empty()) return;
  move_endpoint_and_flush(centre_.x(), centre_.y(), column);
  dequeue();
}

void CutterComp::enqueue(QueuedMove q, std::uint32_t column) {
  q.source = interp_.cur_.source;
  q.line = interp_.cur_.line_no;
  q.column = column;
  queue_.push_back(q);
}

void CutterComp::set_endpoint(double x, double y) {
  endpoint_[0] = x;
  endpoint_[1] = y;
  endpoint_valid_ = true;
}

// The waiting moves run (in the order queued), from where the last one ended.
void CutterComp::dequeue() {
  endpoint_valid_ = false;
  for (const QueuedMove& q : queue_) {
    if (q.kind == GcodeMove::Kind::arc) {
      ArcData d;
      d.c1 = q.c1;
      d.c2 = q.c2;
      d.rad = std::hypot(emitted_.x() - q.c1, emitted_.y() - q.c2);
      d.sweep = find_turn(emitted_.x(), emitted_.y(), q.c1, q.c2, q.turn, q.end.x(), q.end.y());
      interp_.put_arc(emitted_, d, q.end.z(), q.feed, q.column, q.source, q.line, true, &q.end);
    } else {
      interp_.put_line(interp_.to_out(q.end), q.kind == GcodeMove::Kind::rapid, q.feed, q.column,
                       q.source, q.line, true);
    }
    emitted_ = q.end;
  }
  queue_.clear();
}

// Every waiting move now ends at (x, y): a move that would have to turn back (the corner
// is deeper than the move is long) or an arc that would have to sweep further gouges.
void CutterComp::move_endpoint_and_flush(double x, double y, std::uint32_t column) {
  if (queue_.empty()) return;
  for (QueuedMove& q : queue_) {
    if (q.kind == GcodeMove::Kind::arc) {
      const double r1 = std::hypot(q.end.x() - q.c1, q.end.y() - q.c2);
      const double r2 = std::hypot(x - q.c1, y - q.c2);
      const double l2 = find_turn(endpoint_[0], endpoint_[1], q.c1, q.c2, q.turn, x, y);
      if (std::abs(r1 - r2) > 0.01 * interp_.unit_) {
        interp_.fail_at(column,
                        fmt::format("cutter compensation cannot end the arc of line {} on its "
                                    "circle (radius {:.4f} against {:.4f} mm)",
                                    q.line, r1, r2));
      }
      if (q.original_sweep != 0 && endpoint_valid_ &&
          std::abs(l2) > std::abs(q.original_sweep) + 0.0254) {
        interp_.fail_at(column, fmt::format("the arc of line {} meets a concave corner the "
                                            "compensated tool cannot reach without gouging",
                                            q.line));
      }
    } else if (endpoint_valid_ && q.d1 * (x - endpoint_[0]) + q.d2 * (y - endpoint_[1]) < 0) {
      interp_.fail_at(
          column, fmt::format("the move of line {} meets a concave corner the compensated tool "
                              "cannot reach without gouging (the corner is deeper than the move "
                              "is long)",
                              q.line));
    }
    q.end.x() = x;
    q.end.y() = y;
  }
  dequeue();
  set_endpoint(x, y);
}

// A G0/G1 move to programmed p with compensation on (LinuxCNC's convert_straight_comp1/2).
void CutterComp::line(const Vec3& p, bool rapid, std::uint32_t column) {
  const double r = radius_;
  QueuedMove q;
  q.kind = rapid ? GcodeMove::Kind::rapid : GcodeMove::Kind::feed;
  const Vec3 c = first_ ? interp_.cur_pos_ : centre_;
  q.feed = rapid ? 0 : interp_.feed_for((p - c).norm(), column);
  if (first_) {
    // The entry move: to a radius beside the programmed end, square to the move.
    const double distance = std::hypot(p.x() - c.x(), p.y() - c.y());
    if (distance <= r) {
      interp_.fail_at(column,
                      fmt::format("the move that starts cutter compensation ({:.4f} mm in XY) "
                                  "must be longer than the tool radius ({:.4f} mm)",
                                  distance, r));
    }
    const double alpha = std::atan2(p.y() - c.y(), p.x() - c.x()) + (left() ? kPi / 2 : -kPi / 2);
    q.end = Vec3(p.x() + r * std::cos(alpha), p.y() + r * std::sin(alpha), p.z());
    q.d1 = std::cos(alpha);
    q.d2 = std::sin(alpha);
    set_endpoint(c.x(), c.y());
    emitted_ = c;
    enqueue(q, column);
    first_ = false;
    centre_ = q.end;
    return;
  }
  const Vec3 op = interp_.cur_pos_;
  if (p.x() == op.x() && p.y() == op.y()) {  // no XY motion: waits with the move before
    q.end = Vec3(c.x(), c.y(), p.z());
    enqueue(q, column);
    centre_.z() = p.z();
    return;
  }
  double theta = std::atan2(c.y() - op.y(), c.x() - op.x());
  double alpha = std::atan2(p.y() - op.y(), p.x() - op.x());
  double beta = 0, gamma = 0;
  if (left()) {
    if (theta < alpha) theta += kTwoPi;
    beta = theta - alpha - kPi / 2;
    gamma = kPi / 2;
  } else {
    if (alpha < theta) alpha += kTwoPi;
    beta = alpha - theta - kPi / 2;
    gamma = -kPi / 2;
  }
  const double ex = p.x() + r * std::cos(alpha + gamma), ey = p.y() + r * std::sin(alpha + gamma);
  const double mx = op.x() + r * std::cos(alpha + gamma), my = op.y() + r * std::sin(alpha + gamma);
  bool concave = beta < -kConcaveTol || beta > kPi + kConcaveTol;
  if (!concave && beta > kPi - kConcaveTol && !queue_.empty() &&
      queue_.front().kind == GcodeMove::Kind::arc &&
      ((!left() && queue_.front().turn > 0) || (left() && queue_.front().turn < 0))) {
    concave = true;  // over a round top, then down beside it: stay outside ("h" shape)
  }
  if (!concave && beta > kConcaveTol) {
    // Convex: around the programmed corner on an arc (a rapid goes straight).
    move_endpoint_and_flush(c.x(), c.y(), column);
    QueuedMove corner;
    corner.end = Vec3(mx, my, c.z());
    corner.feed = q.feed;
    if (rapid) {
      corner.kind = GcodeMove::Kind::rapid;
    } else {
      corner.kind = GcodeMove::Kind::arc;
      corner.c1 = op.x();
      corner.c2 = op.y();
      corner.turn = left() ? -1 : 1;
    }
    enqueue(corner, column);
    dequeue();
    set_endpoint(mx, my);
  } else if (concave) {
    if (queue_.empty()) concave_after_stop(column);
    if (queue_.front().kind != GcodeMove::Kind::arc) {
      // Line to line: back along the move before to where the offset lines cross.
      const double half = (beta + kPi) / 2;
      if (half == 0) interp_.fail_at(column, "a zero-degree inside corner cannot be compensated");
      const double retreat = r / std::tan(half);
      move_endpoint_and_flush(c.x() + retreat * std::cos(theta + gamma),
                              c.y() + retreat * std::sin(theta + gamma), column);
    } else {
      // Arc to line: along the compensated arc to where it meets the offset line.
      const QueuedMove& prev = queue_.front();
      const double oldrad = std::hypot(prev.c2 - prev.end.y(), prev.c1 - prev.end.x());
      const double base = std::atan2(p.y() - op.y(), p.x() - op.x());
      const double th = prev.turn > 0 ? base + kPi / 2 : base - kPi / 2;
      const double phi = std::atan2(prev.c2 - op.y(), prev.c1 - op.x());
      const bool in = inside(prev.turn);
      const double uncomp = in ? oldrad + r : oldrad - r;
      const double d = uncomp * std::cos(th - phi);
      const double l = (in ? d - r : d + r) / oldrad;
      if (l > 1.0 || l < -1.0) gouge(column, "an arc and a straight move");
      const double sign = (prev.turn > 0) == in ? -1.0 : 1.0;
      const double angle = sign * std::acos(l) + th + kPi;
      move_endpoint_and_flush(prev.c1 + oldrad * std::cos(angle),
                              prev.c2 + oldrad * std::sin(angle), column);
    }
  } else {
    // Straight on (or tangent from an arc).
    dequeue();
    set_endpoint(c.x(), c.y());
  }
  q.end = Vec3(ex, ey, p.z());
  q.d1 = p.x() - op.x();
  q.d2 = p.y() - op.y();
  enqueue(q, column);
  centre_ = q.end;
}

void CutterComp::gouge(std::uint32_t column, const char* what) const {
  interp_.fail_at(column, fmt::format("{} make a corner the compensated tool cannot fit in without "
                                      "gouging (a tool radius of {:.4f} mm)",
                                      what, radius_));
}

void CutterComp::concave_after_stop(std::uint32_t column) const {
  interp_.fail_at(
      column,
      "a concave corner right after a program stop (M0/M1/M60) with cutter compensation "
      "on: the move before the stop is done, the tool would gouge the corner");
}

// A G2/G3 move to programmed p with compensation on (LinuxCNC's convert_arc_comp1/2).
void CutterComp::arc(const Vec3& p, std::uint32_t column) {
  const double r = radius_;
  const bool ccw = interp_.motion_ == 30;
  const Vec3 op = interp_.cur_pos_;
  const ArcData a = interp_.arc_data(op, p, column);
  const int turns = interp_.block_.has('p') ? static_cast<int>(std::round(interp_.block_['p'])) : 1;
  const int turn = ccw ? turns : -turns;
  const double f = interp_.feed_for(std::hypot(a.rad * a.sweep, p.z() - op.z()), column);
  const double arc_radius = std::hypot(a.c1 - p.x(), a.c2 - p.y());
  const bool in = inside(turn);
  if (in && arc_radius <= r) {
    interp_.fail_at(column,
                    fmt::format("the tool radius ({:.4f} mm) is not less than the radius of "
                                "the arc it runs inside ({:.4f} mm)",
                                r, arc_radius));
  }
  QueuedMove q;
  q.kind = GcodeMove::Kind::arc;
  q.feed = f;
  q.turn = turn;
  q.c1 = a.c1;
  q.c2 = a.c2;
  if (first_) {
    // The entry arc: tangent to the tool where it stands, through the offset end point.
    const Vec3 c = interp_.cur_pos_;
    if (std::hypot(p.x() - c.x(), p.y() - c.y()) <= r) {
      interp_.fail_at(column,
                      fmt::format("the arc that starts cutter compensation must end farther "
                                  "than the tool radius ({:.4f} mm) from where it starts",
                                  r));
    }
    const double gamma =
        in ? std::atan2(a.c2 - p.y(), a.c1 - p.x()) : std::atan2(p.y() - a.c2, p.x() - a.c1);
    const double ex = p.x() + r * std::cos(gamma), ey = p.y() + r * std::sin(gamma);
    const double b_len = std::hypot(c.y() - ey, c.x() - ex) / 2;
    const double ab = std::atan2(a.c2 - ey, a.c1 - ex);
    const double ang = std::atan2(c.y() - ey, c.x() - ex) - ab;
    if (std::abs(std::cos(ang)) < kTolEqual) {
      interp_.fail_at(column,
                      "the arc that starts cutter compensation has no arc through the tool's "
                      "position and the offset end point");
    }
    const double c_len = b_len / std::cos(ang);
    q.c1 = ex + c_len * std::cos(ab);
    q.c2 = ey + c_len * std::sin(ab);
    q.end = Vec3(ex, ey, p.z());
    q.original_sweep = find_turn(c.x(), c.y(), q.c1, q.c2, turn, ex, ey);
    first_ = false;
    emitted_ = c;
    enqueue(q, column);
    centre_ = q.end;
    return;
  }
  const Vec3 c = centre_;
  double theta = std::atan2(c.y() - op.y(), c.x() - op.x());
  theta = left() ? theta - kPi / 2 : theta + kPi / 2;
  double delta = std::atan2(a.c2 - op.y(), a.c1 - op.x());
  const double alpha = ccw ? delta - kPi / 2 : delta + kPi / 2;
  double beta = left() ? theta - alpha : alpha - theta;
  beta = beta > 1.5 * kPi ? beta - kTwoPi : beta < -kPi / 2 ? beta + kTwoPi : beta;
  double gamma;
  if ((left() && ccw) || (!left() && !ccw)) {
    gamma = std::atan2(a.c2 - p.y(), a.c1 - p.x());  // the tool inside the arc
  } else {
    gamma = std::atan2(p.y() - a.c2, p.x() - a.c1);
    delta += kPi;
  }
  const double ex = p.x() + r * std::cos(gamma), ey = p.y() + r * std::sin(gamma);
  q.end = Vec3(ex, ey, p.z());
  q.original_sweep = find_turn(op.x(), op.y(), a.c1, a.c2, turn, p.x(), p.y());
  if (beta < -kConcaveTol || beta > kPi + kConcaveTol ||
      (std::abs(beta - kPi) < kConcaveTol && !in)) {
    // Concave.
    if (queue_.empty()) concave_after_stop(column);
    if (queue_.front().kind != GcodeMove::Kind::arc) {
      // Line to arc: back along the line to where it meets the offset arc.
      const double cy = arc_radius * std::sin(beta - kPi / 2);
      const double from_centre = in ? arc_radius - r : arc_radius + r;
      const double l = (in ? cy + r : cy - r) / from_centre;
      if (l > 1.0 || l < -1.0) gouge(column, "a straight move and an arc");
      double angle;
      if (in) {
        angle = turn > 0 ? theta + std::asin(l) : theta - std::asin(l);
      } else {
        angle = turn > 0 ? theta + kPi - std::asin(l) : theta + kPi + std::asin(l);
      }
      move_endpoint_and_flush(a.c1 + from_centre * std::cos(angle),
                              a.c2 + from_centre * std::sin(angle), column);
    } else {
      // Arc to arc: where the two offset circles cross.
      const QueuedMove& prev = queue_.front();
      const double oldrad = std::hypot(prev.c2 - prev.end.y(), prev.c1 - prev.end.x());
      const double newrad = in ? arc_radius - r : arc_radius + r;
      const double cc = std::hypot(prev.c2 - a.c2, prev.c1 - a.c1);
      if (oldrad == 0 || cc == 0) {
        interp_.fail_at(column,
                        "an arc after an arc about the same centre makes no corner to "
                        "compensate (the arcs share their centre)");
      }
      const double k = (oldrad * oldrad + cc * cc - newrad * newrad) / (2 * oldrad * cc);
      if (k > 1.0 || k < -1.0) gouge(column, "two arcs");
      const double pullback = std::acos(k);
      const double dir_cc = std::atan2(a.c2 - prev.c2, a.c1 - prev.c1);
      const bool plus = inside(prev.turn) == (turn > 0);
      const double dir = plus ? dir_cc + pullback : dir_cc - pullback;
      move_endpoint_and_flush(prev.c1 + oldrad * std::cos(dir), prev.c2 + oldrad * std::sin(dir),
                              column);
    }
  } else if (beta > kConcaveTol) {
    // Convex: around the programmed corner on an arc first.
    const double mx = op.x() + r * std::cos(delta), my = op.y() + r * std::sin(delta);
    dequeue();
    QueuedMove corner;
    corner.kind = GcodeMove::Kind::arc;
    corner.end = Vec3(mx, my, c.z());
    corner.c1 = op.x();
    corner.c2 = op.y();
    corner.turn = left() ? -1 : 1;
    corner.feed = f;
    enqueue(corner, column);
    dequeue();
    set_endpoint(mx, my);
  } else {
    dequeue();  // tangent
    set_endpoint(c.x(), c.y());
  }
  enqueue(q, column);
  centre_ = q.end;
}

}  // namespace trochomill::gcode_detail
