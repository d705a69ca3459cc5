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
  const std::size_t t = tile_index(i, j);
  auto& tile = tiles_[t];
  if (!tile) {
    tile = std::make_unique<Dexel[]>(kTile * kTile);
    for (int q = 0; q < kTile * kTile; ++q) tile[static_cast<std::size_t>(q)] = Dexel(full_);
    if (summarised_ && !paused_) {
      // Every ray of the tile that exists holds the whole stock: all bins.
      auto sm = std::make_unique<Summary>();
      const int ti = i / kTile, tj = j / kTile;
      const int rays = std::min(kTile, nu_ - ti * kTile) * std::min(kTile, nv_ - tj * kTile);
      sm->count.fill(static_cast<std::uint16_t>(rays));
      sm->mask.fill(~std::uint64_t{0});
      summaries_[t] = std::move(sm);
    }
  }
  return tile[in_tile(i, j)];
}

void DexelBoard::enable_summary() {
  if (tiles() > 0) throw Error("DexelBoard::enable_summary: the board was already cut");
  summarised_ = true;
  bin_w_ = (full_.hi - full_.lo) / kBins;
  summaries_.resize(tiles_.size());
}

void DexelBoard::pause_summary() { paused_ = summarised_; }

void DexelBoard::resume_summary() {
  if (!paused_) return;
  paused_ = false;
  for (int ti = 0; ti < tu_; ++ti) {
    for (int tj = 0; tj < tv_; ++tj) {
      const std::size_t t = tile_index(ti * kTile, tj * kTile);
      if (!tiles_[t]) continue;
      auto sm = std::make_unique<Summary>();
      for (int a = 0; a < kTile && ti * kTile + a < nu_; ++a) {
        for (int b = 0; b < kTile && tj * kTile + b < nv_; ++b) {
          const auto m = bins_of(tiles_[t][in_tile(ti * kTile + a, tj * kTile + b)]);
          for (std::size_t w = 0; w < m.size(); ++w) {
            std::uint64_t bits = m[w];
            sm->mask[w] |= bits;
            while (bits != 0) {
              const int bit = __builtin_ctzll(bits);
              bits &= bits - 1;
              ++sm->count[w * 64 + static_cast<std::size_t>(bit)];
            }
          }
        }
      }
      summaries_[t] = std::move(sm);
    }
  }
}

int DexelBoard::bin_of(double x) const noexcept {
  const double b = std::floor((x - full_.lo) / bin_w_);
  return static_cast<int>(std::clamp(b, 0.0, static_cast<double>(kBins - 1)));
}

std::array<std::uint64_t, DexelBoard::kBins / 64> DexelBoard::bins_of(const Dexel& d) const {
  std::array<std::uint64_t, kBins / 64> m{};
  for (const Interval& v : d.intervals()) {
    // Bins the interval overlaps (a bin touched only at its edge holds none of it).
    const int b0 = bin_of(v.lo);
    int b1 = bin_of(v.hi);
    if (b1 > b0 && full_.lo + b1 * bin_w_ >= v.hi) --b1;
    for (int w = b0 / 64; w <= b1 / 64; ++w) {
      const int lo = w == b0 / 64 ? b0 % 64 : 0, hi = w == b1 / 64 ? b1 % 64 : 63;
      const std::uint64_t upto = hi == 63 ? ~std::uint64_t{0} : (std::uint64_t{1} << (hi + 1)) - 1;
      m[static_cast<std::size_t>(w)] |= upto & ~((std::uint64_t{1} << lo) - 1);
    }
  }
  return m;
}

double DexelBoard::subtract(int i, int j, double a, double b, std::vector<Interval>& removed) {
  Dexel& d = ray(i, j);
  if (!summarised_ || paused_) return d.subtract(a, b, removed);
  const auto before = bins_of(d);
  const double cut = d.subtract(a, b, removed);
  if (cut > 0) {
    const auto after = bins_of(d);
    Summary& sm = *summaries_[tile_index(i, j)];
    for (std::size_t w = 0; w < before.size(); ++w) {
      std::uint64_t gone = before[w] & ~after[w];
      while (gone != 0) {
        const int bit = __builtin_ctzll(gone);
        gone &= gone - 1;
        const std::size_t bin = w * 64 + static_cast<std::size_t>(bit);
        if (--sm.count[bin] == 0) sm.mask[w] &= ~(std::uint64_t{1} << bit);
      }
    }
  }
  return cut;
}

bool DexelBoard::may_hold(int i0, int i1, int j0, int j1, double lo, double hi) const {
  if (!summarised_ || paused_) return true;
  if (!(hi > full_.lo && lo < full_.hi)) return false;
  const int b0 = bin_of(lo), b1 = bin_of(hi);
  for (int ti = std::max(0, i0) / kTile; ti <= std::min(nu_ - 1, i1) / kTile; ++ti) {
    for (int tj = std::max(0, j0) / kTile; tj <= std::min(nv_ - 1, j1) / kTile; ++tj) {
      const std::size_t t = tile_index(ti * kTile, tj * kTile);
      if (!tiles_[t]) return true;  // untouched: the whole stock
      const Summary& sm = *summaries_[t];
      for (int b = b0; b <= b1;) {
        const auto w = static_cast<std::size_t>(b / 64);
        if (b % 64 == 0 && b + 63 <= b1) {  // a whole word
          if (sm.mask[w] != 0) return true;
          b += 64;
          continue;
        }
        if ((sm.mask[w] >> (b % 64)) & 1) return true;
        ++b;
      }
    }
  }
  return false;
}

std::size_t DexelBoard::tiles() const noexcept {
  return static_cast<std::size_t>(
      std::count_if(tiles_.begin(), tiles_.end(), [](const auto& t) { return t != nullptr; }));
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
  std::size_t b = tiles_.size() * (sizeof(tiles_[0]) + (summarised_ ? sizeof(summaries_[0]) : 0));
  for (const auto& sm : summaries_) b += sm ? sizeof(Summary) : 0;
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
  // The X and Y boards are searched row by row across layers: their summaries let empty
  // stretches be skipped without touching rays.
  boards[0].enable_summary();
  boards[1].enable_summary();
}

}  // namespace trochomill
