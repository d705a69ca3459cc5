// Geometry every module shares, at the bottom of the module graph: the point type, the
// axis-aligned box, triangle meshes and their files (STL, PLY, OBJ through assimp), and planar
// contours of lines and circular arcs with their orientation, area, distance and offsets (the
// offsets through Clipper, Debian's libpolyclipping). All lengths mm, angles rad unless a
// name says otherwise.
#pragma once

#include <Eigen/Core>
#include <array>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <limits>
#include <optional>
#include <vector>

namespace trochomill {

/// A point or a direction in space (mm).
using Vec3 = Eigen::Vector3d;
/// A point or a direction in the plane (mm).
using Vec2 = Eigen::Vector2d;

/// An axis-aligned box (mm). Default-constructed it is empty (lo = +inf, hi = -inf), so that
/// extending it by points gives their box.
struct Box3 {
  Vec3 lo = Vec3::Constant(std::numeric_limits<double>::infinity());
  Vec3 hi = Vec3::Constant(-std::numeric_limits<double>::infinity());

  /// Whether the box holds no point (lo > hi along some axis).
  [[nodiscard]] bool empty() const { return !(lo.array() <= hi.array()).all(); }
  /// hi - lo (mm); zero for an empty box.
  [[nodiscard]] Vec3 size_mm() const { return empty() ? Vec3::Zero() : Vec3(hi - lo); }
  [[nodiscard]] double volume_mm3() const { return size_mm().prod(); }
  [[nodiscard]] bool contains(const Vec3& p) const {
    return (p.array() >= lo.array()).all() && (p.array() <= hi.array()).all();
  }
  void extend(const Vec3& p) {
    lo = lo.cwiseMin(p);
    hi = hi.cwiseMax(p);
  }
  void extend(const Box3& b) {
    lo = lo.cwiseMin(b.lo);
    hi = hi.cwiseMax(b.hi);
  }
};

// ---------------------------------------------------------------------------------------------
// Triangle meshes

struct Mesh {
  std::vector<Vec3> vertices;                           ///< mm
  std::vector<std::array<std::uint32_t, 3>> triangles;  ///< counter-clockwise seen from outside
};

/// Reads a triangle mesh (STL ascii/binary, PLY, OBJ; by content, through assimp), all its
/// meshes merged, identical vertices joined. Throws InputError naming the file.
[[nodiscard]] Mesh read_mesh(const std::filesystem::path& file);
/// Writes a mesh, format by extension (.stl binary, .ply binary, .obj). Written to a
/// temporary file and renamed. Throws InputError for an unknown extension, IoError on failure.
void write_mesh(const std::filesystem::path& file, const Mesh& mesh);

/// A mesh used as a solid (a stock): the box of the vertices its triangles use (mm). Throws
/// InputError when it has no triangles, a triangle names a missing vertex, or a coordinate is
/// not finite or lies beyond 1 km (1e6 mm).
[[nodiscard]] Box3 mesh_bounds(const Mesh& mesh);

/// Checks that a mesh is a closed solid: mesh_bounds's checks, every edge of a triangle (other
/// than a degenerate one) joining it to exactly one other that runs it the other way (a
/// closed surface, turned consistently; identical vertices are joined when read), and a
/// positive signed volume (the triangles counter-clockwise seen from outside). Throws
/// InputError naming the first bad edge's ends (mm).
void check_closed_mesh(const Mesh& mesh);

/// Where the line along `axis` (0 x, 1 y, 2 z) through (u, v) on the next two axes
/// (cyclically: y z for x, z x for y, x y for z; mm) crosses the triangle (a, b, c): its
/// coordinate along the axis (mm), or nothing when it misses or the triangle is edge-on to
/// it. A line through an edge or a vertex of a closed surface crosses exactly one of the
/// triangles meeting there (the rasteriser's top-left rule, on edge functions computed from
/// each edge's lexicographically first end, so that the two triangles of an edge compute
/// exact negatives); a face square to the line is met exactly at its height.
[[nodiscard]] std::optional<double> line_crossing(const Vec3& a, const Vec3& b, const Vec3& c,
                                                  int axis, double u, double v);

// ---------------------------------------------------------------------------------------------
// Planar contours

/// One piece of a planar contour: a straight line from `start` to `end`, or a circular arc
/// from `start` to `end` about `centre`, counter-clockwise when `ccw` (mm). An arc whose start
/// and end coincide is a full circle.
struct ContourPiece {
  Vec2 start = Vec2::Zero(), end = Vec2::Zero();
  std::optional<Vec2> centre;  ///< none: a line
  bool ccw = true;

  [[nodiscard]] static ContourPiece line(const Vec2& a, const Vec2& b) { return {a, b, {}, true}; }
  [[nodiscard]] static ContourPiece arc(const Vec2& a, const Vec2& b, const Vec2& centre,
                                        bool ccw) {
    return {a, b, centre, ccw};
  }
  [[nodiscard]] bool is_arc() const noexcept { return centre.has_value(); }
  /// The arc's radius (mm): |start - centre|; 0 for a line.
  [[nodiscard]] double radius_mm() const;
  /// The arc's signed sweep (rad): positive counter-clockwise, in (0, 2 pi] or [-2 pi, 0);
  /// 0 for a line.
  [[nodiscard]] double sweep_rad() const;
  [[nodiscard]] double length_mm() const;
  /// The point at the fraction t in [0, 1] of the piece's length.
  [[nodiscard]] Vec2 point_at(double t) const;
  /// The unit tangent (direction of travel) at the fraction t.
  [[nodiscard]] Vec2 tangent_at(double t) const;
  /// The shortest distance from p to the piece (mm), exact.
  [[nodiscard]] double distance_mm(const Vec2& p) const;
  /// The same piece run the other way.
  [[nodiscard]] ContourPiece reversed() const;
};

/// A chain of pieces, each starting where the previous one ends; closed when the last ends
/// where the first starts. Orientation of a closed contour: counter-clockwise (positive area)
/// or clockwise.
struct Contour {
  std::vector<ContourPiece> pieces;
  bool closed = false;

  /// A polyline through the points (mm); closed joins the last point to the first.
  [[nodiscard]] static Contour polyline(const std::vector<Vec2>& points, bool closed);
  /// A circle of radius r_mm about c, counter-clockwise (two half arcs).
  [[nodiscard]] static Contour circle(const Vec2& c, double r_mm);

  [[nodiscard]] double length_mm() const;
  /// The signed area enclosed (mm^2), arcs exact: positive when counter-clockwise. Throws
  /// std::logic_error for an open contour.
  [[nodiscard]] double signed_area_mm2() const;
  [[nodiscard]] bool counter_clockwise() const { return signed_area_mm2() > 0; }
  /// The contour run the other way.
  [[nodiscard]] Contour reversed() const;
  /// The shortest distance from p to the contour (mm), exact.
  [[nodiscard]] double distance_mm(const Vec2& p) const;
  /// Points along the contour whose chords stay within `tolerance_mm` of it (arcs split into
  /// equal chords of sagitta <= tolerance; lines kept whole); a closed contour does not repeat
  /// its first point.
  [[nodiscard]] std::vector<Vec2> points(double tolerance_mm) const;
  /// Throws InputError unless every piece is finite and starts within `gap_mm` of where the
  /// previous one ends (and, when closed, the last ends within gap_mm of the first's start).
  void check(double gap_mm) const;
};

/// The region inside closed contours by the even-odd rule (an island inside a boundary is a
/// hole, whatever their orientations), grown by `distance_mm` (shrunk when negative), with
/// round corners, as closed polylines: outer boundaries counter-clockwise, holes clockwise,
/// in a deterministic order (by area, largest first, then by lowest point). Every vertex lies
/// within `tolerance_mm` of the exact offset (the arcs of the input and of the rounded
/// corners are chords of sagitta <= tolerance / 2). Computed with Clipper on a 1 nm grid.
/// Throws InputError for an open contour, a non-finite point or a tolerance outside
/// [1e-5, 10] mm.
[[nodiscard]] std::vector<Contour> offset_region(const std::vector<Contour>& closed,
                                                 double distance_mm, double tolerance_mm);

/// The part of region `a` outside region `b` (each given as closed contours, even-odd), in
/// the form offset_region gives. Same tolerance and errors as offset_region.
[[nodiscard]] std::vector<Contour> region_difference(const std::vector<Contour>& a,
                                                     const std::vector<Contour>& b,
                                                     double tolerance_mm);
/// The part of region `a` inside region `b`, as region_difference.
[[nodiscard]] std::vector<Contour> region_intersection(const std::vector<Contour>& a,
                                                       const std::vector<Contour>& b,
                                                       double tolerance_mm);
/// A region in offset_region's form cut into its connected parts: each outer boundary
/// (counter-clockwise) followed by the holes (clockwise) directly inside it, in the input's
/// order of the outer boundaries.
[[nodiscard]] std::vector<std::vector<Contour>> region_parts(const std::vector<Contour>& region);
/// Whether p lies inside the region of the closed contours by the even-odd rule (arcs
/// exact); a point on a contour may count either way.
[[nodiscard]] bool region_contains(const std::vector<Contour>& region, const Vec2& p);

/// The region within `distance_mm` (> 0) of a contour, open or closed: a slot of width
/// 2 distance_mm along an open contour, with round ends; a ring along a closed one. Same
/// output and tolerance as offset_region.
[[nodiscard]] std::vector<Contour> offset_curve(const Contour& contour, double distance_mm,
                                                double tolerance_mm);

/// A branch of a region's medial axis: points along it at most the spacing asked apart, each
/// with its clearance (mm, the distance to the region's boundary: the disc of that radius
/// about it lies in the region; 0 for a point outside it, where the chord of a curved edge
/// cuts across a corner of the boundary). `closed`: a cycle (around an island), its first point not
/// repeated at the end.
struct MedialBranch {
  std::vector<Vec2> points;
  std::vector<double> clearance_mm;
  bool closed = false;
};
/// The medial axis of a region (closed contours, offset_region's form): the centres of the
/// largest discs inside it whose two nearest boundary points are seen from the centre at least
/// `min_angle_deg` apart (the axis of a channel sees its walls 180 degrees apart; the spokes
/// towards a convex corner of angle alpha, 180 - alpha; those of a chord-approximated arc, a
/// few degrees: pruned), as branches between junctions and ends. From Boost.Polygon's Voronoi
/// diagram of the boundary's segments on a 1 nm grid; a curved Voronoi edge (a point and a
/// segment) is taken as its chord, whose points' clearances are exact nonetheless. In a
/// deterministic order. Throws InputError for an open contour or a point that is not finite.
[[nodiscard]] std::vector<MedialBranch> medial_axis(const std::vector<Contour>& region,
                                                    double min_angle_deg, double spacing_mm);

/// The plan view of a closed mesh taken as a solid (its triangles counter-clockwise seen from
/// outside) between the heights z0_mm <= z1_mm: the points whose vertical line meets the
/// solid at some height in [z0, z1], in offset_region's form. Exact up to Clipper's 1 nm
/// grid: the section at z0 (the winding of the projected parts of the triangles below it:
/// each vertical line enters the solid through a face turned down and leaves through one
/// turned up) joined with the projections of the triangles' parts between z0 and z1. Throws
/// InputError as mesh_bounds does, and for z0 > z1 or a height that is not finite.
[[nodiscard]] std::vector<Contour> mesh_plan_region(const Mesh& mesh, double z0_mm, double z1_mm);

// ---------------------------------------------------------------------------------------------
// Fitting curves with arcs

/// One circular arc (or line) of a fit, in the XY plane at constant z (mm, rad).
struct FitArc {
  bool is_line = false;
  Vec3 start, end;
  double cx = 0, cy = 0, radius_mm = 0;
  double sweep_rad = 0;  ///< signed, positive = counter-clockwise
};
/// A planar curve (z = const) by a parameter u: its point (mm) and unit tangent in the
/// direction of travel (zero where it has none).
class PlanarCurve {
 public:
  virtual ~PlanarCurve() = default;
  [[nodiscard]] virtual Vec3 point(double u) const = 0;
  [[nodiscard]] virtual Vec3 unit_tangent(double u) const = 0;
};
/// An ellipse (or elliptical arc) c + a cos t + b sin t (mm; a and b its conjugate semi-axes,
/// z = const), t increasing: what the drawings' ellipses and elliptical arcs are fitted from.
class EllipseCurve final : public PlanarCurve {
 public:
  EllipseCurve(const Vec3& c, const Vec3& a, const Vec3& b) : c_(c), a_(a), b_(b) {}
  [[nodiscard]] Vec3 point(double t) const override {
    return c_ + a_ * std::cos(t) + b_ * std::sin(t);
  }
  [[nodiscard]] Vec3 unit_tangent(double t) const override {
    const Vec3 d = -a_ * std::sin(t) + b_ * std::cos(t);
    const double n = d.norm();
    return n > 0 ? Vec3(d / n) : Vec3::Zero();
  }

 private:
  Vec3 c_, a_, b_;
};

/// A NURBS curve in a plane z = const (that of its first control point): its degree, knots
/// (control points + degree + 1 of them, not decreasing), control points (mm) and weights (> 0),
/// for u in [knot[degree], knot[control points]]. Evaluated by de Boor's algorithm on the
/// homogeneous points (exact); its tangent by central differences over a millionth of the
/// parameter range. Bézier curves are the NURBS of one span and weights 1. The caller checks
/// the data (the DXF reader and the G-code interpreter say what is wrong with theirs).
class NurbsCurve final : public PlanarCurve {
 public:
  NurbsCurve(int degree, std::vector<double> knots, std::vector<Vec3> ctrl,
             std::vector<double> weights);
  [[nodiscard]] double u0() const { return u_[static_cast<std::size_t>(p_)]; }
  [[nodiscard]] double u1() const { return u_[c_.size()]; }
  [[nodiscard]] Vec3 point(double u) const override;
  [[nodiscard]] Vec3 unit_tangent(double u) const override;

 private:
  int p_;
  std::vector<double> u_;
  std::vector<Vec3> c_;
  std::vector<double> w_;
};

/// Tangent-continuous biarcs through the curve from u0 to u1 (split first into `pieces` equal
/// spans of u, each cut into the longest pieces whose biarc stays within 0.8 tolerance_mm of the
/// curve at 24 interior samples, found by doubling, halving and bisection). The last arc ends
/// exactly where the curve ends. Throws Error when a piece would need more than 30 halvings (a
/// feature below the tolerance), ArcLimit when the fit would take more than max_arcs arcs
/// (the drawing readers' budget, kMaxDrawingArcs; checked as the arcs are made, so a curve
/// far too long for the tolerance costs no more than the budget).
[[nodiscard]] std::vector<FitArc> fit_biarcs(
    const PlanarCurve& curve, double u0, double u1, int pieces, double tolerance_mm,
    std::size_t max_arcs = std::numeric_limits<std::size_t>::max());
/// The parameters in (u0, u1), increasing, where the curve turns back on itself (a cusp: two
/// of `samples` successive chords turning more than 120 degrees), each refined to where the
/// curve moves slowest between them.
[[nodiscard]] std::vector<double> cusp_parameters(const PlanarCurve& curve, double u0, double u1,
                                                  int samples);
/// fit_biarcs of each part of [u0, u1] between the curve's cusps (cusp_parameters, 64 chords a
/// piece), each part's tangent at a cusp taken from its own side: a curve that turns back is
/// fitted as the corner it is, where fit_biarcs alone finds no biarc turning back there
/// (Error). The same arcs as fit_biarcs where there is no cusp. The budget is the whole's.
[[nodiscard]] std::vector<FitArc> fit_biarcs_at_cusps(
    const PlanarCurve& curve, double u0, double u1, int pieces, double tolerance_mm,
    std::size_t max_arcs = std::numeric_limits<std::size_t>::max());
/// fit_biarcs would have taken more than `max_arcs` arcs.
struct ArcLimit {
  std::size_t max_arcs;
};
/// The end points of chords through the curve from u0 to u1 within tolerance_mm (the start
/// not included).
[[nodiscard]] std::vector<Vec3> fit_chords(const PlanarCurve& curve, double u0, double u1,
                                           int pieces, double tolerance_mm);
/// A fit's arc as a contour piece.
[[nodiscard]] ContourPiece to_piece(const FitArc& arc);

/// Lines and circular arcs through a polyline's points within `tolerance_mm` of every point
/// (each piece the longest that fits, found by doubling and bisection: an arc through its
/// first, middle and last point, a line when those are collinear within the tolerance). The
/// pieces start and end on the polyline's points, so consecutive pieces join exactly; they
/// are tangent-continuous only where the polyline is, within the tolerance. The middles of the
/// chords between the points are held within the tolerance too, but an arc turning
/// counter-clockwise (bulge_ccw) or clockwise may bulge outside them, away from its centre, by
/// up to bulge_mm (when larger than the tolerance): a planner whose points' chords are safe
/// on one side.
[[nodiscard]] std::vector<ContourPiece> fit_polyline(const std::vector<Vec2>& points,
                                                     double tolerance_mm, double bulge_mm = 0,
                                                     bool bulge_ccw = true);

/// Where the contour crosses or touches itself (mm), if it does: its pieces as chords within
/// 1e-4 mm, every pair that is not consecutive along the contour tested (a sweep in x); the
/// first crossing found in the contour's order. None for a simple contour.
[[nodiscard]] std::optional<Vec2> contour_self_crossing(const Contour& contour);

/// The area of a region given as its closed contours with orientation (mm^2): the sum of their
/// signed areas (outer boundaries counter-clockwise, holes clockwise, as offset_region gives).
[[nodiscard]] double region_area_mm2(const std::vector<Contour>& contours);

}  // namespace trochomill
