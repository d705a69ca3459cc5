// Tool paths as sequences of exact primitives, their arc-length parametrisation, timing,
// sampling (by time, path length or spindle angle) and tooth-tip trajectories; and the
// planner of the five trochoidal slot families (docs/models.md sections 1-3; Wagih 2023 Eq. 1).
// Frame: slot along +Y, width along X centred on x = 0, top face z = 0 (mm).
#pragma once

#include <Eigen/Geometry>
#include <cstddef>
#include <functional>
#include <limits>
#include <utility>
#include <vector>

#include "trochomill/geometry.hpp"
#include "trochomill/job.hpp"

namespace trochomill {

enum class Motion { rapid, feed };

/// One exact primitive. Two kinds:
///  - line: p(u) = p0 + u (p1 - p0), u in [0, 1];
///  - curve: p(u) = c + A cos u + B sin u + V u, u in [u0, u1] (u1 may be < u0). This one
///    form is exact for circular arcs and helices (|A| = |B|, A.B = 0, V along A x B),
///    elliptical arcs (V = 0) and the drifting ellipses / trochoids of the elliptical
///    families (V in the plane).
/// Positions are mm; the arc length s (mm) runs from 0 at the start to length_mm().
class Segment {
 public:
  enum class Kind { line, curve };

  [[nodiscard]] static Segment line(const Vec3& p0, const Vec3& p1, Motion motion,
                                    double speed_mm_per_min);
  [[nodiscard]] static Segment curve(const Vec3& center, const Vec3& a, const Vec3& b,
                                     const Vec3& v, double u0_rad, double u1_rad, Motion motion,
                                     double speed_mm_per_min);
  /// Circular arc (or helix when z1 != z0) in the XY plane: centre (cx, cy), radius (mm),
  /// start angle and signed sweep (rad, positive = counter-clockwise seen from +Z).
  [[nodiscard]] static Segment arc_xy(double cx, double cy, double radius_mm,
                                      double start_angle_rad, double sweep_rad, double z0_mm,
                                      double z1_mm, Motion motion, double speed_mm_per_min);

  [[nodiscard]] Kind kind() const noexcept { return kind_; }
  [[nodiscard]] Motion motion() const noexcept { return motion_; }
  /// Speed along the path (mm/min): programmed feed, or the rapid rate for rapids.
  [[nodiscard]] double speed_mm_per_min() const noexcept { return speed_mm_per_min_; }
  [[nodiscard]] double length_mm() const noexcept { return length_mm_; }
  [[nodiscard]] Vec3 start() const { return point_u(u0_); }
  [[nodiscard]] Vec3 end() const { return point_u(u1_); }

  /// Parameter u at arc length s (mm from the segment start), exact to ~1e-12 mm.
  [[nodiscard]] double u_at_length(double s_mm) const;
  [[nodiscard]] Vec3 point_u(double u) const;
  [[nodiscard]] Vec3 derivative_u(double u) const;         ///< dp/du
  [[nodiscard]] Vec3 second_derivative_u(double u) const;  ///< d2p/du2
  [[nodiscard]] Vec3 point_at(double s_mm) const { return point_u(u_at_length(s_mm)); }
  /// Unit tangent in the direction of motion at arc length s.
  [[nodiscard]] Vec3 tangent_at(double s_mm) const;
  /// Curvature (1/mm) at arc length s: |p' x p''| / |p'|^3.
  [[nodiscard]] double curvature_at(double s_mm) const;
  /// Point, unit tangent and curvature at arc length s with one length inversion.
  struct Frame {
    Vec3 point, tangent;
    double curvature_per_mm = 0;
  };
  [[nodiscard]] Frame frame_at(double s_mm) const;

  // Curve data (meaningful for Kind::curve).
  [[nodiscard]] const Vec3& center() const noexcept { return c_; }
  [[nodiscard]] const Vec3& axis_a() const noexcept { return a_; }
  [[nodiscard]] const Vec3& axis_b() const noexcept { return b_; }
  [[nodiscard]] const Vec3& drift() const noexcept { return v_; }
  [[nodiscard]] double u0() const noexcept { return u0_; }
  [[nodiscard]] double u1() const noexcept { return u1_; }
  /// True for a circular arc or helix (G2/G3 exact), within relative 1e-12.
  [[nodiscard]] bool is_circular() const noexcept;
  /// True when every point lies in a plane z = const.
  [[nodiscard]] bool is_flat_xy() const noexcept;

 private:
  Segment() = default;
  void build_length_table();

  Kind kind_ = Kind::line;
  Motion motion_ = Motion::feed;
  double speed_mm_per_min_ = 0;
  Vec3 c_ = Vec3::Zero(), a_ = Vec3::Zero(), b_ = Vec3::Zero(), v_ = Vec3::Zero();
  double u0_ = 0, u1_ = 1;
  double length_mm_ = 0;
  // Curve arc length: cumulative length at equally spaced u nodes (Gauss-Legendre per span);
  // empty when |p'| is constant (lines, circles, helices: exact closed form).
  std::vector<double> cum_length_;
  double speed_u_ = 0;  ///< |dp/du| when constant
};

/// A marker for the start of one trochoid cycle (or one pass of the linear family).
struct CycleMark {
  std::size_t first_segment = 0;  ///< index of its first segment
  double start_length_mm = 0;     ///< path length at its start (mm)
  double start_time_s = 0;        ///< programmed-feed time at its start (s)
};

/// A tool-centre path: consecutive exact primitives, continuous in position.
class ToolPath {
 public:
  ToolPath() = default;
  /// Appends a segment; throws Error if it does not start where the path ends (1e-9 mm).
  void append(Segment segment);
  /// Marks the start of a cycle at the current end of the path.
  void mark_cycle();
  /// Room for n segments (a reader that knows about how many will come).
  void reserve(std::size_t n);

  [[nodiscard]] const std::vector<Segment>& segments() const noexcept { return segments_; }
  [[nodiscard]] const std::vector<CycleMark>& cycles() const noexcept { return cycles_; }
  [[nodiscard]] bool empty() const noexcept { return segments_.empty(); }
  [[nodiscard]] double length_mm() const noexcept;
  /// Length of feed moves only (mm).
  [[nodiscard]] double feed_length_mm() const noexcept;
  /// Time at programmed feeds and rapid rate, no acceleration limit (s).
  [[nodiscard]] double duration_s() const noexcept;
  [[nodiscard]] double segment_start_length_mm(std::size_t i) const { return start_length_[i]; }
  [[nodiscard]] double segment_start_time_s(std::size_t i) const { return start_time_[i]; }
  /// Index of the segment containing arc length s (mm), clamped to the path.
  [[nodiscard]] std::size_t segment_at_length(double s_mm) const;
  /// Index of the segment containing time t (s), clamped to the path.
  [[nodiscard]] std::size_t segment_at_time(double t_s) const;
  /// Arc length (mm) reached at time t (s) at the programmed feeds: along the segment
  /// containing t at its speed, clamped to that segment; its index through `segment` if given.
  [[nodiscard]] double length_at_time_mm(double t_s, std::size_t* segment = nullptr) const;
  [[nodiscard]] Vec3 point_at_length(double s_mm) const;

 private:
  std::vector<Segment> segments_;
  std::vector<double> start_length_;  ///< cumulative length at each segment's start (mm)
  std::vector<double> start_time_;    ///< cumulative programmed time at each segment's start (s)
  std::vector<CycleMark> cycles_;
};

/// The stock an earlier program left ([pocket] rest_of), for a tool of radius R no larger
/// than its own: at a tool tip height z, the plan region its flat end mill removed from z up,
/// the union of what it swept along its horizontal moves at z or below (each removed the
/// material above its tip). Its descents (helices, ramps, plunges) count as removing nothing
/// (the material stays in the model: engagements there read high, never low). Lengths mm.
struct RestStock {
  std::string name;           ///< the program's file, for messages
  double tool_radius_mm = 0;  ///< its tool's
  /// Its horizontal moves at one height, in plan view: each run of consecutive moves an open
  /// chain of lines and arcs.
  struct Level {
    double z_mm = 0;
    std::vector<Contour> chains;
  };
  std::vector<Level> levels;  ///< by increasing z
  ToolPath path;              ///< the program as read (the simulation sweeps its tool along it)
};

/// Samples of a path, structure of arrays (one entry per sample).
struct PathSamples {
  std::vector<double> t_s;   ///< programmed-feed time (s)
  std::vector<double> s_mm;  ///< arc length from the path start (mm)
  std::vector<double> x_mm, y_mm, z_mm;
  std::vector<double> tx, ty, tz;  ///< unit tangent
  std::vector<double> curvature_per_mm;
  std::vector<std::size_t> segment;
  [[nodiscard]] std::size_t size() const noexcept { return t_s.size(); }
};

/// Samples every dt_s seconds of programmed time (the last sample at the path's end).
[[nodiscard]] PathSamples sample_by_time(const ToolPath& path, double dt_s);
/// Samples every ds_mm of path length (the last sample at the path's end).
[[nodiscard]] PathSamples sample_by_length(const ToolPath& path, double ds_mm);
/// Samples at the given programmed times (s, non-decreasing; clamped to the path).
[[nodiscard]] PathSamples sample_at_times(const ToolPath& path, const std::vector<double>& times_s);
/// Samples steps_per_rev times per spindle revolution at spindle_rpm.
[[nodiscard]] PathSamples sample_by_spindle_angle(const ToolPath& path, int steps_per_rev,
                                                  double spindle_rpm);

/// Tooth-tip trajectories: tooth k at time t sits at
///   centre(t) + e (cos(phi_s + lambda), sin(phi_s + lambda)) + R (cos phi_k, sin phi_k),
///   phi_k = phi_s(t) + alpha_k, phi_s(t) = -/+ 2 pi n t / 60 (cw / ccw spindle),
/// with radial runout e at phase lambda; its z is centre z - e_ax cos(alpha_k - lambda)
/// (the tooth at the runout phase is the longest). Angles in radians, positions mm.
struct ToothTracks {
  int teeth = 0;
  std::vector<double> spindle_angle_rad;              ///< phi_s per sample
  std::vector<std::vector<double>> x_mm, y_mm, z_mm;  ///< [tooth][sample]
};
[[nodiscard]] ToothTracks tooth_tracks(const PathSamples& samples, const Tool& tool,
                                       const Cutting& cutting);
/// Time between successive teeth passing one angle (s): 60 / (n Z).
[[nodiscard]] double tooth_period_s(const Tool& tool, const Cutting& cutting);
/// Effective cutting radius (mm) of tooth k with radial runout: |R u(alpha_k) + e u(lambda)|.
[[nodiscard]] double tooth_radius_mm(const Tool& tool, int k);

/// Machining time with the machine's acceleration limit (s): trapezoidal speed profile along
/// the path (tangential and centripetal limits, junction-deviation corner speeds). Equals
/// duration_s() when max_acceleration is 0.
[[nodiscard]] double estimate_time_s(const ToolPath& path, const Machine& machine);

/// The path's axis-aligned bounding box (mm): segment end points, curves sampled every
/// quarter degree of parameter (an arc of radius r is then within r (1 - cos(pi/1440)) =
/// 2.4e-6 r of it).
[[nodiscard]] Box3 bounding_box(const ToolPath& path);
/// Grows `box` by one segment (as bounding_box does).
void extend(Box3& box, const Segment& segment);

/// The time window (s) of trochoid cycles [a, b) of the path (its cycle marks; b may be the
/// number of cycles: then to the path's end). Throws InputError for a bad range.
[[nodiscard]] std::pair<double, double> cycle_window(const ToolPath& path, int a, int b);

/// A path's totals accumulated segment by segment, without keeping the segments (a long NC
/// program read as a stream): the same sums as ToolPath's length_mm, feed_length_mm and
/// duration_s, and its bounding box.
struct PathSummary {
  std::size_t segments = 0;
  double length_mm = 0, feed_length_mm = 0, duration_s = 0;
  Box3 box;
  void add(const Segment& segment);
};
/// The summary of a whole path.
[[nodiscard]] PathSummary summarize(const ToolPath& path);

/// Where the slot frame sits in the workpiece (the frame of the program's work offset):
/// `[slot] origin_x, origin_y, angle`. A point p of the slot frame is at
/// (origin_x, origin_y, 0) + Rz(angle) p in the workpiece: turned counter-clockwise seen from
/// +Z, then moved; Z is unchanged. Multiples of 90 degrees turn exactly (cos and sin 0 or 1).
struct Placement {
  double origin_x_mm = 0, origin_y_mm = 0;  ///< workpiece position of the slot origin (mm)
  double angle_deg = 0;                     ///< turn of the slot frame about Z (degrees)
  [[nodiscard]] bool is_identity() const noexcept;
  [[nodiscard]] Vec3 to_work(const Vec3& slot_point_mm) const;  ///< slot frame -> workpiece
  [[nodiscard]] Vec3 to_slot(const Vec3& work_point_mm) const;  ///< workpiece -> slot frame
  [[nodiscard]] Vec3 turn(const Vec3& slot_vector) const;       ///< a direction, not moved
  [[nodiscard]] Vec3 turn_back(const Vec3& work_vector) const;  ///< the inverse turn
};
[[nodiscard]] Placement slot_placement(const Job& job);
/// The path moved into the workpiece (to_work on every primitive, cycle marks kept).
[[nodiscard]] ToolPath to_work_frame(const ToolPath& path, const Placement& placement);
/// A workpiece path (read from a program) back in the slot frame the models work in.
[[nodiscard]] ToolPath to_slot_frame(const ToolPath& path, const Placement& placement);

/// Geometry of a planned trochoidal slot (all mm).
/// The slot's orbit as the families, the mechanism model and the analysis read it (Wagih 2023
/// Section 2): the trochoid radius across the slot a = (W - D) / 2 and the semi-axis along it
/// b = r_e a for the elliptical families (a for the others). Lengths in mm.
struct SlotGeometry {
  double width_mm = 0;        ///< W
  double tool_radius_mm = 0;  ///< R = D / 2
  double orbit_a_mm = 0;      ///< a = (W - D) / 2
  double orbit_b_mm = 0;      ///< b = r_e a (elliptical, linear-elliptical), else a
  double step_mm = 0;         ///< s
};
[[nodiscard]] SlotGeometry slot_geometry(const Job& job);

struct PlanInfo {
  double trochoid_radius_mm = 0;  ///< a = (W - D) / 2
  double semi_axis_feed_mm = 0;   ///< b = r_e a
  double first_cycle_y_mm = 0;    ///< y of the first cycle's start point on the wall
  int cycles = 0;                 ///< number of cycles (passes for linear)
  double cycle_length_mm = 0;     ///< length of one steady-state cycle
  bool closed_start = false;      ///< slot starts inside material (helix/ramp/plunge entry)
  int levels = 1;                 ///< depth levels (a slot along a contour: [slot] max_step_down)
};

struct PlannedPath {
  ToolPath path;
  PlanInfo info;
};

/// The memory plan_path and the G-code of its program will take (bytes), before planning:
/// the cycles the slot needs (its length and orbit over the step), about 3 kB each (the path
/// and the program text), and the process (30 MB); within a factor of 2 of the measured peak.
[[nodiscard]] double estimate_plan_memory(const Job& job);

/// The largest chip (mm) a path makes from `from_mm` of its length to its end: the judge a
/// slot along a curve holds its steps to (engagement.hpp plan_slot passes the exact engagement
/// kernel's).
using ChipJudge = std::function<double(const Job& job, const ToolPath& path, double from_mm)>;

/// Plans the whole slot program of the job: entry to depth, the family's cycles until the
/// slot end is cleared, and the exit. Throws InputError when the geometry is infeasible.
/// A slot along a drawing's contour ([slot] along) needs `judge` (throws Error without one):
/// each cycle's step is the one whose steady chip in a ring of the bend's curvature equals
/// the straight slot's at [path] step (docs/models.md, "Slots along a curve").
[[nodiscard]] PlannedPath plan_path(const Job& job, const ChipJudge& judge = {});

/// One cycle of a trochoidal family (any but linear) in the straight slot's frame (x across, y
/// along, z = 0) as plan_path places each of its cycles (docs/models.md section 2): from
/// (-a, 0) on the left wall to (-a, step_mm), a = orbit_a_mm, b = aspect a, d =
/// linear_distance_mm (linear-elliptical), orbiting clockwise; mirror negates x (the
/// counter-clockwise orbit, climb with a clockwise spindle). At the feed speed_mm_per_min.
[[nodiscard]] ToolPath family_cycle(PathType type, double orbit_a_mm, double aspect, double step_mm,
                                    double linear_distance_mm, bool mirror,
                                    double speed_mm_per_min);

/// Effective feed rate (mm/min) and spindle speed (rpm) of the job's cutting conditions.
[[nodiscard]] double feed_rate_mm_per_min(const Job& job);
[[nodiscard]] double spindle_speed_rpm(const Job& job);
/// The feed of the moves through cleared area that cut nothing or only graze the stock (a
/// curved slot's links between levels, a pocket's links that stay down and its passes' runs
/// through cleared area), mm/min: machine.air_feed, else max_feed, else the rapid rate (the
/// control holds a feed move to its most). Feed moves, because a rapid need not run straight.
[[nodiscard]] double link_feed_mm_per_min(const Machine& machine);
/// Refuses (InputError, naming [stock] max) a [stock] box whose top lies above the top face
/// z = 0 that `plan` plans from: its rapids come down to [path] clearance above z = 0, into
/// such a stock. A top below z = 0 is fine (the first cuts run in the air).
void check_stock_top(const Job& job);

}  // namespace trochomill
