// Dexels, sparse dexel boards and the tri-dexel workpiece (include/trochomill/sim.hpp).
#include <fmt/format.h>

#include <algorithm>
#include <cmath>

#include "trochomill/error.hpp"
#include "trochomill/sim.hpp"

namespace trochomill {

Dexel::Dexel(const Dexel& o) : in_{o.in_[0], o.in_[1]}, n_(o.n_), cap_(o.cap_) {
  if (o.heap_) {
    heap_ = std::make_unique<Interval[]>(cap_);
    std::copy(o.heap_.get(), o.heap_.get() + n_, heap_.get());
  }
}

Dexel& Dexel::operator=(const Dexel& o) {
  if (this != &o) *this = Dexel(o);
  return *this;
}

double Dexel::subtract(double a, double b, std::vector<Interval>& removed) {
  if (!(b > a) || n_ == 0) return 0.0;
  Interval* v = heap_ ? heap_.get() : in_;
  if (b <= v[0].lo || a >= v[n_ - 1].hi) return 0.0;
  // Intervals [first, last) overlap (a, b); at most the first and the last keep a piece.
  std::uint32_t first = 0;
  while (first < n_ && v[first].hi <= a) ++first;
  std::uint32_t last = first;
  while (last < n_ && v[last].lo < b) ++last;
  if (first == last) return 0.0;
  double cut = 0;
  for (std::uint32_t k = first; k < last; ++k) {
    const double lo = std::max(v[k].lo, a), hi = std::min(v[k].hi, b);
    removed.push_back({lo, hi});
    cut += hi - lo;
  }
  Interval keep[2];
  int nk = 0;
  if (v[first].lo < a) keep[nk++] = {v[first].lo, a};
  if (v[last - 1].hi > b) keep[nk++] = {b, v[last - 1].hi};
  const std::uint32_t n_new = n_ - (last - first) + static_cast<std::uint32_t>(nk);
  const std::uint32_t cap_now = heap_ ? cap_ : 2;
  if (n_new > cap_now) {  // grow into the heap: only a split of the widest case
    const std::uint32_t cap = std::max<std::uint32_t>(4, 2 * n_new);
    auto h = std::make_unique<Interval[]>(cap);
    std::copy(v, v + first, h.get());
    std::copy(keep, keep + nk, h.get() + first);
    std::copy(v + last, v + n_, h.get() + first + nk);
    heap_ = std::move(h);
    cap_ = cap;
  } else {  // in place: shift the tail
    const std::uint32_t to = first + static_cast<std::uint32_t>(nk);
    if (to <= last) {
      std::copy(v + last, v + n_, v + to);
    } else {
      std::copy_backward(v + last, v + n_, v + n_new);
    }
    std::copy(keep, keep + nk, v + first);
  }
  n_ = n_new;
  return cut;
}

double Dexel::length() const {
  double s = 0;
  for (const Interval& v : intervals()) s += v.hi - v.lo;
  return s;
}

DexelBoard::DexelBoard(int axis, const StockBox& box, double spacing_mm)
    : axis_(axis), d_(spacing_mm) {
  if (!(spacing_mm > 0)) {
    throw InputError(fmt::format("dexel spacing must be > 0 mm, got {}", spacing_mm));
  }
  const int u = (axis + 1) % 3, v = (axis + 2) % 3;
  u0_ = box.lo[static_cast<std::size_t>(u)];
  v0_ = box.lo[static_cast<std::size_t>(v)];
  const double nu = std::ceil((box.hi[static_cast<std::size_t>(u)] - u0_) / d_ - 1e-9);
  const double nv = std::ceil((box.hi[static_cast<std::size_t>(v)] - v0_) / d_ - 1e-9);
  if (!(nu >= 1 && nv >= 1) || nu * nv > 1e12) {
    throw InputError(fmt::format("stock {} x {} mm at {} mm spacing is not a usable board",
                                 box.hi[static_cast<std::size_t>(u)] - u0_,
                                 box.hi[static_cast<std::size_t>(v)] - v0_, d_));
  }
  nu_ = static_cast<int>(nu);
  nv_ = static_cast<int>(nv);
  tu_ = (nu_ + kTile - 1) / kTile;
  tv_ = (nv_ + kTile - 1) / kTile;
  tiles_.resize(static_cast<std::size_t>(tu_) * static_cast<std::size_t>(tv_));
  full_ = {box.lo[static_cast<std::size_t>(axis)], box.hi[static_cast<std::size_t>(axis)]};
}

Dexel& DexelBoard::ray(int i, int j) {
  auto& tile = tiles_[tile_index(i, j)];
  if (!tile) {
    tile = std::make_unique<Dexel[]>(kTile * kTile);
    for (int q = 0; q < kTile * kTile; ++q) tile[static_cast<std::size_t>(q)] = Dexel(full_);
    ++touched_;
  }
  return tile[in_tile(i, j)];
}

const Dexel* DexelBoard::find(int i, int j) const {
  const auto& tile = tiles_[tile_index(i, j)];
  if (!tile) return nullptr;
  return &tile[in_tile(i, j)];
}

double DexelBoard::volume_mm3() const {
  // Untouched rays: the full interval; touched tiles: their rays (tiles past the board's
  // edge hold rays that do not exist: skipped).
  double touched_rays = 0, len = 0;
  for (int ti = 0; ti < tu_; ++ti) {
    for (int tj = 0; tj < tv_; ++tj) {
      const auto& tile = tiles_[tile_index(ti * kTile, tj * kTile)];
      if (!tile) continue;
      for (int a = 0; a < kTile; ++a) {
        for (int b = 0; b < kTile; ++b) {
          const int i = ti * kTile + a, j = tj * kTile + b;
          if (i >= nu_ || j >= nv_) continue;
          touched_rays += 1;
          len += tile[in_tile(i, j)].length();
        }
      }
    }
  }
  const double all = static_cast<double>(nu_) * static_cast<double>(nv_);
  return ((all - touched_rays) * (full_.hi - full_.lo) + len) * d_ * d_;
}

std::size_t DexelBoard::memory_bytes() const {
  std::size_t b = tiles_.size() * sizeof(tiles_[0]);
  for (const auto& tile : tiles_) {
    if (!tile) continue;
    b += sizeof(Dexel) * kTile * kTile;
    for (int q = 0; q < kTile * kTile; ++q) b += tile[static_cast<std::size_t>(q)].heap_bytes();
  }
  return b;
}

TriDexel::TriDexel(const StockBox& b, double spacing_mm)
    : box(b),
      boards{DexelBoard(0, b, spacing_mm), DexelBoard(1, b, spacing_mm),
             DexelBoard(2, b, spacing_mm)} {
  for (int k = 0; k < 3; ++k) {
    if (!(b.hi[static_cast<std::size_t>(k)] > b.lo[static_cast<std::size_t>(k)])) {
      throw InputError("stock box: every upper corner coordinate must exceed the lower one");
    }
  }
}

}  // namespace trochomill
