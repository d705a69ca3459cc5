// Drawings from CAD: the lines, arcs and curves of a DXF file (through Debian's libdxflib) or
// an SVG file (through pugixml) chained into planar contours, open or closed, each with the
// layer and the entities it came from. Curves that are not arcs (splines, ellipses, Béziers)
// become tangent-continuous biarcs within a tolerance. Lengths mm (the file's units converted:
// DXF's $INSUNITS, SVG's viewBox and width). Part of the geometry module.
#pragma once

#include <filesystem>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "trochomill/geometry.hpp"

namespace trochomill {

/// One piece of a drawing before chaining: the piece and the entity it came from.
struct DrawnPiece {
  ContourPiece piece;
  std::string layer;
  /// For messages: "LINE #2F" (DXF: the kind and its handle), "path #slot1" or
  /// "circle (line 12)" (SVG: the element and its id, or its line when it has none).
  std::string entity;
};

/// A chained contour with where it came from.
struct DrawnContour {
  Contour contour;  ///< mm; closed contours as drawn (see `orientation`)
  std::string layer;
  std::vector<std::string> entities;  ///< the entities chained into it, in order
};

struct Drawing {
  std::filesystem::path file;
  std::vector<DrawnContour> contours;  ///< in the order of their first entity in the file
  std::vector<std::string> layers;     ///< every layer holding a piece, sorted
  double mm_per_unit = 1;  ///< the file's unit ($INSUNITS; 1 when unitless; SVG: user unit)
  std::string units;       ///< "mm", "in", ..., "unitless (read as mm)" or "px (96 per in)"
};

/// The most arcs a drawing's splines, ellipses and Béziers are fitted with, all together. A
/// part's drawing needs far fewer (a Bézier arch 1 m across takes 70 at 0.002 mm); more is
/// a drawing traced from an image, or curves far beyond any machine's travel, which would take
/// seconds to read (about 20 µs an arc).
inline constexpr std::size_t kMaxDrawingArcs = 50'000;

struct DrawingOptions {
  /// Ends of pieces closer than this are one point (mm, 1e-6 to 100).
  double join_tolerance_mm = 0.01;
  /// Splines and ellipses become biarcs within this of the curve (mm).
  double arc_tolerance_mm = 0.002;
  /// Only these layers (empty: all). A named layer that holds nothing is an error.
  std::vector<std::string> layers;
  /// The unit of a DXF drawing that gives none ($INSUNITS absent or 0), one of
  /// drawing_unit_mm's names; empty: such a drawing is read as mm. A DXF that gives its unit,
  /// or an SVG, with this set is refused (the unit would be said twice).
  std::string unitless_unit;
};

/// The units a unitless drawing may be given in (DrawingOptions::unitless_unit): mm, cm, m,
/// in, ft, as mm per unit; none for another name.
[[nodiscard]] std::optional<double> drawing_unit_mm(const std::string& name);

/// Chains pieces into contours: a piece continues the contour whose end lies within `join_mm`
/// of one of its ends (turned round when it is its end that meets). Ends of one layer join
/// only ends of the same layer. Deterministic: contours start at the first piece (in the
/// given order) not yet used, an open chain is followed from its free end. Throws InputError
/// naming the entities: a branch (three or more ends within join_mm), or a gap (two free ends
/// closer than 10 join_mm: a drawing that was meant to join).
[[nodiscard]] std::vector<DrawnContour> chain_pieces(std::vector<DrawnPiece> pieces,
                                                     double join_mm);

/// A drawing file's text for its reader (`kind`: "DXF", "SVG"), after checking the
/// options' tolerances (> 0 mm): a regular file of at most 1 GB (a device, a folder or a
/// larger file is refused before reading: about 40 bytes of pieces per byte of drawing would
/// not fit). Throws InputError naming the file.
[[nodiscard]] std::string read_drawing_text(const std::filesystem::path& file,
                                            std::string_view kind, const DrawingOptions& options);

/// Reads a DXF file: LINE, ARC, CIRCLE, LWPOLYLINE and POLYLINE (with bulges), SPLINE (NURBS,
/// from its control points, knots and weights), ELLIPSE (and elliptical arcs), in the XY plane
/// (entities whose extrusion is -Z mirrored into it, as CAD tools write them); $INSUNITS
/// sets the unit. Entities inside block definitions are skipped and an INSERT is refused
/// (explode the block in the CAD tool); points, texts, dimensions and hatches are ignored.
/// Throws InputError naming the file and the entity (its handle) for what it cannot read:
/// an entity out of the XY plane, a degenerate spline, an unknown unit, no entity on a layer
/// asked for (with the layers it has), a branch or a gap (chain_pieces).
[[nodiscard]] Drawing read_dxf(const std::filesystem::path& file, const DrawingOptions& options);

/// Reads an SVG file (SVG 1.1 and 2, through pugixml): `path` (every command, absolute and
/// relative), `line`, `polyline`, `polygon`, `rect` (with rounded corners), `circle` and
/// `ellipse`, through the transforms of the elements and their groups. Lengths in mm: the
/// root's viewBox into its width and height (mm, cm, in, pt, pc, Q, px at 96 per in; no unit:
/// px), preserveAspectRatio as SVG scales; without a viewBox a user unit is 1 px = 25.4/96 mm.
/// SVG's y points down, a drawing's up: y is mirrored about the page's bottom edge (its
/// height, from the height attribute or the viewBox; y -> -y when it has neither), so the
/// origin is the page's bottom-left corner and contours turn as the picture shows them (a
/// rectangle drawn clockwise on the screen is clockwise). Circular arcs (round after the
/// transform) stay exact arcs; Béziers, elliptical arcs and circles squeezed into ellipses
/// become biarcs within the arc tolerance. The layer of an element: the inkscape:label of
/// its nearest enclosing Inkscape layer (a g of inkscape:groupmode "layer"), else the id of
/// its nearest enclosing g that has one, else "0"; DrawingOptions::layers names match a
/// layer, the id of the element or the id of an enclosing group. Elements inside defs,
/// clipPath, mask, symbol, marker and pattern, hidden ones (display none) and text are
/// skipped; a `use` is refused (unlink the clone in the editor). Throws InputError naming
/// the file and the element (its id, or its line) for what it cannot read: not XML (with
/// line:column), a root that is not svg, bad path data or transforms (with the character),
/// an unknown unit, a negative size, a point beyond 1000 km, nothing on a layer or id asked
/// for (with the layers and ids it has), a branch or a gap (chain_pieces).
[[nodiscard]] Drawing read_svg(const std::filesystem::path& file, const DrawingOptions& options);

/// Reads a drawing by its file's extension (letters in either case): ".dxf" (read_dxf) or
/// ".svg" (read_svg).
/// Throws InputError naming the file and the extensions allowed for any other.
[[nodiscard]] Drawing read_drawing(const std::filesystem::path& file,
                                   const DrawingOptions& options);

}  // namespace trochomill
