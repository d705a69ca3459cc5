// The SVG reader's syntax (private to src/geometry): numbers, lengths, transform lists and path
// data, read by the grammars of SVG 1.1 (https://www.w3.org/TR/SVG11/paths.html#PathDataBNF,
// https://www.w3.org/TR/SVG11/coords.html#TransformAttribute) into user-space geometry.
#pragma once

#include <string>
#include <string_view>
#include <vector>

#include "trochomill/geometry.hpp"
#include "trochomill/geometry/drawing.hpp"

namespace trochomill::svg {

/// Bad syntax: the 0-based character position in the attribute and what was expected there.
struct SyntaxError {
  std::size_t pos;
  std::string what;
};

/// An affine map in SVG's matrix(a b c d e f) order: x' = a x + c y + e, y' = b x + d y + f.
struct Affine {
  double a = 1, b = 0, c = 0, d = 1, e = 0, f = 0;
  [[nodiscard]] Vec2 operator()(const Vec2& p) const {
    return {a * p.x() + c * p.y() + e, b * p.x() + d * p.y() + f};
  }
  /// The linear part only (for directions and ellipse axes).
  [[nodiscard]] Vec2 linear(const Vec2& v) const {
    return {a * v.x() + c * v.y(), b * v.x() + d * v.y()};
  }
  /// This after o (o applied first).
  [[nodiscard]] Affine operator*(const Affine& o) const {
    return {a * o.a + c * o.b, b * o.a + d * o.b,     a * o.c + c * o.d,
            b * o.c + d * o.d, a * o.e + c * o.f + e, b * o.e + d * o.f + f};
  }
  [[nodiscard]] double det() const { return a * d - b * c; }
};

/// Where path data and shapes go, in user units (SVG's y down). An elliptical arc is given by
/// its centre parametrisation c + a cos t + b sin t, t from t0 to t1 (either way round), and
/// its exact end points.
class PathSink {
 public:
  virtual ~PathSink() = default;
  virtual void line(const Vec2& p0, const Vec2& p1) = 0;
  virtual void cubic(const Vec2& p0, const Vec2& p1, const Vec2& p2, const Vec2& p3) = 0;
  virtual void ellipse(const Vec2& c, const Vec2& a, const Vec2& b, double t0, double t1,
                       const Vec2& p0, const Vec2& p1) = 0;
};

/// A number (SVG 1.1's grammar: "1.5e-3", "-.5"; no "inf" or hex) at s[i], i moved past it;
/// SyntaxError when there is none or it is not finite.
double read_number(std::string_view s, std::size_t& i);
/// Skips white space, then one comma and the white space after it if there is one.
void skip_comma_wsp(std::string_view s, std::size_t& i);
[[nodiscard]] bool is_wsp(char c);

/// A length attribute in user units (px: 96 per in; mm, cm, in, pt, pc, Q, px or none).
/// SyntaxError for a percentage, another unit or trailing text.
double read_length(std::string_view s);
/// mm per unit of an absolute CSS unit ("" and "px": 25.4 / 96); 0 for one it does not know.
[[nodiscard]] double mm_per_css_unit(std::string_view unit);

/// A transform list: matrix, translate, scale, rotate (about a point), skewX, skewY.
Affine read_transform(std::string_view s);

/// Path data (commands M L H V C S Q T A Z, absolute and relative, repeated implicitly) to the
/// sink; arcs from their end points to their centres (SVG 1.1 F.6.5, radii scaled up when
/// too small, F.6.6). SyntaxError at the first character that does not fit the grammar (the
/// pieces before it have gone to the sink).
void read_path(std::string_view d, PathSink& sink);

/// An elliptical arc from p0 to p1 (radii rx, ry, x axis turned phi_rad) to the sink as its
/// centre parametrisation: nothing when p0 = p1, a line when a radius is 0.
void endpoint_arc(const Vec2& p0, double rx, double ry, double phi_rad, bool large, bool sweep,
                  const Vec2& p1, PathSink& sink);

/// A problem with one element (the reader names the element with it).
struct Problem {
  std::string what;
};
/// A limit of the whole drawing reached at one element: the reading stops (the reader names
/// the file and the element with it).
struct Limit {
  std::string what;
};

/// One element's pieces (svg_pieces.cpp): user units through `m` into mm (y up), appended to
/// `out` with the layer and entity. Circles (round after the transform) become exact arcs,
/// Béziers and other ellipses biarcs within tolerance_mm, counted in `fitted` (the drawing's
/// fitted arcs so far). Throws Problem for a point beyond 1000 km or a curve that cannot be
/// fitted, Limit beyond two million pieces or kMaxDrawingArcs fitted arcs.
class PieceSink final : public PathSink {
 public:
  PieceSink(const Affine& m, double tolerance_mm, std::vector<DrawnPiece>& out, std::size_t& fitted,
            std::string layer, std::string entity);
  std::size_t added = 0;  ///< pieces appended
  void line(const Vec2& p0, const Vec2& p1) override;
  void cubic(const Vec2& p0, const Vec2& p1, const Vec2& p2, const Vec2& p3) override;
  void ellipse(const Vec2& c, const Vec2& a, const Vec2& b, double t0, double t1, const Vec2& p0,
               const Vec2& p1) override;

 private:
  static void check(const Vec2& p);
  void add(const ContourPiece& p);
  void fit(const PlanarCurve& c, double u0, double u1, int n);

  Affine m_;
  double tol_;
  std::vector<DrawnPiece>& out_;
  std::size_t& fitted_;
  std::string layer_, entity_;
};

}  // namespace trochomill::svg
