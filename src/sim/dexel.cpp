// Dexels, sparse dexel boards and the tri-dexel workpiece (include/trochomill/sim.hpp).
#include "trochomill/sim/dexel.hpp"

#include <fmt/format.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <cstring>

#include "sim/plane.hpp"
#include "trochomill/error.hpp"
#include "trochomill/sim.hpp"

namespace trochomill {

template <std::uint32_t N>
BasicDexel<N>::BasicDexel(const BasicDexel& o) {
  const Interval* b = o.spilled() ? o.block() : nullptr;
  if (b == nullptr) {  // inline, or empty: the bytes are the state
    std::memcpy(static_cast<void*>(in_), o.in_, sizeof in_);
    return;
  }
  const std::uint32_t n = o.spill_count(), cap = capacity(b);
  auto* h = new Interval[cap + 1];
  h[0] = b[0];
  std::copy(b + 1, b + 1 + n, h + 1);
  spill(h, n);
}

template <std::uint32_t N>
BasicDexel<N>& BasicDexel<N>::operator=(const BasicDexel& o) {
  if (this != &o) *this = BasicDexel(o);
  return *this;
}

template <std::uint32_t N>
BasicDexel<N>::BasicDexel(BasicDexel&& o) noexcept {
  std::memcpy(static_cast<void*>(in_), o.in_, sizeof in_);
  o.spill(nullptr, 0);
}

template <std::uint32_t N>
BasicDexel<N>& BasicDexel<N>::operator=(BasicDexel&& o) noexcept {
  if (this == &o) return *this;
  if (spilled()) delete[] block();
  std::memcpy(static_cast<void*>(in_), o.in_, sizeof in_);
  o.spill(nullptr, 0);
  return *this;
}

template <std::uint32_t N>
double BasicDexel<N>::subtract(double a, double b, std::vector<Interval>& removed) {
  if (!(b > a)) return 0.0;
  const bool sp = spilled();
  Interval* const blk = sp ? block() : nullptr;
  const std::uint32_t n = sp ? spill_count() : static_cast<std::uint32_t>(intervals().size());
  if (n == 0) return 0.0;
  Interval* v = sp ? blk + 1 : in_;
  if (b <= v[0].lo || a >= v[n - 1].hi) return 0.0;
  // Intervals [first, last) overlap (a, b); at most the first and the last keep a piece.
  std::uint32_t first = 0;
  while (first < n && v[first].hi <= a) ++first;
  std::uint32_t last = first;
  while (last < n && v[last].lo < b) ++last;
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
  const std::uint32_t n_new = n - (last - first) + static_cast<std::uint32_t>(nk);
  const std::uint32_t cap_now = sp ? capacity(blk) : N;
  if (n_new > cap_now) {  // grow into the heap: only a split of the widest case
    const std::uint32_t cap = std::max<std::uint32_t>(4, 2 * n_new);
    auto* h = new Interval[cap + 1];
    h[0] = {static_cast<double>(cap), 0.0};
    std::copy(v, v + first, h + 1);
    std::copy(keep, keep + nk, h + 1 + first);
    std::copy(v + last, v + n, h + 1 + first + nk);
    delete[] blk;  // v is no longer read (inline, it is overwritten by the tag)
    spill(h, n_new);
    return cut;
  }
  // In place: shift the tail.
  const std::uint32_t to = first + static_cast<std::uint32_t>(nk);
  if (to <= last) {
    std::copy(v + last, v + n, v + to);
  } else {
    std::copy_backward(v + last, v + n, v + n_new);
  }
  std::copy(keep, keep + nk, v + first);
  if (sp && n_new > N) {
    spill(blk, n_new);
  } else if (sp) {  // few enough again: back inline, the block freed (or none when empty)
    if (n_new == 0) {
      spill(nullptr, 0);
    } else {
      std::copy(v, v + n_new, in_);  // v is in the block: in_ does not overlap it
      for (std::uint32_t k = n_new; k < N; ++k) in_[k] = {kUnused, kUnused};
    }
    delete[] blk;
  } else if (n_new == 0) {
    spill(nullptr, 0);
  } else {
    for (std::uint32_t k = n_new; k < N; ++k) in_[k] = {kUnused, kUnused};
  }
  return cut;
}

template <std::uint32_t N>
double BasicDexel<N>::length() const {
  double s = 0;
  for (const Interval& v : intervals()) s += v.hi - v.lo;
  return s;
}

template class BasicDexel<1>;
template class BasicDexel<2>;

DexelBoard::DexelBoard(int axis, const Box3& box, double spacing_mm) : axis_(axis), d_(spacing_mm) {
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
  const std::size_t n_tiles = static_cast<std::size_t>(tu_) * static_cast<std::size_t>(tv_);
  on_tiles(*this, [&](auto& tiles) { tiles.resize(n_tiles); });
  full_ = {box.lo[static_cast<std::size_t>(axis)], box.hi[static_cast<std::size_t>(axis)]};
  fill_.assign(n_tiles, full_);
  fill_n_.assign(n_tiles, 1);
  packed_.assign(n_tiles, 0);
  cut_period_.assign(n_tiles, 0);
  top_.assign(n_tiles, full_.hi);  // untouched: the whole stock
  top_stale_.assign(n_tiles, 0);
}

int DexelBoard::rays_in_tile(std::size_t t) const noexcept {
  const int ti = static_cast<int>(t / static_cast<std::size_t>(tv_));
  const int tj = static_cast<int>(t % static_cast<std::size_t>(tv_));
  return std::min(kTile, nu_ - ti * kTile) * std::min(kTile, nv_ - tj * kTile);
}

void DexelBoard::touch(int i, int j) {
  const std::size_t t = tile_index(i, j);
  on_tiles(*this, [&](auto& tiles) {
    auto& tile = tiles[t];
    if (tile) return;
    using D = typename std::remove_reference_t<decltype(tile)>::element_type;
    tile = std::make_unique<D[]>(kTile * kTile);
    // Every ray what the tile held without its array: the full interval, or the packed one
    // (or none).
    const D fill = fill_n_[t] ? D(fill_[t]) : D();
    for (int q = 0; q < kTile * kTile; ++q) tile[static_cast<std::size_t>(q)] = fill;
    fill_[t] = full_, fill_n_[t] = 1;
    if (packed_[t]) {  // back from packed: its summary still holds
      packed_[t] = 0;
      return;
    }
    if (summarised_ && !paused_) {
      // Every ray of the tile that exists holds the whole stock: all bins.
      auto sm = std::make_unique<Summary>();
      sm->count.fill(static_cast<std::uint16_t>(rays_in_tile(t)));
      sm->mask.fill(~std::uint64_t{0});
      summaries_[t] = std::move(sm);
    }
  });
}

void DexelBoard::enable_summary() {
  if (tiles() > 0) throw Error("DexelBoard::enable_summary: the board was already cut");
  summarised_ = true;
  bins_per_mm_ = kBins / (full_.hi - full_.lo);
  summaries_.resize(static_cast<std::size_t>(tu_) * static_cast<std::size_t>(tv_));
}

void DexelBoard::pause_summary() { paused_ = summarised_; }

void DexelBoard::resume_summary() {
  if (!paused_) return;
  paused_ = false;
  // The tiles' summaries in parallel: each is its tile's alone.
  on_tiles(*this, [&](auto& tiles) {
    tbb::parallel_for(0, tu_ * tv_, [&](int k) {
      const int ti = k / tv_, tj = k % tv_;
      const std::size_t t = tile_index(ti * kTile, tj * kTile);
      if (!tiles[t] && !packed_[t]) return;
      auto sm = std::make_unique<Summary>();
      // Counts `rays` more rays holding material in the bins of `intervals`.
      auto add = [&](std::span<const Interval> intervals, int rays) {
        const auto m = bins_of(intervals);
        for (std::size_t w = 0; w < m.size(); ++w) {
          std::uint64_t bits = m[w];
          sm->mask[w] |= bits;
          while (bits != 0) {
            const int bit = __builtin_ctzll(bits);
            bits &= bits - 1;
            sm->count[w * 64 + static_cast<std::size_t>(bit)] += static_cast<std::uint16_t>(rays);
          }
        }
      };
      if (!tiles[t]) {
        add(fill_span(t), rays_in_tile(t));  // packed: every ray its one interval (or none)
      } else {
        for (int a = 0; a < kTile && ti * kTile + a < nu_; ++a) {
          for (int b = 0; b < kTile && tj * kTile + b < nv_; ++b) {
            add(tiles[t][in_tile(ti * kTile + a, tj * kTile + b)].intervals(), 1);
          }
        }
      }
      summaries_[t] = std::move(sm);
    });
  });
}

std::array<std::uint64_t, DexelBoard::kBins / 64> DexelBoard::bins_of(
    std::span<const Interval> intervals) const {
  std::array<std::uint64_t, kBins / 64> m{};
  for (const Interval& v : intervals) {
    // The bins of its ends and those between (bin_of is monotone: every point's bin).
    const int b0 = bin_of(v.lo), b1 = bin_of(v.hi);
    for (int w = b0 / 64; w <= b1 / 64; ++w) {
      const int lo = w == b0 / 64 ? b0 % 64 : 0, hi = w == b1 / 64 ? b1 % 64 : 63;
      const std::uint64_t upto = hi == 63 ? ~std::uint64_t{0} : (std::uint64_t{1} << (hi + 1)) - 1;
      m[static_cast<std::size_t>(w)] |= upto & ~((std::uint64_t{1} << lo) - 1);
    }
  }
  return m;
}

template <class Tiles>
double DexelBoard::subtract_in(Tiles& tiles, int i, int j, double a, double b,
                               std::vector<Interval>& removed) {
  const std::size_t t = tile_index(i, j);
  if (!tiles[t] && packed_[t]) {
    // A packed tile comes back only for a cut that removes something (the dexel's own test).
    if (!(b > a) || fill_n_[t] == 0 || b <= fill_[t].lo || a >= fill_[t].hi) return 0.0;
  }
  if (!tiles[t]) touch(i, j);
  auto& d = tiles[t][in_tile(i, j)];
  const std::size_t first = removed.size();
  const double cut = d.subtract(a, b, removed);
  if (cut > 0) cut_period_[t] = period_, top_stale_[t] = 1;
  if (!summarised_ || paused_) return cut;
  if (cut > 0) {
    // The ray's bins before the cut are its bins after it and the removed pieces' (an
    // interval's bins are those of its pieces, which meet end to end, and bin_of is
    // monotone): the pieces' bins the ray no longer holds lost it. What the ray keeps lies
    // below a or above b, and bin_of is monotone: of its bins only those of the nearest end
    // below a and the nearest start above b can be a piece's (every piece lies in [a, b]).
    int keep_lo = -1, keep_hi = kBins;  // bins at or below keep_lo and at or above keep_hi kept
    for (const Interval& v : d.intervals()) {
      if (v.hi <= a) {
        keep_lo = bin_of(v.hi);
      } else {
        keep_hi = bin_of(v.lo);
        break;
      }
    }
    Summary& sm = *summaries_[t];
    int last = -1;  // the pieces are sorted: a bin two of them share is counted once
    for (std::size_t q = first; q < removed.size(); ++q) {
      const int b0 = std::max({bin_of(removed[q].lo), keep_lo + 1, last + 1});
      const int b1 = std::min(bin_of(removed[q].hi), keep_hi - 1);
      for (int bin = b0; bin <= b1; ++bin) {
        if (--sm.count[static_cast<std::size_t>(bin)] == 0) {
          sm.mask[static_cast<std::size_t>(bin / 64)] &= ~(std::uint64_t{1} << (bin % 64));
        }
      }
      last = std::max(last, b1);
    }
  }
  return cut;
}

double DexelBoard::subtract(int i, int j, double a, double b, std::vector<Interval>& removed) {
  return on_tiles(*this, [&](auto& tiles) { return subtract_in(tiles, i, j, a, b, removed); });
}

bool DexelBoard::may_hold(int i0, int i1, int j0, int j1, double lo, double hi) const {
  if (!summarised_ || paused_) return true;
  if (!(hi > full_.lo && lo < full_.hi)) return false;
  const int b0 = bin_of(lo), b1 = bin_of(hi);
  for (int ti = std::max(0, i0) / kTile; ti <= std::min(nu_ - 1, i1) / kTile; ++ti) {
    for (int tj = std::max(0, j0) / kTile; tj <= std::min(nv_ - 1, j1) / kTile; ++tj) {
      const std::size_t t = tile_index(ti * kTile, tj * kTile);
      if (!touched(ti * kTile, tj * kTile)) return true;  // untouched: the whole stock
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

void DexelBoard::tighten_top(int i, int j) {
  const std::size_t t = tile_index(i, j);
  if (!top_stale_[t]) return;
  top_stale_[t] = 0;
  on_tiles(*this, [&](const auto& tiles) {
    const auto& tile = tiles[t];
    if (!tile) {  // packed (a cut made the tile stale, so it was touched): its one interval
      top_[t] = fill_n_[t] ? fill_[t].hi : -std::numeric_limits<double>::infinity();
      return;
    }
    // Every ray's last interval's end (the rays that exist: those past the board's edge hold
    // the full interval).
    const int ti = static_cast<int>(t / static_cast<std::size_t>(tv_));
    const int tj = static_cast<int>(t % static_cast<std::size_t>(tv_));
    double top = -std::numeric_limits<double>::infinity();
    for (int a = 0; a < kTile && ti * kTile + a < nu_; ++a) {
      for (int b = 0; b < kTile && tj * kTile + b < nv_; ++b) {
        const auto iv = tile[in_tile(ti * kTile + a, tj * kTile + b)].intervals();
        if (!iv.empty()) top = std::max(top, iv.back().hi);
      }
    }
    top_[t] = top;
  });
}

std::size_t DexelBoard::pack_settled() {
  std::size_t freed = 0;
  on_tiles(*this, [&](auto& tiles) {
    for (std::size_t t = 0; t < tiles.size(); ++t) {
      auto& tile = tiles[t];
      if (!tile || cut_period_[t] + 1 != period_) continue;
      // Uniform: every ray that exists holds the same one interval, or none, inline.
      const int ti = static_cast<int>(t / static_cast<std::size_t>(tv_));
      const int tj = static_cast<int>(t % static_cast<std::size_t>(tv_));
      std::span<const Interval> first;
      bool same = true, have = false;
      for (int a = 0; same && a < kTile && ti * kTile + a < nu_; ++a) {
        for (int b = 0; same && b < kTile && tj * kTile + b < nv_; ++b) {
          const auto& d = tile[in_tile(ti * kTile + a, tj * kTile + b)];
          const auto iv = d.intervals();
          if (iv.size() > 1 || d.heap_bytes() > 0) {
            same = false;
          } else if (!have) {
            first = iv, have = true;
          } else {
            same = iv.size() == first.size() &&
                   (iv.empty() || (iv[0].lo == first[0].lo && iv[0].hi == first[0].hi));
          }
        }
      }
      if (!same || !have) continue;
      fill_n_[t] = static_cast<std::uint8_t>(first.size());
      fill_[t] = first.empty() ? full_ : first[0];
      packed_[t] = 1;
      freed += sizeof(tile[0]) * kTile * kTile;
      tile.reset();
    }
  });
  ++period_;
  return freed;
}

std::size_t DexelBoard::packed_tiles() const noexcept {
  return static_cast<std::size_t>(std::count(packed_.begin(), packed_.end(), std::uint8_t{1}));
}

std::size_t DexelBoard::tiles() const noexcept {
  return on_tiles(*this, [](const auto& tiles) {
    return static_cast<std::size_t>(
        std::count_if(tiles.begin(), tiles.end(), [](const auto& t) { return t != nullptr; }));
  });
}

double DexelBoard::volume_mm3() const {
  // Untouched rays: the full interval; touched tiles: their rays (tiles past the board's
  // edge hold rays that do not exist: skipped).
  double touched_rays = 0, len = 0;
  on_tiles(*this, [&](const auto& tiles) {
    for (int ti = 0; ti < tu_; ++ti) {
      for (int tj = 0; tj < tv_; ++tj) {
        const std::size_t t = tile_index(ti * kTile, tj * kTile);
        const auto& tile = tiles[t];
        if (!tile && packed_[t]) {
          touched_rays += rays_in_tile(t);
          if (fill_n_[t]) len += rays_in_tile(t) * (fill_[t].hi - fill_[t].lo);
          continue;
        }
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
  });
  const double all = static_cast<double>(nu_) * static_cast<double>(nv_);
  return ((all - touched_rays) * (full_.hi - full_.lo) + len) * d_ * d_;
}

std::size_t DexelBoard::memory_bytes() const {
  const std::size_t table = static_cast<std::size_t>(tu_) * static_cast<std::size_t>(tv_);
  std::size_t b = table * (sizeof(tiles1_[0]) + (summarised_ ? sizeof(summaries_[0]) : 0) +
                           sizeof(fill_[0]) + sizeof(fill_n_[0]) + sizeof(packed_[0]) +
                           sizeof(cut_period_[0]) + sizeof(top_[0]) + sizeof(top_stale_[0]));
  for (const auto& sm : summaries_) b += sm ? sizeof(Summary) : 0;
  on_tiles(*this, [&](const auto& tiles) {
    for (const auto& tile : tiles) {
      if (!tile) continue;
      b += sizeof(tile[0]) * kTile * kTile;
      for (int q = 0; q < kTile * kTile; ++q) b += tile[static_cast<std::size_t>(q)].heap_bytes();
    }
  });
  return b;
}

std::size_t DexelBoard::ray_bytes(int axis) noexcept {
  return axis == 2 ? sizeof(BasicDexel<1>) : sizeof(BasicDexel<2>);
}

TriDexel::TriDexel(const Box3& b, double spacing_mm)
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

namespace trochomill {

Box3 mesh_box(const Mesh& mesh) {
  const Box3 b = mesh_bounds(mesh);
  for (std::size_t k = 0; k < 3; ++k) {
    if (!(b.hi[k] > b.lo[k])) {
      throw InputError(fmt::format("the stock mesh is flat along {} (no volume)", "xyz"[k]));
    }
  }
  return b;
}

TriDexel stock_from_mesh(const Mesh& mesh, double spacing_mm, const RunHooks& hooks) {
  TriDexel work(mesh_box(mesh), spacing_mm);
  std::vector<Interval> scratch;
  for (int axis = 0; axis < 3; ++axis) {
    DexelBoard& board = work.boards[static_cast<std::size_t>(axis)];
    const auto a = static_cast<std::size_t>(axis), ua = static_cast<std::size_t>((axis + 1) % 3),
               va = static_cast<std::size_t>((axis + 2) % 3);
    const Interval full = board.full();
    board.pause_summary();
    // The triangles with their extent in the board's plane (sorted by u).
    struct Tri {
      const Vec3* p[3];
      double u_lo, u_hi, v_lo, v_hi;
    };
    std::vector<Tri> tris;
    tris.reserve(mesh.triangles.size());
    for (const auto& t : mesh.triangles) {
      Tri tr{};
      for (int k = 0; k < 3; ++k) tr.p[k] = &mesh.vertices[t[static_cast<std::size_t>(k)]];
      tr.u_lo = std::min({(*tr.p[0])[ua], (*tr.p[1])[ua], (*tr.p[2])[ua]});
      tr.u_hi = std::max({(*tr.p[0])[ua], (*tr.p[1])[ua], (*tr.p[2])[ua]});
      tr.v_lo = std::min({(*tr.p[0])[va], (*tr.p[1])[va], (*tr.p[2])[va]});
      tr.v_hi = std::max({(*tr.p[0])[va], (*tr.p[1])[va], (*tr.p[2])[va]});
      tris.push_back(tr);
    }
    std::sort(tris.begin(), tris.end(), [](const Tri& x, const Tri& y) { return x.u_lo < y.u_lo; });
    const int nu = board.count_u(), nv = board.count_v();
    constexpr int kStrip = DexelBoard::kTile;
    std::vector<std::vector<double>> hits(static_cast<std::size_t>(kStrip * nv));
    std::size_t first = 0;  // the first triangle that may reach the strip (sorted by u_lo)
    for (int i0 = 0; i0 < nu; i0 += kStrip) {
      hooks.check("the stock mesh's dexels interrupted");
      hooks.step(static_cast<std::size_t>(axis * nu + i0), static_cast<std::size_t>(3 * nu));
      const int i1 = std::min(nu, i0 + kStrip);
      const double strip_lo = board.u_of(i0), strip_hi = board.u_of(i1 - 1);
      for (auto& h : hits) h.clear();
      for (std::size_t q = first; q < tris.size() && tris[q].u_lo <= strip_hi; ++q) {
        const Tri& t = tris[q];
        if (t.u_hi < strip_lo) continue;
        const auto [ti0, ti1] = board.index_range(true, t.u_lo, t.u_hi);
        const int ri0 = std::max(ti0, i0), ri1 = std::min(ti1, i1 - 1);
        const auto [rj0, rj1] = board.index_range(false, t.v_lo, t.v_hi);
        for (int i = ri0; i <= ri1; ++i) {
          for (int j = rj0; j <= rj1; ++j) {
            if (const auto w =
                    line_crossing(*t.p[0], *t.p[1], *t.p[2], axis, board.u_of(i), board.v_of(j))) {
              hits[static_cast<std::size_t>((i - i0) * nv + j)].push_back(*w);
            }
          }
        }
      }
      while (first < tris.size() && tris[first].u_hi < strip_hi) ++first;
      for (int i = i0; i < i1; ++i) {
        for (int j = 0; j < nv; ++j) {
          auto& h = hits[static_cast<std::size_t>((i - i0) * nv + j)];
          if (h.size() % 2 != 0) {
            throw InputError(fmt::format(
                "the stock mesh is not closed: the ray along {} at {} = {:.6g} mm, {} = {:.6g} "
                "mm crosses its surface {} times (an even number for a closed solid)",
                "xyz"[a], "xyz"[ua], board.u_of(i), "xyz"[va], board.v_of(j), h.size()));
          }
          std::sort(h.begin(), h.end());
          // The material is between crossings 1-2, 3-4, ...: cut the rest from the full ray.
          double from = full.lo;
          for (std::size_t k = 0; k < h.size(); k += 2) {
            const double lo = std::clamp(h[k], full.lo, full.hi);
            const double hi = std::clamp(h[k + 1], full.lo, full.hi);
            if (!(hi > lo)) continue;
            if (lo > from) (void)board.subtract(i, j, from, lo, scratch);
            from = hi;
            scratch.clear();
          }
          board.touch(i, j);  // held even when the mesh fills it whole
          if (full.hi > from) (void)board.subtract(i, j, from, full.hi, scratch);
          scratch.clear();
        }
      }
    }
    board.resume_summary();
  }
  return work;
}

}  // namespace trochomill
