// SVG drawings through pugixml (geometry/drawing.hpp): the document walked without recursion,
// shapes and path data (svg_syntax.hpp) mapped from user units to mm with y up, circular arcs
// kept exact, Béziers and elliptical arcs fitted with biarcs, then chained into contours.
// References: https://www.w3.org/TR/SVG11/paths.html (path data),
// https://www.w3.org/TR/SVG11/shapes.html (the basic shapes as paths),
// https://www.w3.org/TR/SVG11/coords.html (transforms, viewBox, preserveAspectRatio, units).
#include <fmt/format.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <fstream>
#include <optional>
#include <pugixml.hpp>
#include <sstream>

#include "geometry/svg_syntax.hpp"
#include "trochomill/error.hpp"
#include "trochomill/geometry/drawing.hpp"
#include "trochomill/units.hpp"

namespace trochomill {
namespace {

using svg::Affine;
using svg::Problem;

constexpr double kMmPerPx = 25.4 / 96;  // CSS: 96 px per in
constexpr std::size_t kMaxProblems = 50;
constexpr const char* kSvgNs = "http://www.w3.org/2000/svg";
constexpr const char* kInkscapeNs = "http://www.inkscape.org/namespaces/inkscape";

// What an element inherits: its user space in mm, its layer, the names its groups matched,
// the namespace prefixes bound (SVG's, Inkscape's).
struct Context {
  Affine ctm;
  std::optional<std::string> inkscape_layer, group_id;
  std::vector<char> group_hit;              // per DrawingOptions::layers: an enclosing group's id
  bool svg_default = true;                  // unprefixed names are SVG's
  std::string svg_prefix, inkscape_prefix;  // "svg:", "inkscape:" (empty: none bound)
};

// The namespace declarations on a node, into its context.
void bind_namespaces(const pugi::xml_node& n, Context& c) {
  for (const pugi::xml_attribute& a : n.attributes()) {
    const std::string_view name = a.name(), uri = a.value();
    if (name == "xmlns") c.svg_default = uri == kSvgNs;
    if (name.substr(0, 6) != "xmlns:") continue;
    const std::string prefix = std::string(name.substr(6)) + ":";
    if (uri == kSvgNs) c.svg_prefix = prefix;
    if (uri == kInkscapeNs) c.inkscape_prefix = prefix;
  }
}
bool declares_namespaces(const pugi::xml_node& n) {
  for (const pugi::xml_attribute& a : n.attributes()) {
    if (std::string_view(a.name()).substr(0, 5) == "xmlns") return true;
  }
  return false;
}

// An SVG element's local name ("" for another namespace's element).
std::string_view local_name(const pugi::xml_node& n, const Context& c) {
  const std::string_view name = n.name();
  const auto colon = name.find(':');
  if (colon == std::string_view::npos) return c.svg_default ? name : std::string_view();
  if (!c.svg_prefix.empty() && name.substr(0, colon + 1) == c.svg_prefix) {
    return name.substr(colon + 1);
  }
  return {};
}

// display="none" or display:none in the style attribute.
bool hidden(const pugi::xml_node& n) {
  const auto trim = [](std::string_view s) {
    while (!s.empty() && svg::is_wsp(s.front())) s.remove_prefix(1);
    while (!s.empty() && svg::is_wsp(s.back())) s.remove_suffix(1);
    return s;
  };
  if (trim(n.attribute("display").value()) == "none") return true;
  std::string_view style = n.attribute("style").value();
  while (!style.empty()) {
    const auto semi = style.find(';');
    const std::string_view decl = style.substr(0, semi);
    style = semi == std::string_view::npos ? std::string_view() : style.substr(semi + 1);
    const auto colon = decl.find(':');
    if (colon == std::string_view::npos) continue;
    if (trim(decl.substr(0, colon)) == "display" && trim(decl.substr(colon + 1)) == "none") {
      return true;
    }
  }
  return false;
}

class SvgReader {
 public:
  SvgReader(std::string source, std::string_view text, const DrawingOptions& o)
      : src_(std::move(source)), o_(o), used_(o.layers.size(), 0) {
    for (std::size_t i = 0; i < text.size(); ++i) {
      if (text[i] == '\n') line_starts_.push_back(i + 1);
    }
  }

  std::vector<DrawnPiece> pieces;
  std::vector<std::string> problems, seen_layers, seen_ids;

  // "line:column" of a byte offset.
  [[nodiscard]] std::string where(std::ptrdiff_t offset) const {
    if (offset < 0) return "?";
    const auto o = static_cast<std::size_t>(offset);
    const auto it = std::upper_bound(line_starts_.begin(), line_starts_.end(), o);
    return fmt::format("{}:{}", it - line_starts_.begin(), o - *(it - 1) + 1);
  }
  [[nodiscard]] std::size_t line_of(const pugi::xml_node& n) const {
    const std::ptrdiff_t off = n.offset_debug();
    if (off < 0) return 0;
    return static_cast<std::size_t>(
        std::upper_bound(line_starts_.begin(), line_starts_.end(), static_cast<std::size_t>(off)) -
        line_starts_.begin());
  }

  // The root's viewport: user units to mm with y up (SVG 1.1 7.2, 7.7, 7.8).
  Affine viewport(const pugi::xml_node& root, Drawing& d) {
    const auto length = [&](const char* name) -> std::optional<double> {
      const pugi::xml_attribute a = root.attribute(name);
      if (!a) return std::nullopt;
      const std::string_view v = a.value();
      if (v.find('%') != std::string_view::npos) return std::nullopt;  // of a window: none
      try {
        const double px = svg::read_length(v);
        if (px < 0) throw svg::SyntaxError{0, "a length > 0 (it is negative)"};
        if (px == 0) throw svg::SyntaxError{0, "a length > 0 (0 draws nothing)"};
        return px;
      } catch (const svg::SyntaxError& e) {
        throw InputError(fmt::format("{}: <svg> {}=\"{}\" (line {}): expected {}", src_, name, v,
                                     line_of(root), e.what));
      }
    };
    const std::optional<double> w = length("width"), h = length("height");
    const pugi::xml_attribute vb_attr = root.attribute("viewBox");
    if (!vb_attr) {
      // User units are px; y_mm = height_mm - y_mm when the page's height is known.
      d.mm_per_unit = kMmPerPx;
      d.units = "px (96 per in)";
      const double top = h ? *h * kMmPerPx : 0;
      return Affine{kMmPerPx, 0, 0, -kMmPerPx, 0, top};
    }
    double vb[4];
    const std::string_view vbs = vb_attr.value();
    try {
      std::size_t i = 0;
      svg::skip_comma_wsp(vbs, i);
      for (double& v : vb) {
        v = svg::read_number(vbs, i);
        svg::skip_comma_wsp(vbs, i);
      }
      if (i != vbs.size()) throw svg::SyntaxError{i, "four numbers only"};
      if (!(vb[2] > 0 && vb[3] > 0)) throw svg::SyntaxError{0, "a width and a height > 0"};
    } catch (const svg::SyntaxError& e) {
      throw InputError(fmt::format("{}: <svg> viewBox=\"{}\" (line {}): expected {}", src_, vbs,
                                   line_of(root), e.what));
    }
    // A size missing: from the other and the viewBox's aspect, or the viewBox in px.
    const double width = w ? *w : h ? *h * vb[2] / vb[3] : vb[2];
    const double height = h ? *h : w ? *w * vb[3] / vb[2] : vb[3];
    double sx = width / vb[2], sy = height / vb[3];
    const std::string_view par = root.attribute("preserveAspectRatio").as_string("xMidYMid meet");
    std::istringstream words{std::string(par)};
    std::string align, mode;
    words >> align;
    if (align == "defer") words >> align;
    words >> mode;
    static constexpr const char* kAligns[] = {"none",     "xMinYMin", "xMidYMin", "xMaxYMin",
                                              "xMinYMid", "xMidYMid", "xMaxYMid", "xMinYMax",
                                              "xMidYMax", "xMaxYMax"};
    std::string extra;
    words >> extra;
    if (std::find(std::begin(kAligns), std::end(kAligns), align) == std::end(kAligns) ||
        !(mode.empty() || mode == "meet" || mode == "slice") || !extra.empty()) {
      throw InputError(fmt::format(
          "{}: <svg> preserveAspectRatio=\"{}\" (line {}): expected an alignment (none, "
          "xMinYMin ... xMaxYMax) and meet or slice",
          src_, par, line_of(root)));
    }
    double tx = 0, ty = 0;
    if (align != "none") {
      sx = sy = mode == "slice" ? std::max(sx, sy) : std::min(sx, sy);
      const auto shift = [](std::string_view where, double room) {
        return where == "Mid" ? room / 2 : where == "Max" ? room : 0.0;
      };
      tx = shift(align.substr(1, 3), width - vb[2] * sx);
      ty = shift(align.substr(5, 3), height - vb[3] * sy);
    }
    d.mm_per_unit = std::sqrt(sx * sy) * kMmPerPx;
    d.units = fmt::format("user unit of {:.6g} mm (viewBox)", d.mm_per_unit);
    static constexpr std::pair<const char*, double> kNames[] = {
        {"mm", 1.0}, {"cm", 10.0}, {"in", 25.4}, {"pt", 25.4 / 72}, {"pc", 25.4 / 6}};
    for (const auto& [name, mm] : kNames) {
      if (sx == sy && std::abs(d.mm_per_unit - mm) <= 1e-12 * mm) {
        d.units = name;
        d.mm_per_unit = mm;  // 1, not 0.9999999999999999 (210mm into 210 units)
      }
    }
    if (sx == sy && std::abs(d.mm_per_unit - kMmPerPx) <= 1e-12) {
      d.units = "px (96 per in)";
      d.mm_per_unit = kMmPerPx;
    }
    // x_mm = (tx + sx (x - vb_x)) mm/px; y_mm = (height - ty - sy (y - vb_y)) mm/px.
    const double k = kMmPerPx;
    return Affine{k * sx, 0, 0, -k * sy, k * (tx - sx * vb[0]), k * (height - ty + sy * vb[1])};
  }

  void walk(const pugi::xml_node& root, Context top) {
    bind_namespaces(root, top);
    top.group_hit.assign(o_.layers.size(), 0);
    std::vector<Context> stack{std::move(top)};
    // Depth first in document order without recursion: down to a container's first child,
    // else on to the next sibling, climbing (and leaving containers) where there is none.
    pugi::xml_node n = root.first_child();
    while (n && n != root) {
      bool down = false;
      if (n.type() == pugi::node_element) down = element(n, stack);
      if (down) {
        n = n.first_child();
        continue;
      }
      while (n != root && !n.next_sibling()) {
        n = n.parent();
        if (n != root) stack.pop_back();
      }
      if (n == root) break;
      n = n.next_sibling();
    }
  }

  void check_names() {
    std::sort(seen_layers.begin(), seen_layers.end());
    seen_layers.erase(std::unique(seen_layers.begin(), seen_layers.end()), seen_layers.end());
    std::sort(seen_ids.begin(), seen_ids.end());
    seen_ids.erase(std::unique(seen_ids.begin(), seen_ids.end()), seen_ids.end());
    const auto list = [](const std::vector<std::string>& v) {
      if (v.empty()) return std::string("none");
      if (v.size() <= 20) return fmt::format("{}", fmt::join(v, ", "));
      return fmt::format("{}, ... ({} in all)", fmt::join(v.begin(), v.begin() + 20, ", "),
                         v.size());
    };
    for (std::size_t i = 0; i < o_.layers.size(); ++i) {
      if (used_[i]) continue;
      throw InputError(fmt::format(
          "{}: no line, arc or curve in an element with the id or on the layer '{}' (the "
          "layers with shapes: {}; the ids: {})",
          src_, o_.layers[i], list(seen_layers), list(seen_ids)));
    }
  }

 private:
  template <typename... A>
  void problem(const std::string& entity, const std::string& layer, fmt::format_string<A...> f,
               A&&... a) {
    problems.push_back(fmt::format("{}: {} on layer '{}': {}", src_, entity, layer,
                                   fmt::format(f, std::forward<A>(a)...)));
    if (problems.size() >= kMaxProblems) {
      problems.push_back(fmt::format("{}: stopped after {} problems", src_, kMaxProblems));
      throw InputError(problems);
    }
  }

  // An element: a container entered (true: go down into it), a shape read, others skipped.
  bool element(const pugi::xml_node& n, std::vector<Context>& stack) {
    Context local;
    const Context* ctx = &stack.back();
    if (declares_namespaces(n)) {
      local = *ctx;
      bind_namespaces(n, local);
      ctx = &local;
    }
    const std::string_view name = local_name(n, *ctx);
    if (name.empty() || hidden(n)) return false;
    const std::string id = n.attribute("id").value();
    const bool group = name == "g" || name == "a" || name == "switch" || name == "svg";
    if (group) {
      if (!n.first_child()) return false;
      Context c = *ctx;
      try {
        c.ctm = c.ctm * svg::read_transform(n.attribute("transform").value());
        if (name == "svg") c.ctm = c.ctm * nested_viewport(n);
      } catch (const svg::SyntaxError& e) {
        problem(entity_of(n, name, id), layer_of(c), "{}", syntax(n, "transform", e));
        return false;
      } catch (const Problem& p) {
        problem(entity_of(n, name, id), layer_of(c), "{}", p.what);
        return false;
      }
      if (name == "g" && !c.inkscape_prefix.empty() &&
          std::string_view(n.attribute((c.inkscape_prefix + "groupmode").c_str()).value()) ==
              "layer") {
        const std::string label = n.attribute((c.inkscape_prefix + "label").c_str()).value();
        c.inkscape_layer = !label.empty() ? label : !id.empty() ? id : "0";
      } else if (name == "g" && !id.empty()) {
        c.group_id = id;
      }
      if (!id.empty()) {
        seen_ids.push_back(id);
        for (std::size_t i = 0; i < o_.layers.size(); ++i) c.group_hit[i] |= o_.layers[i] == id;
      }
      stack.push_back(std::move(c));
      return true;
    }
    static constexpr const char* kShapes[] = {"path", "line",   "polyline", "polygon",
                                              "rect", "circle", "ellipse"};
    const bool shape = std::find(std::begin(kShapes), std::end(kShapes), name) != std::end(kShapes);
    if (!shape && name != "use") return false;  // defs, symbols, text, ...: not drawn
    const std::string layer = layer_of(*ctx), entity = entity_of(n, name, id);
    seen_layers.push_back(layer);
    if (!id.empty()) seen_ids.push_back(id);
    std::vector<std::size_t> names;  // the names of DrawingOptions::layers that choose it
    for (std::size_t i = 0; i < o_.layers.size(); ++i) {
      if (o_.layers[i] == id || o_.layers[i] == layer || ctx->group_hit[i]) names.push_back(i);
    }
    if (!o_.layers.empty() && names.empty()) return false;
    if (name == "use") {
      problem(
          entity, layer,
          "a <use> of '{}': references are not read (unlink the clone in the "
          "editor)",
          n.attribute("href") ? n.attribute("href").value() : n.attribute("xlink:href").value());
      return false;
    }
    const char* attr = "transform";
    try {
      const Affine m = ctx->ctm * svg::read_transform(n.attribute("transform").value());
      svg::PieceSink e(m, o_.arc_tolerance_mm, pieces, fitted_, layer, entity);
      attr = "d";
      shape_pieces(n, name, e, attr);
      if (e.added > 0) {
        for (const std::size_t i : names) used_[i] = 1;
      }
    } catch (const svg::Limit& l) {
      throw InputError(fmt::format("{}: {} on layer '{}': {}", src_, entity, layer, l.what));
    } catch (const svg::SyntaxError& e) {
      problem(entity, layer, "{}", syntax(n, attr, e));
    } catch (const Problem& p) {
      problem(entity, layer, "{}", p.what);
    }
    return false;
  }

  // A shape's pieces; `attr` names the attribute being read (for messages).
  void shape_pieces(const pugi::xml_node& n, std::string_view name, svg::PieceSink& e,
                    const char*& attr) {
    // A length attribute; nothing when it is absent or "auto" (SVG 2's radii).
    const auto opt = [&](const char* a) -> std::optional<double> {
      attr = a;
      const pugi::xml_attribute v = n.attribute(a);
      if (!v || std::string_view(v.value()) == "auto") return std::nullopt;
      return svg::read_length(v.value());
    };
    const auto len = [&](const char* a) { return opt(a).value_or(0.0); };
    // Negative sizes are errors; zero ones draw nothing (SVG 1.1 9.2 - 9.4).
    const auto drawn = [](const char* what, std::optional<double> v) {
      if (v && *v < 0) throw Problem{fmt::format("a negative {} ({})", what, *v)};
      return !v || *v > 0;
    };
    if (name == "path") {
      attr = "d";
      return svg::read_path(n.attribute("d").value(), e);
    }
    if (name == "line") return e.line({len("x1"), len("y1")}, {len("x2"), len("y2")});
    if (name == "polyline" || name == "polygon") {
      attr = "points";
      const std::string_view s = n.attribute("points").value();
      std::vector<Vec2> p;
      std::size_t i = 0;
      svg::skip_comma_wsp(s, i);
      while (i < s.size()) {
        const double x = svg::read_number(s, i);
        svg::skip_comma_wsp(s, i);
        if (i >= s.size()) throw svg::SyntaxError{i, "a y coordinate (the x has none)"};
        p.emplace_back(x, svg::read_number(s, i));
        svg::skip_comma_wsp(s, i);
      }
      for (std::size_t k = 1; k < p.size(); ++k) e.line(p[k - 1], p[k]);
      if (name == "polygon" && p.size() > 2) e.line(p.back(), p.front());
      return;
    }
    const double x = len(name == "rect" ? "x" : "cx"), y = len(name == "rect" ? "y" : "cy");
    if (name == "circle" || name == "ellipse") {
      const bool circle = name == "circle";
      std::optional<double> rx = opt(circle ? "r" : "rx"), ry = opt(circle ? "r" : "ry");
      if (!drawn("radius", rx) || !drawn("radius", ry)) return;
      if (!rx) rx = ry;  // SVG 2: an auto radius is the other
      if (!ry) ry = rx;
      if (!rx) return;  // no radius: nothing drawn
      // From (cx + rx, cy) towards +y (clockwise on the screen), as two halves.
      const Vec2 c(x, y), a(*rx, 0), b(0, *ry);
      e.ellipse(c, a, b, 0, kPi, c + a, c - a);
      return e.ellipse(c, a, b, kPi, kTwoPi, c - a, c + a);
    }
    if (name != "rect") return;
    const std::optional<double> w = opt("width"), h = opt("height"), orx = opt("rx"),
                                ory = opt("ry");
    if (!w || !h || !drawn("width", w) || !drawn("height", h)) return;
    if (!drawn("rx", orx) || !drawn("ry", ory)) return;
    // One radius given: both (SVG 1.1 9.2), each at most half the side.
    const double rx = std::min(orx ? *orx : ory.value_or(0.0), *w / 2);
    const double ry = std::min(ory ? *ory : orx.value_or(0.0), *h / 2);
    const Vec2 a(rx, 0), b(0, ry);
    // From (x + rx, y) along the top, clockwise on the screen, each corner a quarter ellipse.
    const Vec2 corners[4] = {
        {x + *w - rx, y + ry}, {x + *w - rx, y + *h - ry}, {x + rx, y + *h - ry}, {x + rx, y + ry}};
    const double W = *w, H = *h;
    const Vec2 along[4] = {{x + rx, y}, {x + W, y + ry}, {x + W - rx, y + H}, {x, y + H - ry}};
    const Vec2 to[4] = {{x + W - rx, y}, {x + W, y + H - ry}, {x + rx, y + H}, {x, y + ry}};
    for (int k = 0; k < 4; ++k) {
      e.line(along[k], to[k]);
      const double t0 = kPi * (k - 1) / 2;
      if (rx > 0 && ry > 0)
        e.ellipse(corners[k], a, b, t0, t0 + kPi / 2, to[k], along[(k + 1) % 4]);
    }
  }

  // A nested <svg>: its x and y, and its viewBox into its width and height (both needed).
  static Affine nested_viewport(const pugi::xml_node& n) {
    const auto len = [&](const char* a) {
      try {
        return n.attribute(a) ? svg::read_length(n.attribute(a).value()) : 0.0;
      } catch (const svg::SyntaxError& e) {
        throw Problem{
            fmt::format("bad {} (\"{}\"): expected {}", a, n.attribute(a).value(), e.what)};
      }
    };
    Affine t{1, 0, 0, 1, len("x"), len("y")};
    if (!n.attribute("viewBox")) return t;
    if (!n.attribute("width") || !n.attribute("height")) {
      throw Problem{"a nested <svg> with a viewBox needs a width and a height"};
    }
    const std::string_view vbs = n.attribute("viewBox").value();
    double vb[4];
    try {
      std::size_t i = 0;
      for (double& v : vb) {
        svg::skip_comma_wsp(vbs, i);
        v = svg::read_number(vbs, i);
      }
    } catch (const svg::SyntaxError& e) {
      throw Problem{fmt::format("bad viewBox (\"{}\"): expected {}", vbs, e.what)};
    }
    const double w = len("width"), h = len("height");
    if (!(vb[2] > 0 && vb[3] > 0 && w > 0 && h > 0)) {
      throw Problem{"a nested <svg> of zero size or viewBox"};
    }
    const double s = std::min(w / vb[2], h / vb[3]);  // xMidYMid meet
    return t * Affine{s, 0, 0, s, (w - vb[2] * s) / 2 - s * vb[0], (h - vb[3] * s) / 2 - s * vb[1]};
  }

  [[nodiscard]] std::string syntax(const pugi::xml_node& n, const char* attr,
                                   const svg::SyntaxError& e) const {
    const std::size_t size = std::string_view(n.attribute(attr).value()).size();
    return e.pos >= size ? fmt::format("bad {} at its end (character {}): expected {}", attr,
                                       e.pos + 1, e.what)
                         : fmt::format("bad {} at character {} ('{}'): expected {}", attr,
                                       e.pos + 1, n.attribute(attr).value()[e.pos], e.what);
  }
  [[nodiscard]] std::string entity_of(const pugi::xml_node& n, std::string_view name,
                                      const std::string& id) const {
    return id.empty() ? fmt::format("{} (line {})", name, line_of(n))
                      : fmt::format("{} #{}", name, id);
  }
  static std::string layer_of(const Context& c) {
    return c.inkscape_layer ? *c.inkscape_layer : c.group_id ? *c.group_id : "0";
  }

  std::string src_;
  const DrawingOptions& o_;
  std::vector<char> used_;
  std::vector<std::size_t> line_starts_{0};
  std::size_t fitted_ = 0;  // arcs fitted to the drawing's curves so far
};

}  // namespace

Drawing read_svg(const std::filesystem::path& file, const DrawingOptions& options) {
  const std::string source = file.string();
  const std::string text = read_drawing_text(file, "SVG", options);
  SvgReader r(source, text, options);
  pugi::xml_document doc;
  const pugi::xml_parse_result res = doc.load_buffer(text.data(), text.size());
  if (!res) {
    throw InputError(fmt::format("{}:{}: not an SVG file (XML: {})", source, r.where(res.offset),
                                 res.description()));
  }
  const pugi::xml_node root = doc.document_element();
  Context top;
  bind_namespaces(root, top);
  if (local_name(root, top) != "svg") {
    throw InputError(fmt::format("{}: the root element is <{}>, not <svg> (is it an SVG file?)",
                                 source, root.name()));
  }
  Drawing d;
  d.file = file;
  top.ctm = r.viewport(root, d);
  r.walk(root, std::move(top));
  if (!r.problems.empty()) throw InputError(r.problems);
  if (r.pieces.empty() && options.layers.empty()) {
    throw InputError(fmt::format(
        "{}: no line, arc or curve in it (hidden elements, defs and text are not read)", source));
  }
  r.check_names();
  for (const DrawnPiece& p : r.pieces) d.layers.push_back(p.layer);
  std::sort(d.layers.begin(), d.layers.end());
  d.layers.erase(std::unique(d.layers.begin(), d.layers.end()), d.layers.end());
  try {
    d.contours = chain_pieces(std::move(r.pieces), options.join_tolerance_mm);
  } catch (const InputError& e) {
    throw InputError(fmt::format("{}: {}", source, e.what()));
  }
  return d;
}

}  // namespace trochomill
