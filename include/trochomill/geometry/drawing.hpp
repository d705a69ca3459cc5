// Drawings from CAD: the lines, arcs and curves of a DXF file (through Debian's libdxflib)
// chained into planar contours, open or closed, each with the layer and the entities it came
// from. Curves that are not arcs (splines, ellipses) become tangent-continuous biarcs within
// a tolerance. Lengths mm (the file's units converted by its $INSUNITS). Part of the geometry
// module.
#pragma once

#include <filesystem>
#include <string>
#include <vector>

#include "trochomill/geometry.hpp"

namespace trochomill {

/// One piece of a drawing before chaining: the piece and the entity it came from.
struct DrawnPiece {
  ContourPiece piece;
  std::string layer;
  std::string entity;  ///< for messages: "LINE #2F" (DXF: the kind and its handle)
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
  double mm_per_unit = 1;              ///< the file's unit ($INSUNITS; 1 when unitless)
  std::string units;                   ///< "mm", "in", ... or "unitless (read as mm)"
};

struct DrawingOptions {
  /// Ends of pieces closer than this are one point (mm, 1e-6 to 100).
  double join_tolerance_mm = 0.01;
  /// Splines and ellipses become biarcs within this of the curve (mm).
  double arc_tolerance_mm = 0.002;
  /// Only these layers (empty: all). A named layer that holds nothing is an error.
  std::vector<std::string> layers;
};

/// Chains pieces into contours: a piece continues the contour whose end lies within `join_mm`
/// of one of its ends (turned round when it is its end that meets). Ends of one layer join
/// only ends of the same layer. Deterministic: contours start at the first piece (in the
/// given order) not yet used, an open chain is followed from its free end. Throws InputError
/// naming the entities: a branch (three or more ends within join_mm), or a gap (two free ends
/// closer than 10 join_mm: a drawing that was meant to join).
[[nodiscard]] std::vector<DrawnContour> chain_pieces(std::vector<DrawnPiece> pieces,
                                                     double join_mm);

/// Reads a DXF file: LINE, ARC, CIRCLE, LWPOLYLINE and POLYLINE (with bulges), SPLINE (NURBS,
/// from its control points, knots and weights), ELLIPSE (and elliptical arcs), in the XY plane
/// (entities whose extrusion is -Z mirrored into it, as CAD tools write them); $INSUNITS
/// sets the unit. Entities inside block definitions are skipped and an INSERT is refused
/// (explode the block in the CAD tool); points, texts, dimensions and hatches are ignored.
/// Throws InputError naming the file and the entity (its handle) for what it cannot read:
/// an entity out of the XY plane, a degenerate spline, an unknown unit, no entity on a layer
/// asked for (with the layers it has), a branch or a gap (chain_pieces).
[[nodiscard]] Drawing read_dxf(const std::filesystem::path& file, const DrawingOptions& options);

/// Reads a drawing by its file's extension (letters in either case): ".dxf" (read_dxf).
/// Throws InputError naming the file and the extensions allowed for any other.
[[nodiscard]] Drawing read_drawing(const std::filesystem::path& file,
                                   const DrawingOptions& options);

}  // namespace trochomill
