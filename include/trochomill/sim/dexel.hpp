// The tri-dexel workpiece's storage (Bergmann 2021 Section 3; docs/models.md section 11):
// dexels with inline intervals, sparse boards of tiles with their summaries, the three boards
// over a stock, and a stock from a closed mesh. The simulation's internals, public for its
// tests and benchmarks; users hold a TriDexel through sim.hpp without this header. mm.
#pragma once

#include <algorithm>
#include <array>
#include <atomic>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>
#include <memory>
#include <span>
#include <utility>
#include <vector>

#include "trochomill/cutter.hpp"
#include "trochomill/geometry.hpp"
#include "trochomill/progress.hpp"

namespace trochomill {

/// A dexel: sorted, disjoint material intervals along one ray, in 16 N bytes. Up to N
/// intervals are stored inline (the common cases: one on a ray through the floor, two on a
/// ray across the slot with a wall on each side); more go to a heap block, and back inline
/// (the block freed) when a cut leaves N or fewer, so that what the teeth split and join again
/// costs no memory after (a whole slot's boards held 426 MiB of such blocks). The first inline
/// interval's `lo` tells which: a material end is never a NaN, so a NaN with kSpillTag's bits
/// there means "spilled" (its low 32 bits the count, the next 8 bytes the block's address); an
/// unused inline slot past the first holds a NaN `lo`. An empty dexel is a spilled one with
/// no block.
template <std::uint32_t N>
class BasicDexel {
  static_assert(N >= 1);

 public:
  BasicDexel() noexcept { spill(nullptr, 0); }
  explicit BasicDexel(Interval full) noexcept {
    in_[0] = full;
    for (std::uint32_t k = 1; k < N; ++k) in_[k] = {kUnused, kUnused};
  }
  BasicDexel(const BasicDexel& o);
  BasicDexel& operator=(const BasicDexel& o);
  BasicDexel(BasicDexel&& o) noexcept;
  BasicDexel& operator=(BasicDexel&& o) noexcept;
  ~BasicDexel() {
    if (spilled()) delete[] block();
  }
  [[nodiscard]] std::span<const Interval> intervals() const noexcept {
    if (spilled()) {  // an empty dexel has no block (no pointer arithmetic on null)
      const Interval* b = block();
      return b ? std::span<const Interval>{b + 1, spill_count()} : std::span<const Interval>{};
    }
    std::uint32_t k = 1;
    while (k < N && !std::isnan(in_[k].lo)) ++k;
    return {in_, k};
  }
  /// Removes [a, b] and appends the removed pieces to `removed` (in order). Returns the
  /// removed length (mm).
  double subtract(double a, double b, std::vector<Interval>& removed);
  [[nodiscard]] double length() const;
  /// Heap bytes held (0 while the intervals are inline).
  [[nodiscard]] std::size_t heap_bytes() const noexcept {
    const Interval* b = spilled() ? block() : nullptr;
    return b ? (capacity(b) + 1) * sizeof(Interval) : 0;
  }

 private:
  // A quiet NaN's bits with the top of the payload set: the spilled state's tag.
  static constexpr std::uint64_t kSpillTag = 0x7FFC'0000'0000'0000ULL;
  static constexpr std::uint64_t kTagMask = 0xFFFF'FFFF'0000'0000ULL;
  static constexpr double kUnused = std::numeric_limits<double>::quiet_NaN();
  [[nodiscard]] std::uint64_t word0() const noexcept {
    std::uint64_t w;
    std::memcpy(&w, &in_[0].lo, sizeof w);
    return w;
  }
  [[nodiscard]] bool spilled() const noexcept { return (word0() & kTagMask) == kSpillTag; }
  [[nodiscard]] std::uint32_t spill_count() const noexcept {
    return static_cast<std::uint32_t>(word0());
  }
  // The heap block: its first element holds the capacity (in lo), the intervals follow.
  [[nodiscard]] Interval* block() const noexcept {
    Interval* b;
    std::memcpy(&b, &in_[0].hi, sizeof b);
    return b;
  }
  [[nodiscard]] static std::uint32_t capacity(const Interval* b) noexcept {
    return static_cast<std::uint32_t>(b[0].lo);
  }
  void spill(Interval* b, std::uint32_t n) noexcept {
    const std::uint64_t w = kSpillTag | n;
    std::memcpy(&in_[0].lo, &w, sizeof w);
    std::memcpy(&in_[0].hi, &b, sizeof b);
  }
  Interval in_[N];
};

/// The dexel of the X and Y boards (two inline intervals).
using Dexel = BasicDexel<2>;

/// One board: rays along `axis` (0 x, 1 y, 2 z) on a square grid of spacing `d` over the
/// two other axes (u = axis + 1, v = axis + 2, cyclically), ray (i, j) at u = u0 + (i + 1/2) d,
/// v = v0 + (j + 1/2) d. Sparse: rays live in tiles of 64 x 64 created on first touch;
/// untouched rays hold the whole stock interval implicitly. A ray holds one interval inline on
/// the Z board (a ray through the floor: 16 bytes) and two on the X and Y boards (a ray
/// across the slot: 32 bytes); more go to the heap.
class DexelBoard {
 public:
  DexelBoard(int axis, const Box3& box, double spacing_mm);
  [[nodiscard]] int axis() const noexcept { return axis_; }
  [[nodiscard]] double spacing() const noexcept { return d_; }
  [[nodiscard]] int count_u() const noexcept { return nu_; }
  [[nodiscard]] int count_v() const noexcept { return nv_; }
  [[nodiscard]] double u_of(int i) const noexcept { return u0_ + (i + 0.5) * d_; }
  [[nodiscard]] double v_of(int j) const noexcept { return v0_ + (j + 0.5) * d_; }
  /// The grid's origin along u and v (mm): u_of(i) = u0 + (i + 1/2) d.
  [[nodiscard]] double u0() const noexcept { return u0_; }
  [[nodiscard]] double v0() const noexcept { return v0_; }
  /// The indices of the rays along u (`along_u`) or v whose coordinate lies in [lo, hi] (mm),
  /// clipped to the board (empty when first > second).
  [[nodiscard]] std::pair<int, int> index_range(bool along_u, double lo, double hi) const {
    const double o = along_u ? u0_ : v0_;
    const int count = along_u ? nu_ : nv_;
    const int i0 = std::max(0, static_cast<int>(std::ceil((lo - o) / d_ - 0.5)));
    const int i1 = std::min(count - 1, static_cast<int>(std::floor((hi - o) / d_ - 0.5)));
    return {i0, i1};
  }
  /// Creates the tile of ray (i, j) (kTile x kTile rays, each the full stock interval) if
  /// untouched. Threads may create tiles at once only different ones and with the summary
  /// paused.
  void touch(int i, int j);
  /// Whether ray (i, j) was ever touched (untouched, it holds the full interval; a packed
  /// tile's rays count as touched).
  [[nodiscard]] bool touched(int i, int j) const noexcept {
    const std::size_t t = tile_index(i, j);
    return (axis_ == 2 ? tiles1_[t] != nullptr : tiles2_[t] != nullptr) || packed_[t] != 0;
  }
  /// The material of ray (i, j): its intervals (mm along the axis), the full interval when
  /// untouched, the tile's one interval (or none) when packed. Valid until the ray is next
  /// cut or its tile packed.
  [[nodiscard, gnu::always_inline]] std::span<const Interval> intervals(int i,
                                                                        int j) const noexcept {
    const std::size_t t = tile_index(i, j);
    if (axis_ == 2) return tiles1_[t] ? tiles1_[t][in_tile(i, j)].intervals() : fill_span(t);
    return tiles2_[t] ? tiles2_[t][in_tile(i, j)].intervals() : fill_span(t);
  }
  /// Packs the tiles cut before the last call and not since whose rays all hold the same one
  /// interval (or nothing), none on the heap: their arrays are freed and their rays read that
  /// interval, until a cut that removes material from one of them brings the array back.
  /// Nothing a ray holds changes, so a simulation's numbers are the same with or without it;
  /// the machined region behind the tool (the floor under a slot, the emptied rays across it)
  /// then costs a few bytes per tile. Returns the bytes freed. Not with other threads cutting
  /// the board.
  std::size_t pack_settled();
  /// Tiles packed now (their rays held as one interval or none).
  [[nodiscard]] std::size_t packed_tiles() const noexcept;
  /// The X or Y board's rays (i, j), (i + 1, j), ... (X board) or (i, j), (i, j + 1), ... (Y
  /// board) as they lie in memory, to the edge of their tile (kTile - i % kTile or
  /// kTile - j % kTile of them): null when the tile is untouched. For the simulation's row
  /// check, which reads their inline words a row of rays at a time.
  [[nodiscard]] const Dexel* row_rays(int i, int j) const noexcept {
    const std::size_t t = tile_index(i, j);
    return axis_ != 2 && tiles2_[t] ? &tiles2_[t][in_tile(i, j)] : nullptr;
  }
  [[nodiscard]] Interval full() const noexcept { return full_; }
  /// Material volume represented by the board (mm^3): sum of lengths times d^2.
  [[nodiscard]] double volume_mm3() const;
  /// Tiles that were ever touched.
  [[nodiscard]] std::size_t tiles() const noexcept;
  [[nodiscard]] std::size_t memory_bytes() const;
  /// The bytes of one held ray on the board along `axis` (without its heap).
  [[nodiscard]] static std::size_t ray_bytes(int axis) noexcept;
  /// Rays per tile side.
  static constexpr int kTile = 64;
  /// Bins along the ray axis of a tile's material summary.
  static constexpr int kBins = 256;

  /// Keeps, per tile, which bins along the rays hold material (counts of rays per bin), so
  /// that whole stretches of a tile can be found empty without touching its rays. Set before
  /// the first cut.
  void enable_summary();
  /// Pauses the summary's upkeep for a burst of cuts (the envelope sweep); resuming rebuilds it
  /// from the rays (cheaper than keeping it through many cuts).
  void pause_summary();
  void resume_summary();
  /// Removes [a, b] from ray (i, j) (as BasicDexel::subtract), keeping the summary.
  double subtract(int i, int j, double a, double b, std::vector<Interval>& removed);
  /// False only when no ray (i, j), i in [i0, i1], j in [j0, j1], holds material in [lo, hi]
  /// (by the summary: exact to a bin); always true without one.
  [[nodiscard]] bool may_hold(int i0, int i1, int j0, int j1, double lo, double hi) const;
  /// False only when no ray of ray (i, j)'s tile holds material above `lo` (mm along the
  /// rays). Every board keeps, per tile, a bound on the highest end of its rays' material: a
  /// cut leaves it a bound (cuts only remove material), and `tighten_top` makes it exact again.
  /// (The Z board's search: behind the tool the floor's tiles hold nothing above the tip.)
  [[nodiscard]] bool may_hold_above(int i, int j, double lo) const noexcept {
    return top_[tile_index(i, j)] > lo;
  }
  /// Makes the bound of ray (i, j)'s tile exact, reading its rays, if a cut removed material
  /// from the tile since the bound was last made exact (else it is exact already). Not with
  /// other threads cutting the tile.
  void tighten_top(int i, int j);

 private:
  struct Summary {
    std::array<std::uint16_t, kBins> count{};      // rays with material in each bin
    std::array<std::uint64_t, kBins / 64> mask{};  // bins with a non-zero count
  };
  [[nodiscard]] std::array<std::uint64_t, kBins / 64> bins_of(
      std::span<const Interval> intervals) const;
  // What a tile without an array holds on each ray: the full interval (untouched) or its
  // packed interval (none when fill_n_ is 0).
  [[nodiscard]] std::span<const Interval> fill_span(std::size_t t) const noexcept {
    return {&fill_[t], fill_n_[t]};
  }
  // The rays of tile t that exist (tiles at the board's far edges hold fewer).
  [[nodiscard]] int rays_in_tile(std::size_t t) const noexcept;
  // Runs f on the board's tile table (tiles1_ on the Z board, tiles2_ on the others).
  template <class Self, class F>
  static decltype(auto) on_tiles(Self& self, F&& f) {
    return self.axis_ == 2 ? f(self.tiles1_) : f(self.tiles2_);
  }
  template <class Tiles>
  double subtract_in(Tiles& tiles, int i, int j, double a, double b,
                     std::vector<Interval>& removed);
  // The bin holding x (mm along the rays), clamped to the board: a multiply and a
  // truncation, monotone in x, so the bins from an interval's ends hold every bin a point of
  // it falls in (the summary stays conservative; an end on a bin's edge may mark that bin).
  [[nodiscard]] int bin_of(double x) const noexcept {
    return static_cast<int>(
        std::clamp((x - full_.lo) * bins_per_mm_, 0.0, static_cast<double>(kBins - 1)));
  }
  // A ray's place in its tile: the board's inner loops run along u on the X board (rows of a
  // layer) and along v on the others, and those neighbours are kept adjacent in memory.
  [[nodiscard]] std::size_t in_tile(int i, int j) const noexcept {
    const int a = i % kTile, b = j % kTile;
    return static_cast<std::size_t>(axis_ == 0 ? b * kTile + a : a * kTile + b);
  }
  [[nodiscard]] std::size_t tile_index(int i, int j) const noexcept {
    return static_cast<std::size_t>(i / kTile) * static_cast<std::size_t>(tv_) +
           static_cast<std::size_t>(j / kTile);
  }
  int axis_;
  double d_, u0_, v0_;
  int nu_, nv_, tu_ = 0, tv_ = 0;
  Interval full_;
  // Dense tables of tile pointers (null: untouched), tu_ x tv_: the Z board's in tiles1_, the
  // others' in tiles2_ (the other table empty).
  std::vector<std::unique_ptr<BasicDexel<1>[]>> tiles1_;
  std::vector<std::unique_ptr<BasicDexel<2>[]>> tiles2_;
  // Per tile: what its rays hold without an array (fill_span), whether it is packed, and the
  // period it last lost material in (periods end at each pack_settled).
  std::vector<Interval> fill_;
  std::vector<std::uint8_t> fill_n_, packed_;
  std::vector<std::uint32_t> cut_period_;
  // Per tile: a bound on its rays' material's highest end (mm; -inf: none), and whether a cut
  // removed material since it was last made exact (may_hold_above, tighten_top).
  std::vector<double> top_;
  std::vector<std::uint8_t> top_stale_;
  std::uint32_t period_ = 1;
  bool summarised_ = false, paused_ = false;
  double bins_per_mm_ = 1;                           // kBins over the stock's extent along the rays
  std::vector<std::unique_ptr<Summary>> summaries_;  // parallel to the tile table
};

/// The three boards over one stock.
struct TriDexel {
  TriDexel(const Box3& box, double spacing_mm);
  Box3 box;
  std::array<DexelBoard, 3> boards;
};

/// The box of a mesh's vertices (mm). Throws InputError for a mesh without triangles or with
/// a coordinate that is not finite.
[[nodiscard]] Box3 mesh_box(const Mesh& mesh);
/// A stock given as a closed triangle mesh (mm, in the simulation's frame): three boards over
/// its box, every ray cut to the mesh's inside (even-odd: the stretches between the 1st and
/// 2nd crossings of its surface, the 3rd and 4th, ...). A ray through an edge or a vertex
/// crosses it once: each point of the boards' plane belongs to one of the triangles that meet
/// there (the rasteriser's top-left rule, on edge functions that are exact negatives of each
/// other across an edge). Every ray is held (no untouched tiles; estimate_simulation_memory
/// counts them). Throws InputError when a ray crosses the surface an odd number of times (an
/// open mesh), naming the ray; `hooks.cancel` stops it with Interrupted.
[[nodiscard]] TriDexel stock_from_mesh(const Mesh& mesh, double spacing_mm,
                                       const RunHooks& hooks = {});

}  // namespace trochomill
