// Chaining a drawing's pieces into contours (geometry/drawing.hpp).
#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <optional>
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

// The piece ends by layer and grid cell, for the ends near a point: cells `size` wide, so the
// ends within size / 2 of a point lie in its cell or the next one towards the half of the
// cell it is in, along x and y (four cells). A hash table of the cells, each cell's ends
// linked through `next_` (the table's order depends on the input only).
class EndGrid {
 public:
  EndGrid(const std::vector<DrawnPiece>& p, const std::vector<End>& ends,
          const std::vector<std::uint32_t>& layer, double size)
      : size_(size), next_(ends.size(), kNone) {
    std::size_t slots = 16;
    while (slots < 2 * ends.size()) slots *= 2;
    head_.assign(slots, kNone);
    cell_.resize(ends.size());
    for (std::size_t k = 0; k < ends.size(); ++k) {
      const Vec2& v = end_point(p, ends[k]);
      cell_[k] = {ends[k], layer[ends[k] / 2], cell(v.x()), cell(v.y())};
      std::size_t& h = head_[slot(cell_[k].layer, cell_[k].x, cell_[k].y)];
      next_[k] = h;
      h = k;
    }
  }
  // Calls f(end) for every end of the layer in the four cells near a, until f returns false.
  template <class F>
  void near(const Vec2& a, std::uint32_t layer, F&& f) const {
    const double cx = a.x() / size_, cy = a.y() / size_;
    const std::int64_t ix = cell(a.x()), iy = cell(a.y());
    const std::int64_t ox = cx - static_cast<double>(ix) < 0.5 ? -1 : 1;
    const std::int64_t oy = cy - static_cast<double>(iy) < 0.5 ? -1 : 1;
    for (const std::int64_t x : {ix, ix + ox}) {
      for (const std::int64_t y : {iy, iy + oy}) {
        for (std::size_t k = head_[slot(layer, x, y)]; k != kNone; k = next_[k]) {
          const Cell& c = cell_[k];
          if (c.layer == layer && c.x == x && c.y == y && !f(c.end)) return;
        }
      }
    }
  }

 private:
  static constexpr std::size_t kNone = static_cast<std::size_t>(-1);
  struct Cell {
    End end;
    std::uint32_t layer;
    std::int64_t x, y;
  };
  [[nodiscard]] std::int64_t cell(double v) const {
    return static_cast<std::int64_t>(std::floor(v / size_));
  }
  [[nodiscard]] std::size_t slot(std::uint32_t layer, std::int64_t x, std::int64_t y) const {
    auto h = static_cast<std::uint64_t>(x) * 0x9E3779B97F4A7C15ULL;
    h ^= static_cast<std::uint64_t>(y) * 0xC2B2AE3D27D4EB4FULL + (h >> 29);
    h ^= static_cast<std::uint64_t>(layer) * 0x165667B19E3779F9ULL + (h >> 32);
    return static_cast<std::size_t>(h ^ (h >> 31)) & (head_.size() - 1);
  }
  double size_;
  std::vector<std::size_t> head_, next_;
  std::vector<Cell> cell_;
};

// Layers as numbers (pieces of one layer mostly come together: compare with the last).
std::vector<std::uint32_t> layer_numbers(const std::vector<DrawnPiece>& p) {
  std::vector<std::uint32_t> layer(p.size());
  std::unordered_map<std::string, std::uint32_t> ids;
  for (std::size_t i = 0; i < p.size(); ++i) {
    if (i > 0 && p[i].layer == p[i - 1].layer) {
      layer[i] = layer[i - 1];
    } else {
      layer[i] = ids.emplace(p[i].layer, static_cast<std::uint32_t>(ids.size())).first->second;
    }
  }
  return layer;
}

// The ends within `tol` of each end (same layer only, other pieces), in compressed rows: the
// partners of end e are list[first[e] .. first[e + 1]), in end order. At most three are kept:
// one is a join, two or more a branch (reported with them), and a point where thousands of
// ends meet then costs no more than one where three do.
struct Partners {
  std::vector<std::size_t> first;
  std::vector<End> list;
  [[nodiscard]] std::size_t count(End e) const { return first[e + 1] - first[e]; }
};

Partners partners_of(const std::vector<DrawnPiece>& p, const std::vector<std::uint32_t>& layer,
                     double tol) {
  const std::size_t n = 2 * p.size();
  std::vector<End> all(n);
  for (End e = 0; e < n; ++e) all[e] = e;
  const EndGrid grid(p, all, layer, 2 * tol);
  Partners out;
  out.first.reserve(n + 1);
  out.list.reserve(n);
  std::vector<End> mine;
  for (End e = 0; e < n; ++e) {
    out.first.push_back(out.list.size());
    const Vec2& a = end_point(p, e);
    mine.clear();
    grid.near(a, layer[e / 2], [&](End f) {
      if (f / 2 != e / 2 && (end_point(p, f) - a).norm() <= tol) mine.push_back(f);
      return mine.size() < 3;
    });
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
  const std::vector<std::uint32_t> layer = layer_numbers(pieces);
  const Partners partners = partners_of(pieces, layer, join_mm);
  for (End e = 0; e < 2 * pieces.size(); ++e) {
    if (partners.count(e) >= 2) {
      // A piece drawn twice (the same line or arc, either way round, within join_mm: a copy
      // pasted in place) meets its copy at both ends: say so, not "a branch".
      const ContourPiece& p = pieces[e / 2].piece;
      for (std::size_t k = partners.first[e]; k < partners.first[e + 1]; ++k) {
        const ContourPiece& q = pieces[partners.list[k] / 2].piece;
        const bool ends =
            ((p.start - q.start).norm() <= join_mm && (p.end - q.end).norm() <= join_mm) ||
            ((p.start - q.end).norm() <= join_mm && (p.end - q.start).norm() <= join_mm);
        const bool shape = p.is_arc() == q.is_arc() &&
                           (!p.is_arc() || ((*p.centre - *q.centre).norm() <= join_mm &&
                                            (p.point_at(0.5) - q.point_at(0.5)).norm() <= join_mm));
        if (ends && shape) {
          throw InputError(fmt::format(
              "layer '{}': {} and {} are the same {} drawn twice, from {} to {} (a copy in "
              "place: delete one)",
              pieces[e / 2].layer, pieces[e / 2].entity, pieces[partners.list[k] / 2].entity,
              p.is_arc() ? "arc" : "line", at(p.start), at(p.end)));
        }
      }
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
  // A gap: two free ends nearer than ten tolerances were meant to meet (the first pair in the
  // order of the chains' ends: the first end that has one, with its first partner).
  std::vector<End> ends;
  for (const auto& [h, t] : free_ends) ends.insert(ends.end(), {h, t});
  const double near = 10 * join_mm;
  const EndGrid grid(pieces, ends, layer, 2 * near);
  std::vector<std::size_t> order(2 * pieces.size(), 0);  // end -> its place in `ends`
  for (std::size_t k = 0; k < ends.size(); ++k) order[ends[k]] = k;
  std::optional<std::pair<std::size_t, std::size_t>> gap;
  for (std::size_t a = 0; a < ends.size(); ++a) {
    const Vec2& pa = end_point(pieces, ends[a]);
    grid.near(pa, layer[ends[a] / 2], [&](End f) {
      const std::size_t b = order[f];
      if (b > a && (end_point(pieces, f) - pa).norm() <= near && (!gap || b < gap->second)) {
        gap = {a, b};
      }
      return true;
    });
    if (gap) break;
  }
  if (gap) {
    const DrawnPiece &pa = pieces[ends[gap->first] / 2], &pb = pieces[ends[gap->second] / 2];
    const Vec2& va = end_point(pieces, ends[gap->first]);
    const double g = (va - end_point(pieces, ends[gap->second])).norm();
    throw InputError(fmt::format(
        "layer '{}': a gap of {:.6g} mm at {} between {} and {} (ends join within {} mm; "
        "close the gap in the drawing or raise the join tolerance)",
        pa.layer, g, at(va), pa.entity, pb.entity, join_mm));
  }
  return out;
}

}  // namespace trochomill
