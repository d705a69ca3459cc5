// The measured-forces CSV reader: every input is a record of finite, increasing times and
// finite forces, or an InputError naming the line.
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstdlib>

#include "fuzz_common.hpp"
#include "trochomill/error.hpp"
#include "trochomill/force.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace trochomill;
  const auto file = fuzz::scratch_file(".csv");
  fuzz::write_bytes(file, data, size);
  try {
    const MeasuredForces f = read_measured_forces(file);
    for (const auto* col : {&f.t_s, &f.fx_n, &f.fy_n, &f.fz_n}) {
      if (col->size() != f.t_s.size()) std::abort();  // columns of one length
      for (double v : *col) {
        if (!std::isfinite(v)) std::abort();  // the reader promises finite numbers
      }
    }
  } catch (const InputError&) {
  }
  return 0;
}
