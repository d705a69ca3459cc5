// The simulation's workpiece storage: dexel arithmetic against a reference under random cuts,
// the boards' material summaries and packed tiles, stocks from meshes, and the vectorised row
// checks against the scalar code on every target.
#include <gtest/gtest.h>
#include <hwy/targets.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>
#include <random>
#include <string>
#include <utility>
#include <vector>

#include "sim/plane.hpp"
#include "sim/rows.hpp"
#include "test_util.hpp"
#include "trochomill/error.hpp"
#include "trochomill/sim.hpp"
#include "trochomill/sim/dexel.hpp"
#include "trochomill/units.hpp"

namespace trochomill {
namespace {

TEST(Sim, DexelSubtract) {
  Dexel d({0, 10});
  std::vector<Interval> removed;
  EXPECT_DOUBLE_EQ(d.subtract(2, 3, removed), 1.0);
  ASSERT_EQ(d.intervals().size(), 2u);
  EXPECT_EQ(d.intervals()[0].hi, 2);
  EXPECT_EQ(d.intervals()[1].lo, 3);
  EXPECT_DOUBLE_EQ(d.subtract(-1, 1, removed), 1.0);
  EXPECT_DOUBLE_EQ(d.subtract(2.5, 4, removed), 1.0);  // half in the gap
  EXPECT_DOUBLE_EQ(d.subtract(20, 30, removed), 0.0);
  EXPECT_DOUBLE_EQ(d.length(), 7.0);
  ASSERT_EQ(removed.size(), 3u);
  EXPECT_EQ(removed[2].lo, 3);
  EXPECT_EQ(removed[2].hi, 4);
  EXPECT_DOUBLE_EQ(d.subtract(0, 100, removed), 7.0);
  EXPECT_TRUE(d.intervals().empty());
  // A default dexel is empty (a spilled state with no block): no intervals, no length, and
  // nothing removed from it (clang's UBSan once caught an offset applied to its null block).
  const Dexel empty;
  EXPECT_TRUE(empty.intervals().empty());
  EXPECT_EQ(empty.length(), 0.0);
  EXPECT_EQ(Dexel().subtract(0, 1, removed), 0.0);
}

// A dexel split beyond its inline intervals moves to the heap, and back inline (its block
// freed) once cuts leave few enough: the intervals are the same either way.
TEST(Sim, DexelComesBackInlineWhenCutsJoinItAgain) {
  std::vector<Interval> removed;
  Dexel d({0, 10});
  (void)d.subtract(2, 3, removed);
  EXPECT_EQ(d.heap_bytes(), 0U);  // two intervals: inline
  (void)d.subtract(5, 6, removed);
  ASSERT_EQ(d.intervals().size(), 3U);
  EXPECT_GT(d.heap_bytes(), 0U);        // three: spilled
  (void)d.subtract(1.5, 5.5, removed);  // [0, 1.5] and [6, 10] left
  ASSERT_EQ(d.intervals().size(), 2U);
  EXPECT_EQ(d.heap_bytes(), 0U);
  EXPECT_EQ(d.intervals()[0].lo, 0);
  EXPECT_EQ(d.intervals()[0].hi, 1.5);
  EXPECT_EQ(d.intervals()[1].lo, 6);
  EXPECT_EQ(d.intervals()[1].hi, 10);
  // Inline again, it splits and spills again, and a spilled one emptied holds no block.
  (void)d.subtract(7, 8, removed);
  EXPECT_GT(d.heap_bytes(), 0U);
  (void)d.subtract(-1, 11, removed);
  EXPECT_TRUE(d.intervals().empty());
  EXPECT_EQ(d.heap_bytes(), 0U);
  // The Z board's dexel (one inline interval) likewise.
  BasicDexel<1> z({0, 10});
  (void)z.subtract(4, 5, removed);
  EXPECT_GT(z.heap_bytes(), 0U);
  (void)z.subtract(3, 10, removed);
  ASSERT_EQ(z.intervals().size(), 1U);
  EXPECT_EQ(z.heap_bytes(), 0U);
  EXPECT_EQ(z.intervals()[0].hi, 3);
}

// Random subtractions against a plain reference (intervals rebuilt in a fresh vector each
// time): the in-place, inline-first dexel holds exactly the same intervals (the arithmetic is
// the same min/max on the same doubles: exact equality) and reports the same removed pieces,
// with one inline interval (the Z board's) and two (the X and Y boards'), through copies and
// moves between inline and heap storage.
template <std::uint32_t N>
void dexel_matches_a_reference() {
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> pos(-1, 11), len(0, 3);
  std::size_t on_heap = 0;
  for (int trial = 0; trial < 200; ++trial) {
    BasicDexel<N> d({0, 10});
    std::vector<Interval> ref{{0, 10}};
    auto same = [&](const BasicDexel<N>& x) {
      const auto iv = x.intervals();
      return std::ranges::equal(iv, ref, [](const Interval& p, const Interval& q) {
        return p.lo == q.lo && p.hi == q.hi;
      });
    };
    for (int op = 0; op < 12; ++op) {
      const double a = pos(rng), b = a + len(rng);
      std::vector<Interval> got, want, next;
      const double cut = d.subtract(a, b, got);
      double want_cut = 0;
      for (const Interval& v : ref) {
        if (v.hi <= a || v.lo >= b) {
          next.push_back(v);
          continue;
        }
        const double lo = std::max(v.lo, a), hi = std::min(v.hi, b);
        want.push_back({lo, hi});
        want_cut += hi - lo;
        if (v.lo < lo) next.push_back({v.lo, lo});
        if (hi < v.hi) next.push_back({hi, v.hi});
      }
      ref = next;
      EXPECT_DOUBLE_EQ(cut, want_cut);
      ASSERT_EQ(got.size(), want.size());
      for (std::size_t k = 0; k < got.size(); ++k) {
        EXPECT_EQ(got[k].lo, want[k].lo);
        EXPECT_EQ(got[k].hi, want[k].hi);
      }
      ASSERT_TRUE(same(d)) << N << " " << trial << " " << op;
      on_heap += d.heap_bytes() > 0 ? 1 : 0;
      const BasicDexel<N> copy = d;  // copies keep the intervals
      ASSERT_TRUE(same(copy));
      BasicDexel<N> moved(std::move(d));  // so do moves, and assignments of either
      ASSERT_TRUE(same(moved));
      BasicDexel<N> other({-5, -4});
      other = copy;
      ASSERT_TRUE(same(other));
      d = std::move(moved);
      ASSERT_TRUE(same(d));
    }
  }
  EXPECT_GT(on_heap, 100u) << N;  // the heap's storage was exercised
}

TEST(Sim, DexelMatchesAReferenceUnderRandomCuts) {
  dexel_matches_a_reference<1>();
  dexel_matches_a_reference<2>();
  static_assert(sizeof(BasicDexel<1>) == 16 && sizeof(BasicDexel<2>) == 32);
}

// The boards' material summaries: after random cuts, whenever a query says a stretch of rays
// holds no material in a range, none of them does (checked ray by ray); and a range that
// covers a ray's remaining material is always reported.
TEST(Sim, BoardSummaryNeverHidesMaterial) {
  const Box3 box{{0, 0, 0}, {10, 7, 3}};
  DexelBoard board(0, box, 0.05);  // rays along x, 140 x 60 of them
  board.enable_summary();
  std::mt19937 rng(3);
  std::uniform_int_distribution<int> ri(0, board.count_u() - 1), rj(0, board.count_v() - 1);
  std::uniform_real_distribution<double> x(-0.5, 10.5), len(0, 4);
  std::vector<Interval> removed;
  for (int k = 0; k < 20000; ++k) {
    const double a = x(rng);
    (void)board.subtract(ri(rng), rj(rng), a, a + len(rng), removed);
  }
  // Cuts ending on the bins' edges (the stock's 10 mm in 256 bins) or a few ulps either side:
  // where a bin rule that is not monotone in x, or an edge rule unlike the query's, would
  // hide material (queries below end there too).
  std::uniform_int_distribution<int> edge(0, DexelBoard::kBins), ulps(-3, 3);
  auto near_edge = [&] {
    double v = 10.0 * edge(rng) / DexelBoard::kBins;
    const int n = ulps(rng);
    for (int q = 0; q < std::abs(n); ++q) v = std::nextafter(v, n > 0 ? 11.0 : -1.0);
    return v;
  };
  for (int k = 0; k < 20000; ++k) {
    const double a = near_edge(), b = near_edge();
    (void)board.subtract(ri(rng), rj(rng), std::min(a, b), std::max(a, b), removed);
  }
  // Half the cuts with the upkeep paused, then rebuilt: the same guarantee.
  board.pause_summary();
  for (int k = 0; k < 10000; ++k) {
    const double a = x(rng);
    (void)board.subtract(ri(rng), rj(rng), a, a + len(rng), removed);
  }
  board.resume_summary();
  int empty = 0;
  for (int q = 0; q < 8000; ++q) {
    const int i0 = ri(rng), j0 = rj(rng);
    const int i1 = std::min(board.count_u() - 1, i0 + 5),
              j1 = std::min(board.count_v() - 1, j0 + 2);
    double lo = x(rng), hi = lo + 0.3 * len(rng);
    if (q % 2 == 1) {  // a stretch between two bins' edges (give or take ulps)
      lo = near_edge(), hi = near_edge();
      if (lo > hi) std::swap(lo, hi);
    }
    bool any = false;
    for (int i = i0; i <= i1; ++i) {
      for (int j = j0; j <= j1; ++j) {
        // Untouched rays: the whole stock, [0, 10].
        for (const Interval& v : board.intervals(i, j)) any = any || (v.hi > lo && v.lo < hi);
      }
    }
    const bool may = board.may_hold(i0, i1, j0, j1, lo, hi);
    if (any) {
      EXPECT_TRUE(may) << i0 << " " << j0 << " " << lo << " " << hi;
    }
    if (!may) ++empty;
  }
  EXPECT_GT(empty, 100);  // the summary does find empty stretches
}

// The summary kept cut by cut is the one made from the rays (its counts exact, not only
// conservative): a board of one tile with four rays (so that bins do empty), cut at random
// by short cuts (ends on the bins' edges give or take ulps, cuts across the gaps between a
// ray's intervals taking several pieces at once) and long ones, is asked bin by bin after
// every cut, beside a twin whose summary is rebuilt from its rays each time.
TEST(Sim, BoardSummaryKeptCutByCutIsTheRebuiltOne) {
  const Box3 box{{0, 0, 0}, {10, 0.2, 0.05}};
  DexelBoard board(0, box, 0.05), twin(0, box, 0.05);  // rays along x: 4 (y) by 1 (z)
  ASSERT_EQ(board.count_u() * board.count_v(), 4);
  board.enable_summary(), twin.enable_summary();
  std::mt19937 rng(11);
  std::uniform_int_distribution<int> ray(0, 3), edge(0, DexelBoard::kBins), ulps(-2, 2), kind(0, 9);
  std::uniform_real_distribution<double> x(-0.5, 10.5), len(0, 0.3), wide(0, 4);
  auto near_edge = [&] {
    double v = 10.0 * edge(rng) / DexelBoard::kBins;
    const int n = ulps(rng);
    for (int q = 0; q < std::abs(n); ++q) v = std::nextafter(v, n > 0 ? 11.0 : -1.0);
    return v;
  };
  std::vector<Interval> removed;
  int differ = 0, empty_bins = 0, several = 0;
  for (int k = 0; k < 3000; ++k) {
    const int i = ray(rng);
    double a = x(rng), b = a + (kind(rng) == 0 ? wide(rng) : len(rng));
    if (kind(rng) < 5) a = near_edge(), b = a + 10.0 * len(rng) / DexelBoard::kBins;
    removed.clear();
    (void)board.subtract(i, 0, a, b, removed);
    several += removed.size() > 1;
    (void)twin.subtract(i, 0, a, b, removed);
    twin.pause_summary(), twin.resume_summary();  // rebuilt from the rays
    for (int q = 0; q < DexelBoard::kBins; ++q) {
      const double c = 10.0 * (q + 0.5) / DexelBoard::kBins;
      const bool m = board.may_hold(0, 3, 0, 0, c - 1e-9, c + 1e-9);
      differ += m != twin.may_hold(0, 3, 0, 0, c - 1e-9, c + 1e-9);
      empty_bins += !m;
    }
  }
  EXPECT_EQ(differ, 0);
  EXPECT_GT(empty_bins, 100000);  // the bins did empty (the test asks real questions)
  EXPECT_GT(several, 50);         // cuts taking several pieces at once were made
}

// The boards' tiles' bounds on their material's highest end (may_hold_above, tighten_top), on
// the Z board (140 x 75 rays: tiles of 64, 64 and 12 rays by 64 and 11, so edge tiles hold
// rays past the board's edge that do not exist):
// - every ray cut to a height of its own below the stock's top, one ray a tile split in two
//   with its upper interval the tile's highest end (so that a ray's first interval is not
//   its top): once made exact, each tile's bound is that end, no more and no less;
// - tiles cut flat to a floor or emptied, then packed, their bound made exact from the packed
//   interval (or none); a cut that brings one back, its bound still a bound and exact again;
// - random cuts after all that: a tile with a ray holding material above a height is never
//   passed by.
TEST(Sim, TileTopsBoundTheMaterial) {
  const Box3 box{{0, 0, 0}, {7, 3.75, 3}};
  DexelBoard board(2, box, 0.05);
  ASSERT_EQ(board.count_u(), 140);
  ASSERT_EQ(board.count_v(), 75);
  constexpr int T = DexelBoard::kTile;
  std::mt19937 rng(5);
  std::vector<Interval> removed;
  // The highest end in ray (i, j)'s tile, ray by ray (the rays that exist).
  auto top = [&](int i, int j) {
    double t = -std::numeric_limits<double>::infinity();
    const int ti = i / T, tj = j / T;
    for (int a = ti * T; a < std::min(board.count_u(), (ti + 1) * T); ++a) {
      for (int b = tj * T; b < std::min(board.count_v(), (tj + 1) * T); ++b) {
        const auto iv = board.intervals(a, b);
        if (!iv.empty()) t = std::max(t, iv.back().hi);
      }
    }
    return t;
  };
  // The bound is exact once made exact: nothing above the highest end, something just below.
  auto exact = [&](int i, int j) {
    const double t = top(i, j);
    board.tighten_top(i, j);
    EXPECT_FALSE(board.may_hold_above(i, j, t)) << i << " " << j << " " << t;
    if (std::isfinite(t)) {
      EXPECT_TRUE(board.may_hold_above(i, j, std::nextafter(t, -1.0))) << i << " " << j << " " << t;
    } else {
      EXPECT_FALSE(board.may_hold_above(i, j, -1e300)) << i << " " << j;
    }
  };
  // 1. Every ray to its own height in [0.5, 2.5], but one ray a tile (somewhere among the
  //    rays that exist) split: [0, 0.4] and [0.45, top], top in [2.6, 2.95].
  std::uniform_real_distribution<double> own(0.5, 2.5), high(2.6, 2.95);
  auto split_ray = [&](int ti, int tj) {
    return std::pair{ti * T + std::min(5 + ti, board.count_u() - ti * T - 1),
                     tj * T + std::min(3 + tj, board.count_v() - tj * T - 1)};
  };
  for (int i = 0; i < board.count_u(); ++i) {
    for (int j = 0; j < board.count_v(); ++j) {
      if (split_ray(i / T, j / T) == std::pair{i, j}) {
        (void)board.subtract(i, j, 0.4, 0.45, removed);
        (void)board.subtract(i, j, high(rng), 3.5, removed);
        ASSERT_EQ(board.intervals(i, j).size(), 2U);
      } else {
        (void)board.subtract(i, j, own(rng), 3.5, removed);
      }
    }
  }
  for (int ti = 0; ti < 3; ++ti) {
    for (int tj = 0; tj < 2; ++tj) {
      const auto [i, j] = split_ray(ti, tj);
      EXPECT_TRUE(board.may_hold_above(i, j, 2.0));  // a bound still (the stock's top)
      exact(i, j);
      EXPECT_EQ(top(i, j), board.intervals(i, j).back().hi);  // that ray sets the tile's top
      EXPECT_LT(top(i, j), 2.96);  // not the stock's top: no ray past the board's edge read
    }
  }
  // 2. Tile (1, 0) cut flat to 0.3 mm, tile (2, 1) (an edge tile) emptied; packed (a tile is
  //    packed at the second call after its last cut), their bounds left stale until then.
  for (int i = T; i < 2 * T; ++i) {
    for (int j = 0; j < T; ++j) (void)board.subtract(i, j, 0.3, 3.5, removed);
  }
  for (int i = 2 * T; i < board.count_u(); ++i) {
    for (int j = T; j < board.count_v(); ++j) (void)board.subtract(i, j, -1.0, 3.5, removed);
  }
  const std::size_t packed0 = board.packed_tiles();
  (void)board.pack_settled();
  (void)board.pack_settled();
  EXPECT_EQ(board.packed_tiles(), packed0 + 2);
  EXPECT_TRUE(board.may_hold_above(T + 3, 7, 2.0));  // stale: a bound, not yet exact
  exact(T + 3, 7);                                   // from the packed interval: 0.3 mm
  EXPECT_FALSE(board.may_hold_above(T + 3, 7, 0.3));
  exact(2 * T + 1, T + 1);  // nothing at all
  // A cut that removes something brings the flat tile back: its bound still a bound, then
  // exact again.
  (void)board.subtract(T + 10, 20, 0.1, 2.0, removed);
  EXPECT_EQ(board.packed_tiles(), packed0 + 1);
  EXPECT_TRUE(board.may_hold_above(T + 10, 20, std::nextafter(0.3, 0.0)));
  exact(T + 10, 20);
  // 3. Random cuts: a tile with material above a height is never passed by.
  std::uniform_int_distribution<int> ri(0, board.count_u() - 1), rj(0, board.count_v() - 1);
  std::uniform_real_distribution<double> z(-0.2, 3.2), len(0, 1.5);
  int passed = 0;
  for (int round = 0; round < 4; ++round) {
    for (int k = 0; k < 3000; ++k) {
      const double a = z(rng);
      (void)board.subtract(ri(rng), rj(rng), a, a + len(rng), removed);
    }
    if (round % 2 == 1) (void)board.pack_settled();
    for (int q = 0; q < 400; ++q) {
      const int i = ri(rng), j = rj(rng);
      const double lo = z(rng), t = top(i, j);
      if (t > lo) {
        ASSERT_TRUE(board.may_hold_above(i, j, lo)) << i << " " << j << " " << lo;
      }
      if (q % 4 == 0) {
        exact(i, j);
        passed += !board.may_hold_above(i, j, lo);
      }
    }
  }
  EXPECT_GT(passed, 20);  // tiles were passed by
}

// Packed tiles (DexelBoard::pack_settled) hold what their rays held. Two boards take the same
// cuts; one packs after each period, the other never. Tiles cut to one level all over (a
// floor), emptied (rays across a slot) or left uneven, on the board's inner and edge tiles
// (140 x 75 rays: tiles of 64, 64 and 12 rays by 64 and 11): every ray the same bit for bit, the
// same touched rays, the summary's answers the same (kept through packing, rebuilt from the
// packed interval after a pause); a cut that removes nothing leaves a tile packed, one that
// removes something brings it back; the arrays' bytes are what packing reports freed.
TEST(Sim, PackedTilesHoldWhatTheirRaysHeld) {
  for (const int axis : {2, 0}) {
    // 140 x 75 rays on either board (u along x and v along y on the Z board; y and z on X).
    const Box3 box = axis == 2 ? Box3{{0, 0, 0}, {7, 3.75, 3}} : Box3{{0, 0, 0}, {3, 7, 3.75}};
    DexelBoard packed(axis, box, 0.05), plain(axis, box, 0.05);
    if (axis == 0) packed.enable_summary(), plain.enable_summary();
    ASSERT_EQ(packed.count_u(), 140);
    ASSERT_EQ(packed.count_v(), 75);
    const Interval full = packed.full();
    std::vector<Interval> removed;
    auto cut = [&](int i, int j, double a, double b) {
      removed.clear();
      const double r1 = packed.subtract(i, j, a, b, removed);
      removed.clear();
      const double r2 = plain.subtract(i, j, a, b, removed);
      ASSERT_EQ(r1, r2) << i << " " << j;
    };
    auto same = [&] {
      for (int i = 0; i < packed.count_u(); ++i) {
        for (int j = 0; j < packed.count_v(); ++j) {
          ASSERT_EQ(packed.touched(i, j), plain.touched(i, j)) << i << " " << j;
          ASSERT_TRUE(std::ranges::equal(
              packed.intervals(i, j), plain.intervals(i, j),
              [](const Interval& p, const Interval& q) { return p.lo == q.lo && p.hi == q.hi; }))
              << axis << " " << i << " " << j;
        }
      }
      // Volumes summed in another order (a packed tile's rays as one product): to 1e-12
      // relative, far below a ray's d^2 times a spacing.
      EXPECT_NEAR(packed.volume_mm3(), plain.volume_mm3(), 1e-12 * plain.volume_mm3());
    };
    const double mid = 0.5 * (full.lo + full.hi);
    std::mt19937 rng(11);
    std::uniform_real_distribution<double> x(full.lo, full.hi);
    for (int i = 0; i < packed.count_u(); ++i) {
      for (int j = 0; j < packed.count_v(); ++j) {
        if (i < 64) {
          cut(i, j, mid, full.hi + 1);  // a floor at mid: uniform tiles
        } else if (i < 128 && j < 64) {
          cut(i, j, full.lo - 1, full.hi + 1);  // emptied
        } else if (i >= 128) {
          cut(i, j, mid, full.hi + 1);  // the edge tiles (12 rays across), a floor
          if (i == 130 && j == 70) cut(i, j, mid - 0.1, mid);  // one ray lower, same start
        } else {
          const double a = x(rng);
          cut(i, j, a, a + 0.5);  // uneven
        }
      }
    }
    const std::size_t bytes = packed.memory_bytes();
    EXPECT_EQ(packed.pack_settled(), 0U);  // cut in this period: nothing settled yet
    const std::size_t freed = packed.pack_settled();
    EXPECT_EQ(packed.memory_bytes(), bytes - freed);
    // Packed: the floor's two tiles, the emptied one and the edge's (2, 0) (its tile (2, 1)
    // holds the ray apart); not the uneven tile (1, 1).
    EXPECT_EQ(packed.packed_tiles(), 4U);
    EXPECT_EQ(freed, 4 * packed.ray_bytes(axis) * DexelBoard::kTile * DexelBoard::kTile);
    same();
    // The summary's answers (X board) over random stretches: the same on both boards.
    auto same_summary = [&] {
      if (axis != 0) return;
      std::uniform_int_distribution<int> ri(0, packed.count_u() - 1), rj(0, packed.count_v() - 1);
      int empty = 0;
      for (int q = 0; q < 4000; ++q) {
        const int i0 = ri(rng), j0 = rj(rng);
        const double lo = x(rng), hi = lo + 0.2;
        const bool m = packed.may_hold(i0, i0 + 3, j0, j0 + 3, lo, hi);
        ASSERT_EQ(m, plain.may_hold(i0, i0 + 3, j0, j0 + 3, lo, hi)) << i0 << " " << j0;
        empty += m ? 0 : 1;
      }
      EXPECT_GT(empty, 100);
    };
    same_summary();
    packed.pause_summary(), plain.pause_summary();
    packed.resume_summary(), plain.resume_summary();
    same_summary();
    // Cuts that remove nothing keep the tiles packed; one that removes brings its tile back.
    cut(10, 10, mid + 0.1, full.hi);  // above the floor
    cut(70, 10, full.lo, full.hi);    // an emptied ray
    EXPECT_EQ(packed.packed_tiles(), 4U);
    cut(10, 10, mid - 0.2, mid - 0.1);
    EXPECT_EQ(packed.packed_tiles(), 3U);
    same();
    same_summary();
  }
}

// A box given as a mesh is the box: every ray of the three boards holds the same interval as
// the box stock's (bit for bit: faces square to the rays are met at their exact height, and a
// diagonal through a ray centre is taken by one of its two triangles, not both or neither).
TEST(Sim, AMeshStockOfABoxIsTheBox) {
  const Box3 box{{-1.0, 0.0, -0.5}, {1.0, 2.0, 0.5}};
  const double d = 0.05;
  const TriDexel from_mesh = stock_from_mesh(test::box_mesh(box.lo, box.hi), d);
  const TriDexel plain(box, d);
  for (std::size_t b = 0; b < 3; ++b) {
    const DexelBoard& m = from_mesh.boards[b];
    const DexelBoard& p = plain.boards[b];
    ASSERT_EQ(m.count_u(), p.count_u());
    ASSERT_EQ(m.count_v(), p.count_v());
    EXPECT_EQ(m.volume_mm3(), p.volume_mm3()) << b;
    for (int i = 0; i < m.count_u(); ++i) {
      for (int j = 0; j < m.count_v(); ++j) {
        ASSERT_TRUE(m.touched(i, j));  // every ray is held
        const auto r = m.intervals(i, j);
        ASSERT_EQ(r.size(), 1u) << b << " " << i << " " << j;
        EXPECT_EQ(r[0].lo, p.full().lo);
        EXPECT_EQ(r[0].hi, p.full().hi);
      }
    }
  }
}

// Two closed solids in one mesh: an octahedron |x| + |y| + |z| <= 1 (volume 4/3) and, apart
// from it, a box with a box-shaped hole through it (its inner walls face inward): every board's
// volume is the solids' (the midpoint rule over the rays: the octahedron's section lengths
// are piecewise linear across the rays, its error under 2e-4 of the volume at 0.01 mm,
// measured 1.8e-5 on each board), and rays through the hole are empty. A mesh with one triangle
// missing is refused, naming a ray.
TEST(Sim, AMeshStockHoldsWhatTheMeshEncloses) {
  Mesh m;
  const std::array<std::array<double, 3>, 6> v = {
      {{1, 0, 0}, {-1, 0, 0}, {0, 1, 0}, {0, -1, 0}, {0, 0, 1}, {0, 0, -1}}};
  for (const auto& p : v) m.vertices.emplace_back(p[0], p[1], p[2]);
  for (const std::uint32_t x : {0u, 1u}) {
    for (const std::uint32_t y : {2u, 3u}) {
      for (const std::uint32_t z : {4u, 5u}) m.triangles.push_back({x, y, z});
    }
  }
  auto add = [&m](const Mesh& o, bool inward) {
    const auto base = static_cast<std::uint32_t>(m.vertices.size());
    for (const auto& p : o.vertices) m.vertices.push_back(p);
    for (auto t : o.triangles) {
      if (inward) std::swap(t[1], t[2]);
      m.triangles.push_back({t[0] + base, t[1] + base, t[2] + base});
    }
  };
  add(test::box_mesh({2.0, -1.0, -1.0}, {4.0, 1.0, 1.0}), false);
  add(test::box_mesh({2.5, -0.5, -1.0}, {3.5, 0.5, 1.0}), true);  // the hole, through along z
  // Measured as a Z-board hole along z: its faces at z = -1, 1 coincide with the outer box's
  // (the rays there cross four faces at two heights: in, in, out, out: no material).
  const double volume = 4.0 / 3.0 + 2 * 2 * 2 - 1 * 1 * 2;
  const TriDexel w = stock_from_mesh(m, 0.01);
  for (std::size_t b = 0; b < 3; ++b) {
    EXPECT_NEAR(w.boards[b].volume_mm3(), volume, 2e-4 * volume) << b;
  }
  const DexelBoard& z = w.boards[2];
  const auto [i0, i1] = z.index_range(true, 2.6, 3.4);
  const auto [j0, j1] = z.index_range(false, -0.4, 0.4);
  for (int i = i0; i <= i1; ++i) {
    for (int j = j0; j <= j1; ++j)
      EXPECT_TRUE(z.touched(i, j) && z.intervals(i, j).empty()) << i << " " << j;
  }
  Mesh open = m;
  open.triangles.erase(open.triangles.begin());
  try {
    (void)stock_from_mesh(open, 0.01);
    ADD_FAILURE() << "an open mesh was accepted";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("not closed"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace trochomill

namespace trochomill {

// The X and Y boards' row check done for a layer's rows at once with Highway's vectors
// (sim_detail::row_chords) against the scalar pieces it replaces (SectorSlicer::on_line and
// annulus_parts), row by row, on every vector target this processor runs: the same bits, or
// the simulation's results would depend on the processor. Sectors of every kind (about the
// axes, across 0 and pi, ending on multiples of pi), rows through the centre, inner radii
// from none to beyond the outer.
TEST(Sim, RowChordsAreTheScalarRowsOnEveryTarget) {
  using sim_detail::annulus_parts;
  using sim_detail::RowChords;
  using sim_detail::SectorSlicer;
  std::mt19937_64 rng(20261203);
  std::uniform_real_distribution<double> U(0, 1);
  const auto bits = [](double x) {
    std::uint64_t b;
    std::memcpy(&b, &x, sizeof b);
    return b;
  };
  std::vector<int64_t> targets = hwy::SupportedAndGeneratedTargets();
  ASSERT_FALSE(targets.empty());
  std::size_t rows = 0, chords = 0, split = 0;
  for (const int64_t target : targets) {
    hwy::SetSupportedTargetsForTest(target);
    for (int c = 0; c < 2000; ++c) {
      // Ends on the multiples of pi / 2 a fifth of the time each.
      auto angle = [&] {
        return U(rng) < 0.2 ? std::floor(U(rng) * 8 - 4) * 0.5 * kPi : (U(rng) * 4 - 2) * kPi;
      };
      const double a0 = angle();
      const double a1 = a0 + (U(rng) < 0.2 ? 0.5 * kPi : U(rng) * 0.99 * kPi);
      const SectorSlicer slicer(a0, a1);
      const double d = 0.005 * (1 + std::floor(U(rng) * 4));
      const double origin = -5 + 10 * U(rng), R = 8 * U(rng) + 0.01;
      const double r_in = U(rng) < 0.2 ? 0.0 : R * 1.1 * U(rng);
      const int r0 = static_cast<int>(U(rng) * 100);
      const int n = 1 + static_cast<int>(U(rng) * 2.5 * R / d);
      // A row through the centre in half the cases.
      const int mid = r0 + static_cast<int>(U(rng) * n);
      const double centre = U(rng) < 0.5 ? origin + (mid + 0.5) * d : origin + U(rng) * n * d;
      const bool negate = U(rng) < 0.5;
      RowChords out;
      sim_detail::row_chords(slicer.coeffs(), origin, d, r0, n, centre, negate, R, r_in, out);
      for (int k = 0; k < n; ++k) {
        const auto q = static_cast<std::size_t>(k);
        const double perp = (origin + (r0 + k + 0.5) * d) - centre;
        ASSERT_EQ(bits(out.perp[q]), bits(perp));
        const auto on = slicer.on_line(negate ? -perp : perp, R);
        std::array<Interval, 2> parts{};
        const int np = on ? annulus_parts(perp, on->lo, on->hi, r_in, R, parts) : 0;
        // The vectors keep the near part and the far one apart (the scalar code packs them);
        // an empty part is (inf, -inf).
        std::vector<Interval> got;
        if (out.a_lo[q] < out.a_hi[q]) got.push_back({out.a_lo[q], out.a_hi[q]});
        if (out.b_lo[q] < out.b_hi[q]) got.push_back({out.b_lo[q], out.b_hi[q]});
        ASSERT_EQ(static_cast<int>(got.size()), np) << "target " << hwy::TargetName(target);
        for (int p = 0; p < np; ++p) {
          ASSERT_EQ(bits(got[static_cast<std::size_t>(p)].lo), bits(parts[p].lo));
          ASSERT_EQ(bits(got[static_cast<std::size_t>(p)].hi), bits(parts[p].hi));
        }
        if (np > 0) {  // the chord itself is only read where a part holds material
          ASSERT_EQ(bits(out.lo[q]), bits(on->lo));
          ASSERT_EQ(bits(out.hi[q]), bits(on->hi));
        }
        ++rows, chords += on ? 1 : 0, split += np == 2 ? 1 : 0;
      }
    }
  }
  hwy::SetSupportedTargetsForTest(0);
  // The cases reached what they are for: many rows, most with a chord, some split in two.
  EXPECT_GT(rows, 100'000U);
  EXPECT_GT(chords, rows / 4);
  EXPECT_GT(split, 1000U);
}

// The row check's vectorised look at the rays (sim_detail::rays_maybe) never passes over a
// ray with material in a row's parts, and finds material exactly where the intervals have it
// for the rays it reads (one or two inline intervals; spilled and emptied rays are left to
// the caller, flagged): rays of both X and Y boards cut at random into 0-4 intervals, parts
// at random (some empty, some touching a ray's ends), runs of every length up to a tile's
// edge, on every vector target.
TEST(Sim, RaysMaybeIsTheIntervalsOnEveryTarget) {
  using sim_detail::kInf;
  using sim_detail::RowChords;
  std::mt19937_64 rng(3122026);
  std::uniform_real_distribution<double> U(0, 1);
  const Box3 box{{0, 0, 0}, {10, 6.4, 6.4}};
  std::size_t inline_rays = 0, flagged = 0, with_material = 0;
  for (const int64_t target : hwy::SupportedAndGeneratedTargets()) {
    hwy::SetSupportedTargetsForTest(target);
    for (int axis = 0; axis < 2; ++axis) {
      DexelBoard board(axis, box, 0.1);  // 64 x 64 rays: one tile
      std::vector<Interval> removed;
      for (int i = 0; i < 64; ++i) {
        for (int j = 0; j < 64; ++j) {
          const int cuts = static_cast<int>(U(rng) * 4);
          for (int c = 0; c < cuts; ++c) {
            const double a = U(rng) * 10;
            (void)board.subtract(i, j, a, a + U(rng) * 3, removed);
          }
          if (U(rng) < 0.05) (void)board.subtract(i, j, -1, 11, removed);  // emptied
        }
      }
      for (int t = 0; t < 400; ++t) {
        const int layer = static_cast<int>(U(rng) * 64), r0 = static_cast<int>(U(rng) * 64);
        const int count = 1 + static_cast<int>(U(rng) * (64 - r0));
        RowChords rc;
        rc.reserve_rows(static_cast<std::size_t>(count) + 64);
        const double along = U(rng) * 4;
        for (int k = 0; k < count; ++k) {
          const auto u = static_cast<std::size_t>(k);
          auto part = [&](double& lo, double& hi) {
            lo = U(rng) * 8 - along, hi = lo + U(rng) * 2;
            if (U(rng) < 0.3) lo = kInf, hi = -kInf;  // no part
          };
          part(rc.a_lo[u], rc.a_hi[u]);
          part(rc.b_lo[u], rc.b_hi[u]);
        }
        const int i = axis == 0 ? r0 : layer, j = axis == 0 ? layer : r0;
        const Dexel* rays = board.row_rays(i, j);
        ASSERT_NE(rays, nullptr);
        sim_detail::rays_maybe(reinterpret_cast<const double*>(rays), count, 0, along, rc);
        for (int k = 0; k < count; ++k) {
          const auto u = static_cast<std::size_t>(k);
          const auto found =
              board.intervals(axis == 0 ? r0 + k : layer, axis == 0 ? layer : r0 + k);
          bool any = false;
          for (const Interval& v : found) {
            for (const auto& [lo, hi] :
                 {std::pair{rc.a_lo[u], rc.a_hi[u]}, std::pair{rc.b_lo[u], rc.b_hi[u]}}) {
              any = any || (lo < hi && v.hi > along + lo && v.lo < along + hi);
            }
          }
          ASSERT_TRUE(rc.maybe[u] == 0.0 || rc.maybe[u] == 1.0);
          if (any) {
            ASSERT_EQ(rc.maybe[u], 1.0) << hwy::TargetName(target);
          }
          // Inline rays (one or two intervals, not spilled): the answer is exact.
          if (!found.empty() && found.size() <= 2 &&
              static_cast<const void*>(found.data()) == static_cast<const void*>(&rays[k])) {
            ++inline_rays;
            ASSERT_EQ(rc.maybe[u] == 1.0, any) << hwy::TargetName(target);
          }
          flagged += rc.maybe[u] == 1.0 ? 1 : 0, with_material += any ? 1 : 0;
        }
      }
    }
  }
  hwy::SetSupportedTargetsForTest(0);
  EXPECT_GT(inline_rays, 10'000U);
  EXPECT_GT(with_material, inline_rays / 10);
  EXPECT_LT(with_material, flagged + 1);
}

}  // namespace trochomill
