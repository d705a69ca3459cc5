// The rows of one layer crossing an annular sector (rows.hpp): the calls into the plugin
// libtrochomill_rows.so, loaded by the first simulation.
#include "sim/rows.hpp"
#include "trochomill/common/plugin.hpp"

namespace trochomill::sim_detail {
namespace {

const RowsTable& rows() {
  static const RowsTable& table =
      plugin_table<RowsTable>("rows", kRowsSymbol, "the simulation's vector code (Google Highway)");
  return table;
}

}  // namespace

void require_rows() { (void)rows(); }

void row_chords(const SlicerCoeffs& sector, double origin, double d, int r0, int n, double centre,
                bool negate, double R, double r_in, RowChords& out) {
  rows().row_chords(sector, origin, d, r0, n, centre, negate, R, r_in, out);
}

void rays_maybe(const double* rays, int count, int first, double along, RowChords& out) {
  rows().rays_maybe(rays, count, first, along, out);
}

}  // namespace trochomill::sim_detail
