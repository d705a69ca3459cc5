// Chaining a drawing's pieces into contours (geometry/drawing.hpp).
#include <fmt/format.h>

#include <cmath>
#include <cstdint>
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

// The ends within `tol` of each end, from a grid of cells `tol` wide (same layer only).
std::vector<std::vector<End>> partners_of(const std::vector<DrawnPiece>& p, double tol) {
  const auto key = [tol](const Vec2& v, long dx, long dy) {
    const auto ix = static_cast<std::int64_t>(std::floor(v.x() / tol)) + dx;
    const auto iy = static_cast<std::int64_t>(std::floor(v.y() / tol)) + dy;
    return static_cast<std::uint64_t>(ix) * 0x9E3779B97F4A7C15ULL ^ static_cast<std::uint64_t>(iy);
  };
  std::unordered_multimap<std::uint64_t, End> grid;
  grid.reserve(2 * p.size());
  for (End e = 0; e < 2 * p.size(); ++e) grid.emplace(key(end_point(p, e), 0, 0), e);
  std::vector<std::vector<End>> out(2 * p.size());
  for (End e = 0; e < 2 * p.size(); ++e) {
    const Vec2& a = end_point(p, e);
    for (long dx = -1; dx <= 1; ++dx) {
      for (long dy = -1; dy <= 1; ++dy) {
        const auto [lo, hi] = grid.equal_range(key(a, dx, dy));
        for (auto it = lo; it != hi; ++it) {
          const End f = it->second;
          if (f / 2 == e / 2 || p[f / 2].layer != p[e / 2].layer) continue;
          if ((end_point(p, f) - a).norm() <= tol) out[e].push_back(f);
        }
      }
    }
    std::sort(out[e].begin(), out[e].end());
    out[e].erase(std::unique(out[e].begin(), out[e].end()), out[e].end());
  }
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
  const std::vector<std::vector<End>> partners = partners_of(pieces, join_mm);
  for (End e = 0; e < partners.size(); ++e) {
    if (partners[e].size() >= 2) {
      std::string names = pieces[e / 2].entity;
      for (const End f : partners[e]) names += ", " + pieces[f / 2].entity;
      throw InputError(fmt::format(
          "layer '{}': a branch at {}: the ends of {} meet there (a contour may not fork)",
          pieces[e / 2].layer, at(end_point(pieces, e)), names));
    }
  }
  const auto partner = [&](End e) -> std::optional<End> {
    if (partners[e].empty()) return std::nullopt;
    return partners[e].front();
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
