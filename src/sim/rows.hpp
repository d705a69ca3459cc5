// The rows of one layer crossing an annular sector, all at once (src/sim/, not public): the
// X and Y boards' row check in the time-stepped simulation, vectorised with Google Highway
// (its dynamic dispatch picks the widest vectors the processor has at run time). Every lane
// does the scalar code's operations in the same order (no fused multiply-add, the same
// comparisons for min and max), so the results are the same bits on every target. The
// vector code is the plugin libtrochomill_rows.so (rows.cpp): libhwy's set-up at load (its
// timer's calibration) cost every start of the program about 3 ms; the first simulation
// loads it.
#pragma once

#include <cstddef>
#include <vector>

#include "sim/plane.hpp"

namespace trochomill::sim_detail {

// The rows' chords and annulus parts (mm, offsets along the row from the centre's
// projection), one entry per row. A row's part is empty when its lo is not below its hi; a
// row with both parts empty holds nothing the sector can cut.
struct RowChords {
  std::vector<double> perp, lo, hi, a_lo, a_hi, b_lo, b_hi;
  // rays_maybe's answer: 1 where the row's ray may hold material in its parts, 0 where it
  // surely does not.
  std::vector<double> maybe;
  // Makes room for n rows (the vectors' lanes, a whole number of vectors).
  void reserve_rows(std::size_t n) {
    if (perp.size() >= n) return;
    for (std::vector<double>* v : {&perp, &lo, &hi, &a_lo, &a_hi, &b_lo, &b_hi, &maybe}) {
      v->resize(n);
    }
  }
};

// Rows r0 .. r0 + n - 1 of a board whose rows lie at origin + (r + 1/2) d (mm): each row's
// distance from the centre perp = (origin + (r + 1/2) d) - centre, the sector's chord on the
// line at signed distance (negate ? -perp : perp) within radius R (SectorSlicer::on_line),
// and the parts of that chord at distances in [r_in, R] from the centre (annulus_parts): the
// part on the near side, then the far one (one part, the whole span, when r_in is below the
// row's distance).
void row_chords(const SlicerCoeffs& sector, double origin, double d, int r0, int n, double centre,
                bool negate, double R, double r_in, RowChords& out);

// Whether the rays of rows first .. first + count - 1 may hold material in their parts: the
// rays' inline words as BasicDexel<2> lays them out (four doubles a ray: two intervals, the
// second's bounds NaN when unused; a spilled or empty ray's first word a NaN tag), `count`
// rays one after the other; a part is (along + a_lo, along + a_hi) and the same with b. 1 in
// out.maybe where a part overlaps an inline interval or the ray is spilled (the caller
// looks at those itself), else 0: exactly where has_material finds nothing.
void rays_maybe(const double* rays, int count, int first, double along, RowChords& out);

// Loads the plugin now (it loads at the first row check otherwise): a simulation without it
// fails at its start, not after its pre-roll. Throws Error naming the places tried.
void require_rows();

// The plugin's functions (trochomill_rows_table()): row_chords and rays_maybe, dispatched to
// the processor's widest vectors.
struct RowsTable {
  void (*row_chords)(const SlicerCoeffs& sector, double origin, double d, int r0, int n,
                     double centre, bool negate, double R, double r_in, RowChords& out);
  void (*rays_maybe)(const double* rays, int count, int first, double along, RowChords& out);
};
inline constexpr const char* kRowsSymbol = "trochomill_rows_table";

}  // namespace trochomill::sim_detail
