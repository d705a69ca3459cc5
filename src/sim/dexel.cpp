// Dexels, sparse dexel boards and the tri-dexel workpiece (include/trochomill/sim.hpp).
#include <fmt/format.h>

#include <algorithm>
#include <cmath>

#include "trochomill/error.hpp"
#include "trochomill/sim.hpp"

namespace trochomill {

double Dexel::subtract(double a, double b, std::vector<Interval>& removed) {
  if (!(b > a) || iv_.empty() || b <= iv_.front().lo || a >= iv_.back().hi) return 0.0;
  double cut = 0;
  std::vector<Interval> out;
  out.reserve(iv_.size() + 1);
  for (const Interval& v : iv_) {
    if (v.hi <= a || v.lo >= b) {  // untouched
      out.push_back(v);
      continue;
    }
    const double lo = std::max(v.lo, a), hi = std::min(v.hi, b);
    removed.push_back({lo, hi});
    cut += hi - lo;
    if (v.lo < lo) out.push_back({v.lo, lo});
    if (hi < v.hi) out.push_back({hi, v.hi});
  }
  iv_.swap(out);
  return cut;
}

double Dexel::length() const {
  double s = 0;
  for (const Interval& v : iv_) s += v.hi - v.lo;
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
  if (!(nu >= 1 && nv >= 1) || nu * nv > 4e12) {
    throw InputError(fmt::format("stock {} x {} mm at {} mm spacing is not a usable board",
                                 box.hi[static_cast<std::size_t>(u)] - u0_,
                                 box.hi[static_cast<std::size_t>(v)] - v0_, d_));
  }
  nu_ = static_cast<int>(nu);
  nv_ = static_cast<int>(nv);
  full_ = {box.lo[static_cast<std::size_t>(axis)], box.hi[static_cast<std::size_t>(axis)]};
}

Dexel& DexelBoard::ray(int i, int j) {
  const auto key =
      (static_cast<std::uint64_t>(i / kTile) << 32) | static_cast<std::uint32_t>(j / kTile);
  auto& tile = tiles_[key];
  if (!tile) tile = std::make_unique<std::vector<Dexel>>(kTile * kTile, Dexel(full_));
  return (*tile)[static_cast<std::size_t>((i % kTile) * kTile + (j % kTile))];
}

const Dexel* DexelBoard::find(int i, int j) const {
  const auto key =
      (static_cast<std::uint64_t>(i / kTile) << 32) | static_cast<std::uint32_t>(j / kTile);
  const auto it = tiles_.find(key);
  if (it == tiles_.end()) return nullptr;
  return &(*it->second)[static_cast<std::size_t>((i % kTile) * kTile + (j % kTile))];
}

double DexelBoard::volume_mm3() const {
  // Untouched rays: the full interval; touched tiles: their rays (tiles past the board's
  // edge hold rays that do not exist: skipped).
  double touched_rays = 0, len = 0;
  for (const auto& [key, tile] : tiles_) {
    const int ti = static_cast<int>(key >> 32), tj = static_cast<int>(key & 0xffffffffu);
    for (int a = 0; a < kTile; ++a) {
      for (int b = 0; b < kTile; ++b) {
        const int i = ti * kTile + a, j = tj * kTile + b;
        if (i >= nu_ || j >= nv_) continue;
        touched_rays += 1;
        len += (*tile)[static_cast<std::size_t>(a * kTile + b)].length();
      }
    }
  }
  const double all = static_cast<double>(nu_) * static_cast<double>(nv_);
  return ((all - touched_rays) * (full_.hi - full_.lo) + len) * d_ * d_;
}

std::size_t DexelBoard::memory_bytes() const {
  std::size_t b = 0;
  for (const auto& [key, tile] : tiles_) {
    b += sizeof(Dexel) * tile->size() + 64;
    for (const Dexel& x : *tile) b += x.intervals().capacity() * sizeof(Interval);
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
