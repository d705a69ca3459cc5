// The medial axis of a planar region from Boost.Polygon's Voronoi diagram of its boundary's
// segments (geometry.hpp, medial_axis).
#include <fmt/format.h>

#include <algorithm>
#include <boost/polygon/point_data.hpp>
#include <boost/polygon/segment_data.hpp>
#include <boost/polygon/voronoi.hpp>
#include <cmath>
#include <cstdint>
#include <limits>
#include <map>

#include "trochomill/error.hpp"
#include "trochomill/geometry.hpp"
#include "trochomill/units.hpp"

namespace trochomill {

namespace {

namespace bp = boost::polygon;
using IPoint = bp::point_data<std::int32_t>;
using ISegment = bp::segment_data<std::int32_t>;
using Diagram = bp::voronoi_diagram<double>;

// The closest point to p of the segment [a, b].
Vec2 foot(const Vec2& p, const Vec2& a, const Vec2& b) {
  const Vec2 d = b - a;
  const double L2 = d.squaredNorm();
  if (L2 <= 0) return a;
  return a + std::clamp((p - a).dot(d) / L2, 0.0, 1.0) * d;
}

// The distance from a point to the nearest of a set of segments, through a uniform grid of
// square cells: each segment listed in the cells it crosses (column by column), a query
// reading rings of cells about its own until the nearest found lies within the rings read (a
// point of ring r is more than (r - 1) cells away). The same minimum, to the bit, as over all
// the segments (the nearest is among those read); a point outside the grid reads them all.
class NearestSegment {
 public:
  explicit NearestSegment(const std::vector<std::pair<Vec2, Vec2>>& segs) : segs_(segs) {
    if (segs.empty()) return;
    lo_ = hi_ = segs.front().first;
    for (const auto& [a, b] : segs) {
      for (const Vec2& q : {a, b}) {
        lo_ = lo_.cwiseMin(q);
        hi_ = hi_.cwiseMax(q);
      }
    }
    // About as many cells as segments, at most 2048 a side.
    const Vec2 size = hi_ - lo_;
    const double area = std::max(size.x(), 1e-9) * std::max(size.y(), 1e-9);
    cell_ = std::max(
        {std::sqrt(area / static_cast<double>(segs.size())), size.maxCoeff() / 2048, 1e-6});
    nx_ = static_cast<int>(std::floor(size.x() / cell_)) + 1;
    ny_ = static_cast<int>(std::floor(size.y() / cell_)) + 1;
    std::vector<std::pair<int, int>> entries;  // (cell, segment)
    for (std::size_t k = 0; k < segs.size(); ++k) {
      const Vec2& a = segs[k].first;
      const Vec2& b = segs[k].second;
      const int c0 = col(std::min(a.x(), b.x())), c1 = col(std::max(a.x(), b.x()));
      for (int c = c0; c <= c1; ++c) {
        // The segment's y range within the column (its ends where the column holds them).
        const double x0 = lo_.x() + c * cell_, x1 = x0 + cell_;
        double ya = a.y(), yb = b.y();
        if (b.x() != a.x()) {
          const auto y_at = [&](double x) {
            const double t = std::clamp((x - a.x()) / (b.x() - a.x()), 0.0, 1.0);
            return a.y() + t * (b.y() - a.y());
          };
          ya = y_at(x0);
          yb = y_at(x1);
        }
        const int r0 = row(std::min(ya, yb)), r1 = row(std::max(ya, yb));
        for (int r = std::max(0, r0 - 1); r <= std::min(ny_ - 1, r1 + 1); ++r) {
          entries.emplace_back(r * nx_ + c, static_cast<int>(k));
        }
      }
    }
    std::sort(entries.begin(), entries.end());
    entries.erase(std::unique(entries.begin(), entries.end()), entries.end());
    start_.assign(static_cast<std::size_t>(nx_) * ny_ + 1, 0);
    for (const auto& [c, k] : entries) ++start_[static_cast<std::size_t>(c) + 1];
    for (std::size_t i = 1; i < start_.size(); ++i) start_[i] += start_[i - 1];
    list_.reserve(entries.size());
    for (const auto& [c, k] : entries) list_.push_back(k);
  }

  [[nodiscard]] double distance(const Vec2& p) const {
    double best = std::numeric_limits<double>::infinity();
    const auto take = [&](int k) {
      const auto& [a, b] = segs_[static_cast<std::size_t>(k)];
      best = std::min(best, (foot(p, a, b) - p).norm());
    };
    if (segs_.empty()) return best;
    if (!(p.x() >= lo_.x() && p.y() >= lo_.y() && p.x() <= hi_.x() && p.y() <= hi_.y())) {
      for (std::size_t k = 0; k < segs_.size(); ++k) take(static_cast<int>(k));
      return best;
    }
    const int cx = col(p.x()), cy = row(p.y());
    for (int r = 0;; ++r) {
      const int x0 = cx - r, x1 = cx + r, y0 = cy - r, y1 = cy + r;
      if (x0 < 0 && y0 < 0 && x1 >= nx_ && y1 >= ny_) break;  // every cell read
      for (int y = std::max(0, y0); y <= std::min(ny_ - 1, y1); ++y) {
        const bool edge_row = y == y0 || y == y1;
        for (int x = std::max(0, x0); x <= std::min(nx_ - 1, x1); ++x) {
          if (!edge_row && x != x0 && x != x1) continue;  // the ring only
          const std::size_t c = static_cast<std::size_t>(y) * nx_ + x;
          for (int i = start_[c]; i < start_[c + 1]; ++i) take(list_[static_cast<std::size_t>(i)]);
        }
      }
      if (best <= r * cell_) break;  // ring r + 1 and beyond: more than r cells away
    }
    return best;
  }

 private:
  [[nodiscard]] int col(double x) const {
    return std::clamp(static_cast<int>(std::floor((x - lo_.x()) / cell_)), 0, nx_ - 1);
  }
  [[nodiscard]] int row(double y) const {
    return std::clamp(static_cast<int>(std::floor((y - lo_.y()) / cell_)), 0, ny_ - 1);
  }
  const std::vector<std::pair<Vec2, Vec2>>& segs_;
  Vec2 lo_ = Vec2::Zero(), hi_ = Vec2::Zero();
  double cell_ = 1;
  int nx_ = 1, ny_ = 1;
  std::vector<int> start_, list_;
};

// region_contains for a region of lines only (offset_region's): the same test on the same
// pieces (a rightward ray from the point, a piece crossing it when one end lies above the
// point and the other not, counted where it lies right of the point), but only on the pieces
// listed in the point's band of y (each piece in every band its y range meets), so the same
// answer to the bit. Not usable with arcs (region_contains then).
class InsideLines {
 public:
  explicit InsideLines(const std::vector<Contour>& region) {
    for (const Contour& c : region) {
      for (const ContourPiece& piece : c.pieces) {
        if (piece.is_arc()) return;
        pieces_.emplace_back(piece.start, piece.end);
      }
    }
    usable_ = true;
    if (pieces_.empty()) return;
    lo_ = hi_ = pieces_.front().first.y();
    for (const auto& [a, b] : pieces_) {
      lo_ = std::min({lo_, a.y(), b.y()});
      hi_ = std::max({hi_, a.y(), b.y()});
    }
    bands_ = static_cast<int>(std::clamp<std::size_t>(pieces_.size() / 4, 1, 1 << 16));
    h_ = std::max((hi_ - lo_) / bands_, 1e-12);
    std::vector<std::pair<int, int>> entries;
    for (std::size_t k = 0; k < pieces_.size(); ++k) {
      const auto& [a, b] = pieces_[k];
      for (int r = band(std::min(a.y(), b.y())); r <= band(std::max(a.y(), b.y())); ++r) {
        entries.emplace_back(r, static_cast<int>(k));
      }
    }
    std::sort(entries.begin(), entries.end());
    start_.assign(static_cast<std::size_t>(bands_) + 1, 0);
    for (const auto& [r, k] : entries) ++start_[static_cast<std::size_t>(r) + 1];
    for (std::size_t i = 1; i < start_.size(); ++i) start_[i] += start_[i - 1];
    for (const auto& [r, k] : entries) list_.push_back(k);
  }
  [[nodiscard]] bool usable() const { return usable_; }
  [[nodiscard]] bool contains(const Vec2& p) const {
    if (pieces_.empty() || !(p.y() >= lo_ && p.y() <= hi_)) return false;
    const int r = band(p.y());
    int n = 0;
    for (int i = start_[static_cast<std::size_t>(r)]; i < start_[static_cast<std::size_t>(r) + 1];
         ++i) {
      const auto& [a, b] = pieces_[static_cast<std::size_t>(list_[static_cast<std::size_t>(i)])];
      if ((a.y() > p.y()) == (b.y() > p.y())) continue;
      const double x = a.x() + (p.y() - a.y()) / (b.y() - a.y()) * (b.x() - a.x());
      if (x > p.x()) ++n;
    }
    return n % 2 == 1;
  }

 private:
  [[nodiscard]] int band(double y) const {
    return std::clamp(static_cast<int>(std::floor((y - lo_) / h_)), 0, bands_ - 1);
  }
  std::vector<std::pair<Vec2, Vec2>> pieces_;
  bool usable_ = false;
  double lo_ = 0, hi_ = 0, h_ = 1;
  int bands_ = 1;
  std::vector<int> start_, list_;
};

}  // namespace

std::vector<MedialBranch> medial_axis(const std::vector<Contour>& region, double min_angle_deg,
                                      double spacing_mm) {
  if (!(min_angle_deg > 0 && min_angle_deg < 180)) {
    throw Error(fmt::format("medial_axis: angle {} degrees: allowed (0, 180)", min_angle_deg));
  }
  if (!(spacing_mm > 0) || !std::isfinite(spacing_mm)) {
    throw Error(fmt::format("medial_axis: spacing {} mm: allowed > 0", spacing_mm));
  }
  // The boundary's chords, within 1 um of arcs (offset_region's regions are chords already).
  std::vector<std::pair<Vec2, Vec2>> edges;
  Box3 box;
  for (const Contour& c : region) {
    if (!c.closed) throw InputError("medial_axis: an open contour bounds no region");
    const std::vector<Vec2> pts = c.points(1e-3);
    for (std::size_t i = 0; i < pts.size(); ++i) {
      edges.emplace_back(pts[i], pts[(i + 1) % pts.size()]);
      box.extend(Vec3(pts[i].x(), pts[i].y(), 0));
    }
  }
  if (edges.empty()) return {};
  // On an integer grid about the box's centre: 1 nm (Clipper's, so offset_region's vertices
  // come back exactly and its edges, which cross nowhere, still do not) while the region fits
  // in +-2 m, coarser beyond.
  const double extent = std::max({box.hi.x() - box.lo.x(), box.hi.y() - box.lo.y(), 1e-3});
  if (!std::isfinite(extent)) throw InputError("medial_axis: a point is not finite");
  double scale = 1e6;
  while (0.5 * extent * scale > 1.9e9) scale /= 10;
  const Vec2 mid(std::round(0.5 * (box.lo.x() + box.hi.x()) * 1e3) / 1e3,
                 std::round(0.5 * (box.lo.y() + box.hi.y()) * 1e3) / 1e3);
  auto to_int = [&](const Vec2& p) {
    return IPoint(static_cast<std::int32_t>(std::llround((p.x() - mid.x()) * scale)),
                  static_cast<std::int32_t>(std::llround((p.y() - mid.y()) * scale)));
  };
  auto to_mm = [&](double x, double y) { return Vec2(x / scale + mid.x(), y / scale + mid.y()); };
  std::vector<ISegment> segments;
  std::vector<std::pair<Vec2, Vec2>> kept;  // each segment in mm, as rounded
  for (const auto& [a, b] : edges) {
    const IPoint ia = to_int(a), ib = to_int(b);
    if (ia == ib) continue;
    segments.emplace_back(ia, ib);
    kept.emplace_back(to_mm(ia.x(), ia.y()), to_mm(ib.x(), ib.y()));
  }
  Diagram vd;
  bp::construct_voronoi(segments.begin(), segments.end(), &vd);

  // The site of a cell: a segment, or one of its ends.
  struct Site {
    Vec2 a, b;  // a == b for a point
  };
  auto site_of = [&](const Diagram::cell_type& cell) {
    const auto& s = kept[cell.source_index()];
    switch (cell.source_category()) {
      case bp::SOURCE_CATEGORY_SEGMENT_START_POINT:
        return Site{s.first, s.first};
      case bp::SOURCE_CATEGORY_SEGMENT_END_POINT:
        return Site{s.second, s.second};
      default:
        return Site{s.first, s.second};
    }
  };
  const NearestSegment nearest(kept);
  auto clearance = [&](const Vec2& p) { return nearest.distance(p); };
  const InsideLines lines(region);
  auto inside = [&](const Vec2& p) {
    return lines.usable() ? lines.contains(p) : region_contains(region, p);
  };
  const double cos_min = std::cos(deg_to_rad(min_angle_deg));

  // The kept edges: primary, finite, inside the region, their two sites seen from the edge's
  // middle at least min_angle apart. Vertices numbered in the diagram's order.
  std::map<const Diagram::vertex_type*, int> index;
  std::vector<Vec2> nodes;
  std::vector<std::vector<int>> adj;  // node -> edges
  std::vector<std::pair<int, int>> links;
  auto node = [&](const Diagram::vertex_type* v) {
    const auto [it, fresh] = index.emplace(v, static_cast<int>(nodes.size()));
    if (fresh) {
      nodes.push_back(to_mm(v->x(), v->y()));
      adj.emplace_back();
    }
    return it->second;
  };
  for (const auto& e : vd.edges()) {
    if (!e.is_primary() || !e.is_finite()) continue;
    if (&e > e.twin()) continue;  // each edge once
    const Vec2 p0 = to_mm(e.vertex0()->x(), e.vertex0()->y());
    const Vec2 p1 = to_mm(e.vertex1()->x(), e.vertex1()->y());
    const Vec2 m = 0.5 * (p0 + p1);
    // Its ends inside or on the boundary (an axis running into a convex corner of the region,
    // a wedge's tip, ends there), its middle inside.
    const auto inside_or_on = [&](const Vec2& q) { return inside(q) || clearance(q) <= 1e-6; };
    if (!inside(m) || !inside_or_on(p0) || !inside_or_on(p1)) continue;
    const Site sa = site_of(*e.cell()), sb = site_of(*e.twin()->cell());
    const Vec2 fa = foot(m, sa.a, sa.b) - m, fb = foot(m, sb.a, sb.b) - m;
    const double na = fa.norm(), nb = fb.norm();
    if (!(na > 0 && nb > 0) || fa.dot(fb) > cos_min * na * nb) continue;
    const int i = node(e.vertex0()), j = node(e.vertex1());
    if (i == j) continue;
    adj[static_cast<std::size_t>(i)].push_back(static_cast<int>(links.size()));
    adj[static_cast<std::size_t>(j)].push_back(static_cast<int>(links.size()));
    links.emplace_back(i, j);
  }

  // Branches: runs of links between nodes that do not have exactly two; then the cycles left.
  std::vector<bool> used(links.size(), false);
  std::vector<MedialBranch> out;
  auto walk = [&](int from, int first_link) {
    std::vector<int> path{from};
    int at = from, l = first_link;
    for (;;) {
      used[static_cast<std::size_t>(l)] = true;
      const auto [a, b] = links[static_cast<std::size_t>(l)];
      at = a == at ? b : a;
      path.push_back(at);
      const auto& here = adj[static_cast<std::size_t>(at)];
      if (here.size() != 2 || at == from) break;
      const int next = here[0] == l ? here[1] : here[0];
      if (used[static_cast<std::size_t>(next)]) break;
      l = next;
    }
    MedialBranch br;
    br.closed = path.size() > 2 && path.front() == path.back();
    for (std::size_t k = 0; k + 1 < path.size(); ++k) {
      const Vec2 a = nodes[static_cast<std::size_t>(path[k])];
      const Vec2 b = nodes[static_cast<std::size_t>(path[k + 1])];
      const int n = std::max(1, static_cast<int>(std::ceil((b - a).norm() / spacing_mm)));
      for (int q = 0; q < n; ++q) br.points.push_back(a + (b - a) * (static_cast<double>(q) / n));
    }
    br.points.push_back(nodes[static_cast<std::size_t>(path.back())]);
    if (br.closed) br.points.pop_back();
    // A sample outside (a curved edge's chord cutting across a hole's corner): no disc.
    for (const Vec2& p : br.points) {
      br.clearance_mm.push_back(inside(p) ? clearance(p) : 0.0);
    }
    out.push_back(std::move(br));
  };
  for (std::size_t n = 0; n < nodes.size(); ++n) {
    if (adj[n].size() == 2) continue;
    for (const int l : adj[n]) {
      if (!used[static_cast<std::size_t>(l)]) walk(static_cast<int>(n), l);
    }
  }
  for (std::size_t l = 0; l < links.size(); ++l) {
    if (!used[l]) walk(links[l].first, static_cast<int>(l));
  }
  return out;
}

}  // namespace trochomill
