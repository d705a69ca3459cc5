// Chaining a drawing's pieces into contours (geometry/drawing.hpp).
#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <tuple>
#include <unordered_map>

#include "trochomill/error.hpp"
#include "trochomill/geometry/drawing.hpp"

namespace trochomill {
namespace {

// An end of a piece: piece index * 2 + (0 start, 1 end).
using End = std::size_t;

const Vec2& end_point(const std::vector<DrawnPiece>& p, End e) {
  return e % 2 == 0 ? p[e / 2].piece.start : p[e / 2].piece.end;
}

// The ends within `tol` of each end (same layer only), in compressed rows: the partners of
// end e are list[first[e] .. first[e + 1]). Found through the ends sorted by layer and grid
// cell: cells 2 tol wide, so an end's partners lie in its cell or the next one towards the
// half of the cell it is in, along x and y: two runs of the sorted ends, each found by one
// binary search (the cells of one column, y next to y, are consecutive).
struct Partners {
  std::vector<std::size_t> first;
  std::vector<End> list;
  [[nodiscard]] std::size_t count(End e) const { return first[e + 1] - first[e]; }
};

Partners partners_of(const std::vector<DrawnPiece>& p, double tol) {
  // Layers as numbers (pieces of one layer mostly come together: compare with the last).
  std::vector<std::uint32_t> layer(p.size());
  {
    std::unordered_map<std::string, std::uint32_t> ids;
    for (std::size_t i = 0; i < p.size(); ++i) {
      if (i > 0 && p[i].layer == p[i - 1].layer) {
        layer[i] = layer[i - 1];
      } else {
        layer[i] = ids.emplace(p[i].layer, static_cast<std::uint32_t>(ids.size())).first->second;
      }
    }
  }
  using Key = std::tuple<std::uint32_t, std::int64_t, std::int64_t>;  // layer, cell x, cell y
  const double size = 2 * tol;
  const std::size_t n = 2 * p.size();
  std::vector<std::pair<Key, End>> cells(n);
  for (End e = 0; e < n; ++e) {
    const Vec2& v = end_point(p, e);
    cells[e] = {Key{layer[e / 2], static_cast<std::int64_t>(std::floor(v.x() / size)),
                    static_cast<std::int64_t>(std::floor(v.y() / size))},
                e};
  }
  std::sort(cells.begin(), cells.end());
  Partners out;
  out.first.reserve(n + 1);
  std::vector<End> mine;
  for (End e = 0; e < n; ++e) {
    out.first.push_back(out.list.size());
    const Vec2& a = end_point(p, e);
    const double cx = a.x() / size, cy = a.y() / size;
    const auto ix = static_cast<std::int64_t>(std::floor(cx));
    const auto iy = static_cast<std::int64_t>(std::floor(cy));
    const std::int64_t ox = cx - static_cast<double>(ix) < 0.5 ? -1 : 1;
    const std::int64_t oy = cy - static_cast<double>(iy) < 0.5 ? -1 : 1;
    mine.clear();
    for (const std::int64_t x : {ix, ix + ox}) {
      const Key lo{layer[e / 2], x, std::min(iy, iy + oy)};
      const Key hi{layer[e / 2], x, std::max(iy, iy + oy)};
      auto it = std::lower_bound(cells.begin(), cells.end(), lo,
                                 [](const auto& c, const Key& k) { return c.first < k; });
      for (; it != cells.end() && it->first <= hi; ++it) {
        const End f = it->second;
        if (f / 2 != e / 2 && (end_point(p, f) - a).norm() <= tol) mine.push_back(f);
      }
    }
    std::sort(mine.begin(), mine.end());
    out.list.insert(out.list.end(), mine.begin(), mine.end());
  }
  out.first.push_back(out.list.size());
  return out;
}

std::string at(const Vec2& v) { return fmt::format("({:.6g}, {:.6g}) mm", v.x(), v.y()); }

}  // namespace

std::vector<DrawnContour> chain_pieces(std::vector<DrawnPiece> pieces, double join_mm) {
  // From 1 nm: the ends' grid cells (coordinates / join_mm) then stay far inside 64 bits.
  if (!(join_mm >= 1e-6 && join_mm <= 100)) {
    throw InputError(fmt::format("join tolerance {} mm: allowed 1e-6 to 100 mm", join_mm));
  }
  for (const DrawnPiece& d : pieces) {
    for (const Vec2* v : {&d.piece.start, &d.piece.end}) {
      if (!(std::abs(v->x()) <= 1e9 && std::abs(v->y()) <= 1e9)) {
        throw InputError(
            fmt::format("{} on layer '{}': the point ({}, {}) mm is not finite or "
                        "beyond 1000 km",
                        d.entity, d.layer, v->x(), v->y()));
      }
    }
  }
  const Partners partners = partners_of(pieces, join_mm);
  for (End e = 0; e < 2 * pieces.size(); ++e) {
    if (partners.count(e) >= 2) {
      std::string names = pieces[e / 2].entity;
      for (std::size_t k = partners.first[e]; k < partners.first[e + 1]; ++k) {
        names += ", " + pieces[partners.list[k] / 2].entity;
      }
      throw InputError(fmt::format(
          "layer '{}': a branch at {}: the ends of {} meet there (a contour may not fork)",
          pieces[e / 2].layer, at(end_point(pieces, e)), names));
    }
  }
  const auto partner = [&](End e) -> std::optional<End> {
    if (partners.count(e) == 0) return std::nullopt;
    return partners.list[partners.first[e]];
  };
  std::vector<char> used(pieces.size(), 0);
  std::vector<DrawnContour> out;
  std::vector<std::pair<End, End>> free_ends;  // of each open chain: (its start, its end)
  for (std::size_t i = 0; i < pieces.size(); ++i) {
    if (used[i]) continue;
    used[i] = 1;
    // Forward from the piece's end, each next piece turned to continue the chain.
    std::vector<std::pair<std::size_t, bool>> fwd{{i, false}};  // (piece, reversed)
    bool closed = false;
    End tail = 2 * i + 1;
    while (const auto next = partner(tail)) {
      const std::size_t j = *next / 2;
      if (j == i) {
        closed = true;
        break;
      }
      if (used[j]) break;
      used[j] = 1;
      const bool rev = *next % 2 == 1;  // it is the piece's end that meets: run it backwards
      fwd.push_back({j, rev});
      tail = rev ? 2 * j : 2 * j + 1;
    }
    std::vector<std::pair<std::size_t, bool>> back;
    End head = 2 * i;
    if (!closed) {
      while (const auto prev = partner(head)) {
        const std::size_t j = *prev / 2;
        if (used[j]) break;
        used[j] = 1;
        const bool rev = *prev % 2 == 0;  // its start meets our start: run it backwards
        back.push_back({j, rev});
        head = rev ? 2 * j + 1 : 2 * j;
      }
    }
    DrawnContour c;
    c.layer = pieces[i].layer;
    c.contour.closed = closed;
    for (auto it = back.rbegin(); it != back.rend(); ++it) {
      const DrawnPiece& d = pieces[it->first];
      c.contour.pieces.push_back(it->second ? d.piece.reversed() : d.piece);
      c.entities.push_back(d.entity);
    }
    for (const auto& [j, rev] : fwd) {
      const DrawnPiece& d = pieces[j];
      c.contour.pieces.push_back(rev ? d.piece.reversed() : d.piece);
      c.entities.push_back(d.entity);
    }
    // Joined ends meet exactly: each piece starts where the one before it ends.
    for (std::size_t k = 1; k < c.contour.pieces.size(); ++k) {
      c.contour.pieces[k].start = c.contour.pieces[k - 1].end;
    }
    if (closed) c.contour.pieces.front().start = c.contour.pieces.back().end;
    c.entities.erase(std::unique(c.entities.begin(), c.entities.end()), c.entities.end());
    if (!closed) free_ends.push_back({head, tail});
    out.push_back(std::move(c));
  }
  // A gap: two free ends nearer than ten tolerances were meant to meet.
  std::vector<End> ends;
  for (const auto& [h, t] : free_ends) ends.insert(ends.end(), {h, t});
  const double near = 10 * join_mm;
  for (std::size_t a = 0; a < ends.size(); ++a) {
    for (std::size_t b = a + 1; b < ends.size(); ++b) {
      const DrawnPiece &pa = pieces[ends[a] / 2], &pb = pieces[ends[b] / 2];
      if (pa.layer != pb.layer) continue;
      const double g = (end_point(pieces, ends[a]) - end_point(pieces, ends[b])).norm();
      if (g <= near) {
        throw InputError(fmt::format(
            "layer '{}': a gap of {:.6g} mm at {} between {} and {} (ends join within {} mm; "
            "close the gap in the drawing or raise the join tolerance)",
            pa.layer, g, at(end_point(pieces, ends[a])), pa.entity, pb.entity, join_mm));
      }
    }
  }
  return out;
}

}  // namespace trochomill
