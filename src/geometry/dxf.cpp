// DXF drawings through libdxflib: entities into pieces (splines and ellipses fitted with
// biarcs), the unit from $INSUNITS, then chained into contours (geometry/drawing.hpp).
#include <dxflib/dl_creationadapter.h>
#include <dxflib/dl_dxf.h>
#include <fmt/format.h>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdlib>
#include <fstream>
#include <map>
#include <optional>
#include <sstream>

#include "geometry/drawing_limits.hpp"
#include "trochomill/error.hpp"
#include "trochomill/geometry/drawing.hpp"
#include "trochomill/io.hpp"
#include "trochomill/units.hpp"

namespace trochomill {
namespace {

// Layer names compare as DXF compares them: letters in either case.
bool same_name(const std::string& a, const std::string& b) {
  return a.size() == b.size() && std::equal(a.begin(), a.end(), b.begin(), [](char x, char y) {
           return std::tolower(static_cast<unsigned char>(x)) ==
                  std::tolower(static_cast<unsigned char>(y));
         });
}

// $INSUNITS: mm per unit and the unit's name; nothing for a code trochomill does not know.
std::optional<std::pair<double, const char*>> insunits(int code) {
  switch (code) {
    case 0:
      return std::pair{1.0, "unitless (read as mm)"};
    case 1:
      return std::pair{25.4, "in"};
    case 2:
      return std::pair{304.8, "ft"};
    case 4:
      return std::pair{1.0, "mm"};
    case 5:
      return std::pair{10.0, "cm"};
    case 6:
      return std::pair{1000.0, "m"};
    case 8:
      return std::pair{25.4e-6, "microinch"};
    case 9:
      return std::pair{0.0254, "mil"};
    case 10:
      return std::pair{914.4, "yd"};
    case 13:
      return std::pair{1e-3, "micron"};
    case 14:
      return std::pair{100.0, "dm"};
    default:
      return std::nullopt;
  }
}

// What libdxflib's reader does not pass on, read from the file's groups beforehand (its
// stream reader hands no group to processCodeValuePair): where each entity stands (the line
// of its type, for a file without handles), which polylines are LWPOLYLINEs (libdxflib hands
// both over as POLYLINE), each VERTEX's flags (a spline-fit POLYLINE holds its spline's
// frame, flag 16, beside the fitted vertices), what the ENTITIES section holds and whether it
// ends. Entities of a type come to the reader in the file's order, so the k-th of a type is
// the k-th listed here.
struct Scanned {
  std::map<std::string, std::vector<std::size_t>> lines;  // by type (POLYLINE: both kinds)
  std::vector<std::string> poly_types;                    // POLYLINE or LWPOLYLINE
  std::vector<std::vector<int>> vertex_flags;             // a POLYLINE's VERTEX flags
  std::map<std::string, std::size_t> types;               // in the ENTITIES section
  bool opened = false, closed = false;
  bool eof = false;  // its last group: 0 EOF
};

Scanned scan_groups(const std::string& text) {
  Scanned out;
  std::istringstream in(text);
  std::string code, value, section, entity;
  bool want_name = false;
  std::size_t line = 0;
  const auto trim = [](std::string& t) {
    const auto b = t.find_first_not_of(" \t\r");
    const auto e = t.find_last_not_of(" \t\r");
    t = b == std::string::npos ? std::string() : t.substr(b, e - b + 1);
  };
  while (std::getline(in, code) && std::getline(in, value)) {
    line += 2;
    trim(code);
    trim(value);
    if (code == "0") {
      entity = value;
      out.eof = value == "EOF";
      if (value == "SECTION") {
        want_name = true;
      } else if (value == "ENDSEC") {
        if (section == "ENTITIES") out.closed = true;
        section.clear();
      } else if (section == "ENTITIES" || section == "BLOCKS") {
        if (section == "ENTITIES") ++out.types[value];
        const bool poly = value == "POLYLINE" || value == "LWPOLYLINE";
        if (value != "VERTEX" && value != "SEQEND") {
          out.lines[poly ? "POLYLINE" : value].push_back(line);
        }
        if (poly) {
          out.poly_types.push_back(value);
          out.vertex_flags.emplace_back();
        } else if (value == "VERTEX" && !out.vertex_flags.empty()) {
          out.vertex_flags.back().push_back(0);
        }
      }
    } else if (code == "2" && want_name) {
      section = value;
      want_name = false;
      if (value == "ENTITIES") out.opened = true;
    } else if (code == "70" && entity == "VERTEX" && !out.vertex_flags.empty() &&
               !out.vertex_flags.back().empty()) {
      out.vertex_flags.back().back() = std::atoi(value.c_str());
    }
  }
  return out;
}

class Reader final : public DL_CreationAdapter {
 public:
  Reader(std::string source, const DrawingOptions& o, const Scanned& scan)
      : src_(std::move(source)), o_(o), scan_(scan) {
    if (!o.unitless_unit.empty()) {
      const auto mm = drawing_unit_mm(o.unitless_unit);
      if (!mm) {
        throw InputError(fmt::format("{}: '{}' is no unit trochomill reads: mm, cm, m, in or ft",
                                     src_, o.unitless_unit));
      }
      unit_ = *mm;
      units_given_ = fmt::format("unitless (read as {}: [geometry] units)", o.unitless_unit);
      units = units_given_.c_str();
    }
  }

  std::vector<DrawnPiece> pieces;
  std::vector<std::string> problems;
  std::optional<std::string> units_error;  ///< a unit it cannot read, or one after entities
  std::optional<std::string> limit_error;  ///< the drawing's arcs beyond kMaxDrawingArcs
  const char* units = insunits(0)->second;
  [[nodiscard]] double unit() const { return unit_; }
  std::vector<std::string> seen_layers;     ///< of every entity, chosen or not
  std::vector<std::string> problem_layers;  ///< the layer of each problem

  // The unit, from the header (before any entity: the pieces are scaled as they come).
  void setVariableInt(const std::string& key, int value, int) override {
    if (key != "$INSUNITS") return;
    if (value != 0 && !o_.unitless_unit.empty() && insunits(value)) {
      units_error = fmt::format(
          "{}: its $INSUNITS gives its unit ({}): [geometry] units = \"{}\" is for a drawing "
          "that gives none; remove it",
          src_, insunits(value)->second, o_.unitless_unit);
      return;
    }
    if (value == 0) return;  // unitless: as the reader began (mm, or [geometry] units)
    const auto unit = insunits(value);
    if (!unit) {
      units_error = fmt::format(
          "{}: $INSUNITS {} is a unit trochomill does not read (0 unitless, 1 in, 2 ft, 4 mm, "
          "5 cm, 6 m, 8 microinch, 9 mil, 10 yd, 13 micron, 14 dm)",
          src_, value);
    } else if (entities_ > 0) {
      units_error = fmt::format(
          "{}: $INSUNITS comes after {} entities (a DXF's HEADER section comes before its "
          "ENTITIES)",
          src_, entities_);
    } else {
      unit_ = unit->first;
      units = unit->second;
    }
  }
  void addBlock(const DL_BlockData&) override {
    flush();
    in_block_ = true;
  }
  void endBlock() override {
    flush();
    in_block_ = false;
  }
  // A spline is whole at its entity's end; a polyline's vertices may follow as entities of
  // their own (POLYLINE ... VERTEX ... SEQEND): it is whole when the next entity begins.
  void endEntity() override {
    if (spline_) finish_spline();
  }
  void endSequence() override { flush(); }

  void addLine(const DL_LineData& d) override {
    if (!begin("LINE")) return;
    if (!flat(d.z1, d.z2))
      return problem("a line out of the XY plane (its ends at z {} and {})", d.z1, d.z2);
    add(ContourPiece::line(xy(d.x1, d.y1), xy(d.x2, d.y2)));
  }
  void addArc(const DL_ArcData& d) override {
    if (!begin("ARC")) return;
    if (!(d.radius > 0)) return problem("an arc of radius {}", d.radius);
    const double a0 = deg_to_rad(d.angle1), a1 = deg_to_rad(d.angle2);
    const Vec2 c = xy(d.cx, d.cy);
    const double r = d.radius;
    const Vec2 s = c + r * dir(a0), e = c + r * dir(a1);
    add(ContourPiece::arc(s, e, c, true));
  }
  void addCircle(const DL_CircleData& d) override {
    if (!begin("CIRCLE")) return;
    if (!(d.radius > 0)) return problem("a circle of radius {}", d.radius);
    const Vec2 c = xy(d.cx, d.cy);
    const Vec2 a = c + Vec2(d.radius, 0), b = c - Vec2(d.radius, 0);
    add(ContourPiece::arc(a, b, c, true));
    add(ContourPiece::arc(b, a, c, true));
  }
  void addPolyline(const DL_PolylineData& d) override {
    poly_at_ = count_["POLYLINE"];  // (begin counts it: the k-th POLYLINE or LWPOLYLINE)
    vertex_at_ = 0;
    if (!begin("POLYLINE")) return;
    if (d.flags & (16 | 64)) return problem("a polygon mesh or polyface (not a 2D polyline)");
    poly_ = Poly{};
    poly_->closed = (d.flags & 1) != 0;
  }
  void addVertex(const DL_VertexData& d) override {
    if (!poly_) return;
    // A spline-fit POLYLINE holds its spline's frame (vertex flag 16, the control points)
    // beside the fitted vertices (flag 8): the curve is the fitted ones.
    const std::size_t j = vertex_at_++;
    if (poly_at_ < scan_.vertex_flags.size() && j < scan_.vertex_flags[poly_at_].size() &&
        (scan_.vertex_flags[poly_at_][j] & 16) != 0) {
      return;
    }
    poly_->v.push_back({xy(d.x, d.y), d.bulge, d.z});
  }
  void addSpline(const DL_SplineData& d) override {
    if (!begin("SPLINE")) return;
    spline_ = Spline{};
    spline_->degree = static_cast<int>(d.degree);
    spline_->fit = d.nFit;
  }
  void addKnot(const DL_KnotData& d) override {
    if (spline_) spline_->knots.push_back(d.k);
  }
  void addControlPoint(const DL_ControlPointData& d) override {
    if (spline_) {
      spline_->ctrl.emplace_back(d.x, d.y, d.z);
      spline_->w.push_back(d.w);
    }
  }
  void addEllipse(const DL_EllipseData& d) override {
    if (!begin("ELLIPSE")) return;
    // (A ratio above 1, which some writers give, is the same ellipse with its axes named the
    // other way round: the curve below takes either.)
    if (!(d.ratio > 0) || !std::isfinite(d.ratio)) {
      return problem("an ellipse of axis ratio {} (the minor axis over the major: need > 0)",
                     d.ratio);
    }
    const Vec2 c = xy(d.cx, d.cy), m = xy(d.mx, d.my);
    if (!(m.norm() > 0)) return problem("an ellipse with no major axis");
    // The minor axis: the major turned a quarter counter-clockwise, scaled by the ratio.
    const Vec2 minor = d.ratio * Vec2(-m.y(), m.x());
    if (!std::isfinite(d.angle2 - d.angle1)) {
      return problem("an ellipse whose parameters run from {} to {} (need finite angles, radians)",
                     d.angle1, d.angle2);
    }
    // Taken within a turn (a writer may give any multiple of 2 pi): at most one turn long,
    // and no huge angle left for the loop below or the arcs' count.
    const double t0 = std::fmod(d.angle1, kTwoPi);
    double t1 = t0 + std::fmod(d.angle2 - d.angle1, kTwoPi);
    while (t1 <= t0) t1 += kTwoPi;
    const EllipseCurve curve(Vec3(c.x(), c.y(), 0), Vec3(m.x(), m.y(), 0),
                             Vec3(minor.x(), minor.y(), 0));
    fit(curve, t0, t1, std::max(1, static_cast<int>(std::ceil((t1 - t0) / (0.5 * kPi)))));
  }
  void addInsert(const DL_InsertData& d) override {
    if (!begin("INSERT")) return;
    problem("an INSERT of block '{}': blocks are not read (explode the block in the CAD tool)",
            d.name);
  }

  void flush() {
    if (poly_) finish_polyline();
    if (spline_) finish_spline();
  }

 private:
  struct Poly {
    struct V {
      Vec2 p;
      double bulge, z;
    };
    std::vector<V> v;
    bool closed = false;
  };
  struct Spline {
    int degree = 0;
    unsigned fit = 0;
    std::vector<double> knots, w;
    std::vector<Vec3> ctrl;
  };

  template <typename... A>
  void problem(fmt::format_string<A...> f, A&&... a) {
    problem_layers.push_back(layer_);
    problems.push_back(fmt::format("{}: {} on layer '{}': {}", src_, entity_, layer_,
                                   fmt::format(f, std::forward<A>(a)...)));
  }

  // Starts an entity: its name for messages, its layer, its plane. False: skip it.
  bool begin(const char* kind) {
    flush();
    ++entities_;
    const std::size_t k = count_[kind]++;  // the k-th of its kind in the file (Scanned)
    if (in_block_ || units_error || limit_error) return false;
    const DL_Attributes& at = getAttributes();
    // Its type as the file names it (libdxflib hands an LWPOLYLINE over as a POLYLINE), and,
    // in a file without handles (R12 may omit them), its line instead.
    const std::string name = std::string(kind) == "POLYLINE" && k < scan_.poly_types.size()
                                 ? scan_.poly_types[k]
                                 : std::string(kind);
    const auto lines = scan_.lines.find(kind);
    const std::size_t line =
        lines != scan_.lines.end() && k < lines->second.size() ? lines->second[k] : 0;
    entity_ = at.getHandle() >= 0 ? fmt::format("{} #{:X}", name, at.getHandle())
              : line > 0          ? fmt::format("{} at line {}", name, line)
                                  : name;
    layer_ = at.getLayer();
    seen_layers.push_back(layer_);
    const double* z = getExtrusion()->getDirection();
    mirrored_ = false;
    if (std::abs(z[0]) > 1e-9 || std::abs(z[1]) > 1e-9 || z[2] == 0) {
      problem("out of the XY plane (its extrusion is ({}, {}, {}))", z[0], z[1], z[2]);
      return false;
    }
    mirrored_ = z[2] < 0;  // the entity's own x runs along -X
    if (!o_.layers.empty() &&
        std::none_of(o_.layers.begin(), o_.layers.end(),
                     [&](const std::string& l) { return same_name(l, layer_); })) {
      return false;
    }
    return true;
  }

  // Points in the entity's own coordinates; add() takes pieces into the drawing's (mm).
  static Vec2 xy(double x, double y) { return {x, y}; }
  static Vec2 dir(double a) { return {std::cos(a), std::sin(a)}; }
  // A piece from the entity's coordinates into the drawing's: mirrored (x -> -x, turning the
  // other way) when the entity's extrusion is -Z, scaled to mm.
  void add(ContourPiece p) {
    const auto place = [&](Vec2& v) { v = unit_ * Vec2(mirrored_ ? -v.x() : v.x(), v.y()); };
    place(p.start);
    place(p.end);
    if (p.centre) place(*p.centre);
    if (mirrored_) p.ccw = !p.ccw;
    if (p.start == p.end && !p.is_arc()) return;  // a zero-length line joins nothing
    pieces.push_back({p, layer_, entity_});
  }

  // Biarcs within the arc tolerance (in the entity's units: the tolerance divided by the unit).
  void fit(const PlanarCurve& c, double u0, double u1, int n) {
    try {
      const std::vector<FitArc> arcs =
          fit_biarcs_at_cusps(c, u0, u1, n, o_.arc_tolerance_mm / unit_, kMaxDrawingArcs - fitted_);
      fitted_ += arcs.size();
      for (const FitArc& a : arcs) add(to_piece(a));
    } catch (const ArcLimit&) {
      limit_error = fmt::format("{}: {} on layer '{}': {}", src_, entity_, layer_,
                                drawing_detail::too_many_arcs(o_.arc_tolerance_mm));
    } catch (const Error& e) {
      problem("cannot be fitted with arcs within {} mm ({})", o_.arc_tolerance_mm, e.what());
    }
  }

  void finish_polyline() {
    Poly p = std::move(*poly_);
    poly_.reset();
    for (std::size_t i = 1; i < p.v.size(); ++i) {
      if (!flat(p.v[i].z, p.v[0].z)) {
        return problem("a polyline out of the XY plane (its vertex {} at z {}, its first at {})",
                       i + 1, p.v[i].z, p.v[0].z);
      }
    }
    const std::size_t n = p.v.size();
    const std::size_t segs = p.closed ? n : (n == 0 ? 0 : n - 1);
    for (std::size_t i = 0; i < segs; ++i) {
      const auto &a = p.v[i], &b = p.v[(i + 1) % n];
      if (a.bulge == 0 || (a.p - b.p).norm() == 0) {
        add(ContourPiece::line(a.p, b.p));
        continue;
      }
      // bulge = tan(sweep / 4); the centre off the chord's middle along its left normal by
      // (d / 2) / tan(sweep / 2) (negative: to the right).
      const double th = 4 * std::atan(a.bulge);
      const Vec2 ch = b.p - a.p;
      const double d = ch.norm();
      const Vec2 left(-ch.y() / d, ch.x() / d);
      const Vec2 c = 0.5 * (a.p + b.p) + left * (0.5 * d / std::tan(0.5 * th));
      add(ContourPiece::arc(a.p, b.p, c, th > 0));
    }
  }

  void finish_spline() {
    Spline s = std::move(*spline_);
    spline_.reset();
    const std::size_t nc = s.ctrl.size();
    if (nc == 0 && s.fit > 0) {
      return problem(
          "a spline given by fit points only; save it with its control points (or as a polyline)");
    }
    if (s.degree < 1 || nc < static_cast<std::size_t>(s.degree) + 1 ||
        s.knots.size() != nc + static_cast<std::size_t>(s.degree) + 1) {
      return problem(
          "a spline of degree {} with {} control points and {} knots (need "
          "degree >= 1, degree + 1 control points or more, control points + degree "
          "+ 1 knots)",
          s.degree, nc, s.knots.size());
    }
    for (std::size_t i = 0; i < nc; ++i) {
      if (!(s.w[i] > 0) || !std::isfinite(s.w[i])) {
        return problem("control point {} has the weight {} (need > 0)", i + 1, s.w[i]);
      }
      if (!flat(s.ctrl[i].z(), s.ctrl[0].z())) {
        return problem(
            "a spline out of the XY plane (its control point {} at z {}, its first at {})", i + 1,
            s.ctrl[i].z(), s.ctrl[0].z());
      }
    }
    for (std::size_t i = 1; i < s.knots.size(); ++i) {
      if (!(s.knots[i] >= s.knots[i - 1])) return problem("its knots decrease at knot {}", i + 1);
    }
    const NurbsCurve curve(s.degree, s.knots, s.ctrl, s.w);
    if (!(curve.u1() > curve.u0())) return problem("its knots span no parameter range");
    fit(curve, curve.u0(), curve.u1(), static_cast<int>(std::max<std::size_t>(4, nc)));
  }

  // Heights equal to 1e-6 mm are one plane: CAD tools write -5e-14 for 0.
  [[nodiscard]] bool flat(double z0, double z1) const { return std::abs(z0 - z1) * unit_ <= 1e-6; }

 private:
  std::string src_;
  const DrawingOptions& o_;
  const Scanned& scan_;
  std::string units_given_;  // `units` of a unitless drawing read in [geometry] units
  std::map<std::string, std::size_t> count_;  // entities handed over so far, by kind
  std::size_t poly_at_ = 0, vertex_at_ = 0;   // the polyline being read, its next vertex
  bool in_block_ = false, mirrored_ = false;
  std::string entity_, layer_;
  std::optional<Poly> poly_;
  std::optional<Spline> spline_;
  std::size_t entities_ = 0;
  std::size_t fitted_ = 0;  // arcs fitted to the drawing's curves so far
  double unit_ = insunits(0)->first;
};

}  // namespace

Drawing read_dxf(const std::filesystem::path& file, const DrawingOptions& options) {
  const std::string source = file.string();
  const std::string text = read_drawing_text(file, "DXF", options);
  Drawing d;
  d.file = file;
  const Scanned scan = scan_groups(text);
  Reader r(source, options, scan);
  std::istringstream in(text);
  DL_Dxf dxf;
  dxf.in(in, &r);
  r.flush();
  if (scan.opened && !scan.closed) {
    throw InputError(fmt::format(
        "{}: its ENTITIES section has no end (0 ENDSEC): the file is cut short (saved or copied "
        "only in part?)",
        source));
  }
  if (r.units_error) throw InputError(*r.units_error);
  if (r.limit_error) throw InputError(*r.limit_error);
  d.mm_per_unit = r.unit();
  d.units = r.units;
  std::vector<std::string>& seen = r.seen_layers;
  std::sort(seen.begin(), seen.end());
  seen.erase(std::unique(seen.begin(), seen.end()), seen.end());
  if (!r.problems.empty()) {
    // Read whole (no layer chosen): which layers read without a problem, since a job, or
    // check-drawing --layer, reads only the layers it names.
    std::vector<std::string>& bad = r.problem_layers;
    std::sort(bad.begin(), bad.end());
    bad.erase(std::unique(bad.begin(), bad.end()), bad.end());
    std::vector<std::string> good = seen;
    good.erase(std::remove_if(good.begin(), good.end(),
                              [&](const std::string& l) {
                                return std::binary_search(bad.begin(), bad.end(), l);
                              }),
               good.end());
    if (options.layers.empty() && !good.empty()) {
      r.problems.push_back(fmt::format(
          "{}: the layers above hold what cannot be read; a job reads only the layers it names, "
          "and check-drawing --layer L one of them: these read without a problem: {}",
          source, fmt::join(good, ", ")));
    }
    throw InputError(r.problems);
  }
  if (r.pieces.empty() && options.layers.empty()) {
    std::vector<std::string> held;
    for (const auto& [type, n] : scan.types) held.push_back(fmt::format("{} {}", n, type));
    throw InputError(
        held.empty()
            ? fmt::format("{}: no line, arc or curve in it (no ENTITIES section{})", source,
                          scan.eof ? ": is it a DXF file?"
                                   : ", and it ends before its EOF: the file is cut short")
            : fmt::format("{}: no line, arc or curve in it: its entities are {} (contours are "
                          "drawn with LINE, ARC, CIRCLE, LWPOLYLINE, POLYLINE, SPLINE, ELLIPSE)",
                          source, fmt::join(held, ", ")));
  }
  for (const DrawnPiece& p : r.pieces) d.layers.push_back(p.layer);
  std::sort(d.layers.begin(), d.layers.end());
  d.layers.erase(std::unique(d.layers.begin(), d.layers.end()), d.layers.end());
  for (const std::string& want : options.layers) {
    const bool found = std::any_of(d.layers.begin(), d.layers.end(),
                                   [&](const std::string& l) { return same_name(l, want); });
    if (!found) {
      throw InputError(fmt::format(
          "{}: no line, arc or curve on layer '{}' (the layers with entities: {})", source, want,
          seen.empty() ? std::string("none") : fmt::format("{}", fmt::join(seen, ", "))));
    }
  }
  try {
    d.contours = chain_pieces(std::move(r.pieces), options.join_tolerance_mm);
  } catch (const InputError& e) {
    throw InputError(fmt::format("{}: {}", source, e.what()));
  }
  return d;
}

std::string read_drawing_text(const std::filesystem::path& file, std::string_view kind,
                              const DrawingOptions& options) {
  if (!(options.arc_tolerance_mm > 0) || !(options.join_tolerance_mm > 0)) {
    throw InputError("drawing: the arc and join tolerances must be > 0 mm");
  }
  std::error_code ec;
  const auto status = std::filesystem::status(file, ec);
  if (ec || !std::filesystem::exists(status)) {
    throw InputError(
        fmt::format("{}: cannot open the {} file: it does not exist", file.string(), kind));
  }
  if (!std::filesystem::is_regular_file(status)) {
    throw InputError(fmt::format("{}: not a {} file (a folder or a device)", file.string(), kind));
  }
  const std::uintmax_t size = std::filesystem::file_size(file, ec);
  constexpr std::uintmax_t kMaxBytes = 1ULL << 30;
  if (!ec && size > kMaxBytes) {
    throw InputError(fmt::format("{}: {:.3g} GB, more than the 1 GB a drawing may have",
                                 file.string(), static_cast<double>(size) / 1e9));
  }
  try {
    return read_text_file(file);
  } catch (const Error& e) {
    throw InputError(
        fmt::format("{}: cannot open the {} file ({})", file.string(), kind, e.what()));
  }
}

std::optional<double> drawing_unit_mm(const std::string& name) {
  static const std::pair<const char*, double> kUnits[] = {
      {"mm", 1.0}, {"cm", 10.0}, {"m", 1000.0}, {"in", 25.4}, {"ft", 304.8}};
  for (const auto& [n, mm] : kUnits) {
    if (name == n) return mm;
  }
  return std::nullopt;
}

Drawing read_drawing(const std::filesystem::path& file, const DrawingOptions& options) {
  std::string ext = file.extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  if (ext == ".dxf") return read_dxf(file, options);
  if (ext == ".svg") {
    if (!options.unitless_unit.empty()) {
      throw InputError(fmt::format(
          "{}: [geometry] units = \"{}\" is for a DXF drawing that gives no unit; an SVG's "
          "unit is its own (px, 96 to the inch, or its viewBox in mm): remove it",
          file.string(), options.unitless_unit));
    }
    return read_svg(file, options);
  }
  throw InputError(fmt::format("{}: a drawing must be a .dxf or .svg file (got '{}')",
                               file.string(), ext.empty() ? std::string("no extension") : ext));
}

}  // namespace trochomill
